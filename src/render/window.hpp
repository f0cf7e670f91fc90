#pragma once
// A GLFW window with an OpenGL 3.3 core context (4x multisampled), and what the user does in it:
// the interactive viewer's face. Everything here runs on the thread that made the window (GLFW
// wants the main thread).

#include "render/offscreen_context.hpp"

#include <functional>
#include <string>

struct GLFWwindow;

namespace vox::render {

struct InputHandlers {
    std::function<void(int key, int mods)> key;                        ///< a key pressed (GLFW key codes)
    std::function<void(int button, bool down, int mods)> button;       ///< a mouse button
    std::function<void(double x, double y)> move;                      ///< the cursor, pixels from the top-left
    std::function<void(double dy, int mods)> scroll;                   ///< the wheel
};

class Window {
public:
    /// Throws NoOpenGL naming the problem (no display: say to run under a desktop or xvfb-run).
    Window(const std::string& title, int width, int height, InputHandlers handlers);
    ~Window();
    Window(const Window&) = delete;
    Window& operator=(const Window&) = delete;

    [[nodiscard]] bool should_close() const;
    void close();
    void set_title(const std::string& title);
    /// Shows what was drawn and handles pending input.
    void present();
    /// Framebuffer size in pixels.
    void size(int& width, int& height) const;
    /// Window size in screen units (the cursor's), which a scaled display makes smaller than the framebuffer.
    void window_size(int& width, int& height) const;
    /// Whether a mouse button is down.
    [[nodiscard]] bool button_down(int button) const;

private:
    GLFWwindow* m_window = nullptr;
    InputHandlers m_handlers;
};

} // namespace vox::render
