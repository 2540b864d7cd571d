#pragma once
// The viewer's input (window.h): GLFW's mouse, scroll, key and resize callbacks turned into camera
// moves (OrbitCamera), requests for the application (ViewerRequests) and flags for the window.
#include "weft/render/window.h"
#include "weft/render/window_overlay.h"

#include "window/orbit_camera.h"

struct GLFWwindow;

namespace weft::render::detail {

class WindowInput {
public:
    /// Installs the callbacks on `window` (its user pointer is this object, which must outlive them
    /// or be detached first).
    explicit WindowInput(GLFWwindow* window);
    ~WindowInput();
    WindowInput(const WindowInput&) = delete;
    WindowInput& operator=(const WindowInput&) = delete;

    OrbitCamera& camera() { return camera_; }
    [[nodiscard]] const OrbitCamera& camera() const { return camera_; }
    [[nodiscard]] ViewerRequests take_requests();
    /// Esc or Q was pressed.
    [[nodiscard]] bool quit() const { return quit_; }
    /// While `overlay` (may be null) wants the mouse or the keys, the camera and the keys ignore them.
    void set_overlay(const WindowOverlay* overlay) { overlay_ = overlay; }
    /// The framebuffer changed size since the last call.
    [[nodiscard]] bool take_resized();

private:
    static WindowInput* self(GLFWwindow* window);
    static void on_key(GLFWwindow* window, int key, int scancode, int action, int mods);
    static void on_char(GLFWwindow* window, unsigned int codepoint);
    static void on_button(GLFWwindow* window, int button, int action, int mods);
    static void on_cursor(GLFWwindow* window, double x, double y);
    static void on_scroll(GLFWwindow* window, double dx, double dy);
    static void on_framebuffer_size(GLFWwindow* window, int width, int height);

    [[nodiscard]] bool overlay_mouse() const;
    [[nodiscard]] bool overlay_keyboard() const;

    GLFWwindow* window_;
    const WindowOverlay* overlay_ = nullptr;
    OrbitCamera camera_;
    ViewerRequests requests_;
    bool quit_ = false;
    bool resized_ = false;
    enum class Drag : unsigned char { none, orbit, pan } drag_ = Drag::none;
    double last_x_ = 0.0, last_y_ = 0.0;
};

}  // namespace weft::render::detail
