#include "render/window.hpp"

#include <GLFW/glfw3.h>

#include <cstdlib>

namespace vox::render {
namespace {

Window* owner(GLFWwindow* w) { return static_cast<Window*>(glfwGetWindowUserPointer(w)); }

} // namespace

Window::Window(const std::string& title, int width, int height, InputHandlers handlers) : m_handlers(std::move(handlers))
{
    if (!glfwInit()) {
        const char* display = std::getenv("DISPLAY");
        throw NoOpenGL(std::string("no window: GLFW cannot start (") + (display && *display ? "DISPLAY=" + std::string(display) + " refused it" : "DISPLAY is not set") +
                       "); run it on a desktop, or headless under xvfb-run (Debian package xvfb); pictures without a window: voxsculpt render");
    }
    glfwWindowHint(GLFW_CONTEXT_VERSION_MAJOR, 3);
    glfwWindowHint(GLFW_CONTEXT_VERSION_MINOR, 3);
    glfwWindowHint(GLFW_OPENGL_PROFILE, GLFW_OPENGL_CORE_PROFILE);
    glfwWindowHint(GLFW_OPENGL_FORWARD_COMPAT, GLFW_TRUE);
    glfwWindowHint(GLFW_SAMPLES, 4);
    m_window = glfwCreateWindow(width, height, title.c_str(), nullptr, nullptr);
    if (!m_window) {
        glfwTerminate();
        throw NoOpenGL("no OpenGL 3.3 core window: the display's OpenGL is older or missing (Debian packages libgl1-mesa-dri, libglx-mesa0)");
    }
    glfwMakeContextCurrent(m_window);
    glfwSwapInterval(1);
    glfwSetWindowUserPointer(m_window, this);
    glfwSetKeyCallback(m_window, [](GLFWwindow* w, int key, int, int action, int mods) {
        if (action != GLFW_RELEASE && owner(w)->m_handlers.key) owner(w)->m_handlers.key(key, mods);
    });
    glfwSetMouseButtonCallback(m_window, [](GLFWwindow* w, int button, int action, int mods) {
        if (owner(w)->m_handlers.button) owner(w)->m_handlers.button(button, action == GLFW_PRESS, mods);
    });
    glfwSetCursorPosCallback(m_window, [](GLFWwindow* w, double x, double y) {
        if (owner(w)->m_handlers.move) owner(w)->m_handlers.move(x, y);
    });
    glfwSetScrollCallback(m_window, [](GLFWwindow* w, double, double dy) {
        const int mods = (glfwGetKey(w, GLFW_KEY_LEFT_SHIFT) == GLFW_PRESS || glfwGetKey(w, GLFW_KEY_RIGHT_SHIFT) == GLFW_PRESS) ? GLFW_MOD_SHIFT : 0;
        if (owner(w)->m_handlers.scroll) owner(w)->m_handlers.scroll(dy, mods);
    });
}

Window::~Window()
{
    if (m_window) glfwDestroyWindow(m_window);
    glfwTerminate();
}

bool Window::should_close() const { return glfwWindowShouldClose(m_window); }
void Window::close() { glfwSetWindowShouldClose(m_window, GLFW_TRUE); }
void Window::set_title(const std::string& title) { glfwSetWindowTitle(m_window, title.c_str()); }

void Window::present()
{
    glfwSwapBuffers(m_window);
    glfwPollEvents();
}

void Window::size(int& width, int& height) const { glfwGetFramebufferSize(m_window, &width, &height); }
void Window::window_size(int& width, int& height) const { glfwGetWindowSize(m_window, &width, &height); }
bool Window::button_down(int button) const { return glfwGetMouseButton(m_window, button) == GLFW_PRESS; }

} // namespace vox::render
