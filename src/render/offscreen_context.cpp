#include "render/offscreen_context.hpp"

#define GL_GLEXT_PROTOTYPES
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/gl.h>

#include <cstring>

namespace vox::render {
namespace {

[[noreturn]] void fail(const std::string& step)
{
    throw NoOpenGL("no offscreen OpenGL 3.3: " + step + " (EGL error 0x" + [] {
        char hex[16];
        std::snprintf(hex, sizeof hex, "%x", static_cast<unsigned>(eglGetError()));
        return std::string(hex);
    }() + "); the Debian packages libegl-mesa0 and libgl1-mesa-dri provide it (scripts/install-deps.sh)");
}

} // namespace

OffscreenContext::OffscreenContext()
{
    // Mesa's surfaceless platform needs no X server or GPU; fall back to the default display.
    EGLDisplay display = EGL_NO_DISPLAY;
    const char* extensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    auto get_platform_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (extensions && std::strstr(extensions, "EGL_MESA_platform_surfaceless") && get_platform_display)
        display = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
    if (display == EGL_NO_DISPLAY) display = eglGetDisplay(EGL_DEFAULT_DISPLAY);
    if (display == EGL_NO_DISPLAY) fail("no EGL display");
    EGLint major = 0, minor = 0;
    if (!eglInitialize(display, &major, &minor)) fail("eglInitialize failed");
    m_display = display;
    if (!eglBindAPI(EGL_OPENGL_API)) fail("EGL has no desktop OpenGL");
    // Surfaceless displays offer no window configurations (the default asked for): ask for
    // pbuffer ones, or any.
    EGLConfig config = nullptr;
    EGLint configs = 0;
    for (const EGLint surface : {EGL_PBUFFER_BIT, EGL_DONT_CARE}) {
        const EGLint config_attributes[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_SURFACE_TYPE, surface, EGL_NONE};
        if (eglChooseConfig(display, config_attributes, &config, 1, &configs) && configs > 0) break;
    }
    if (configs < 1) fail("no EGL configuration for OpenGL");
    const EGLint context_attributes[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
                                         EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
    EGLContext context = eglCreateContext(display, config, EGL_NO_CONTEXT, context_attributes);
    if (context == EGL_NO_CONTEXT) fail("cannot create an OpenGL 3.3 core context");
    m_context = context;
    if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) fail("cannot make the context current without a surface");
    const auto* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    m_description = std::string("OpenGL ") + (version ? version : "?") + " (" + (renderer ? renderer : "?") + ")";
}

OffscreenContext::~OffscreenContext()
{
    if (m_display) {
        eglMakeCurrent(m_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (m_context) eglDestroyContext(m_display, m_context);
        eglTerminate(m_display);
    }
}

} // namespace vox::render
