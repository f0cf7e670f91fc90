#pragma once
// An OpenGL 3.3 core context with no window and no display server: EGL on Mesa's surfaceless
// platform (software rendering through llvmpipe where there is no GPU). Pictures are drawn into
// framebuffer objects. One per thread that renders; it is current on the thread that made it.

#include "core/error.hpp"

#include <string>

namespace vox::render {

/// No OpenGL could be had (no EGL, no driver): names what is missing and the packages to install.
/// Like a missing device, it is reported as one line and a non-zero exit.
class NoOpenGL : public InputError {
public:
    explicit NoOpenGL(const std::string& what) : InputError(what) {}
};

class OffscreenContext {
public:
    /// Throws NoOpenGL when no context can be made.
    OffscreenContext();
    ~OffscreenContext();
    OffscreenContext(const OffscreenContext&) = delete;
    OffscreenContext& operator=(const OffscreenContext&) = delete;

    /// "OpenGL <version> (<renderer>)", for logs and benchmark notes.
    [[nodiscard]] const std::string& description() const { return m_description; }

private:
    void* m_display = nullptr;
    void* m_context = nullptr;
    std::string m_description;
};

} // namespace vox::render
