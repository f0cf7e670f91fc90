#pragma once
// The program's version (CMake's project version), for --version and for files that must be read
// back by the same program (session journals).

namespace vox {

/// "voxsculpt 0.1.0".
[[nodiscard]] const char* program_version();

} // namespace vox
