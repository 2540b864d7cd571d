// Mouse and keys of the viewer (see window_input.h).
#include "window/window_input.h"

#include <GLFW/glfw3.h>

namespace weft::render::detail {

WindowInput::WindowInput(GLFWwindow* window) : window_(window) {
    glfwSetWindowUserPointer(window_, this);
    glfwSetKeyCallback(window_, on_key);
    glfwSetCharCallback(window_, on_char);
    glfwSetMouseButtonCallback(window_, on_button);
    glfwSetCursorPosCallback(window_, on_cursor);
    glfwSetScrollCallback(window_, on_scroll);
    glfwSetFramebufferSizeCallback(window_, on_framebuffer_size);
}

WindowInput::~WindowInput() {
    glfwSetKeyCallback(window_, nullptr);
    glfwSetCharCallback(window_, nullptr);
    glfwSetMouseButtonCallback(window_, nullptr);
    glfwSetCursorPosCallback(window_, nullptr);
    glfwSetScrollCallback(window_, nullptr);
    glfwSetFramebufferSizeCallback(window_, nullptr);
    glfwSetWindowUserPointer(window_, nullptr);
}

ViewerRequests WindowInput::take_requests() {
    const ViewerRequests out = requests_;
    requests_ = {};
    return out;
}

bool WindowInput::take_resized() {
    const bool out = resized_;
    resized_ = false;
    return out;
}

bool WindowInput::overlay_mouse() const { return overlay_ != nullptr && overlay_->wants_mouse(); }

bool WindowInput::overlay_keyboard() const { return overlay_ != nullptr && overlay_->wants_keyboard(); }

WindowInput* WindowInput::self(GLFWwindow* window) {
    return static_cast<WindowInput*>(glfwGetWindowUserPointer(window));
}

void WindowInput::on_key(GLFWwindow* window, int key, int /*scancode*/, int action, int /*mods*/) {
    WindowInput* in = self(window);
    if (in == nullptr || (action != GLFW_PRESS && action != GLFW_REPEAT)) return;
    if (in->overlay_keyboard()) return;  // typed into the overlay (an editor's text field)
    // Held keys repeat only where repeating makes sense: stepping.
    const bool press = action == GLFW_PRESS;
    switch (key) {
        case GLFW_KEY_ESCAPE:
        case GLFW_KEY_Q:
            in->quit_ = true;
            break;
        case GLFW_KEY_SPACE:
            if (press) in->requests_.toggle_pause = !in->requests_.toggle_pause;
            break;
        case GLFW_KEY_RIGHT:
        case GLFW_KEY_N:
            ++in->requests_.single_steps;
            break;
        case GLFW_KEY_R:
            if (press) in->camera_.reset();
            break;
        case GLFW_KEY_S:
            if (press) in->requests_.screenshot = true;
            break;
        default:
            break;
    }
}

// '+' and '-' by the character typed, keypad included, so that they work on every keyboard layout
// ('+' is Shift+= on a US keyboard).
void WindowInput::on_char(GLFWwindow* window, unsigned int codepoint) {
    WindowInput* in = self(window);
    if (in == nullptr || in->overlay_keyboard()) return;
    if (codepoint == '+') ++in->requests_.time_scale_steps;
    if (codepoint == '-') --in->requests_.time_scale_steps;
}

void WindowInput::on_button(GLFWwindow* window, int button, int action, int /*mods*/) {
    WindowInput* in = self(window);
    if (in == nullptr) return;
    if (action == GLFW_RELEASE) {
        in->drag_ = Drag::none;
        return;
    }
    if (in->overlay_mouse()) return;  // a click on the overlay's panels starts no drag
    if (button == GLFW_MOUSE_BUTTON_LEFT)
        in->drag_ = Drag::orbit;
    else if (button == GLFW_MOUSE_BUTTON_RIGHT || button == GLFW_MOUSE_BUTTON_MIDDLE)
        in->drag_ = Drag::pan;
    glfwGetCursorPos(window, &in->last_x_, &in->last_y_);
}

void WindowInput::on_cursor(GLFWwindow* window, double x, double y) {
    WindowInput* in = self(window);
    if (in == nullptr) return;
    const double dx = x - in->last_x_;
    const double dy = y - in->last_y_;
    in->last_x_ = x;
    in->last_y_ = y;
    if (in->drag_ == Drag::orbit) {
        in->camera_.orbit(dx, dy);
    } else if (in->drag_ == Drag::pan) {
        // Cursor positions are in screen coordinates: scale by the window's height in them.
        int width = 0;
        int height = 0;
        glfwGetWindowSize(window, &width, &height);
        in->camera_.pan(dx, dy, height);
    }
}

void WindowInput::on_scroll(GLFWwindow* window, double /*dx*/, double dy) {
    WindowInput* in = self(window);
    if (in != nullptr && !in->overlay_mouse()) in->camera_.zoom(dy);
}

void WindowInput::on_framebuffer_size(GLFWwindow* window, int /*width*/, int /*height*/) {
    WindowInput* in = self(window);
    if (in != nullptr) in->resized_ = true;
}

}  // namespace weft::render::detail
