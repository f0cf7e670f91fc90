#pragma once
// Compiling and linking a vertex + fragment shader pair, with the driver's message on failure.
// Needs a current OpenGL 3.3 context.

namespace vox::render {

/// The linked program; throws std::runtime_error with the compiler's or linker's log.
[[nodiscard]] unsigned link_program(const char* vertex_source, const char* fragment_source);

} // namespace vox::render
