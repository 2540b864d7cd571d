#pragma once
/// @file
/// The live window (`weft view`): a resizable GLFW window with a Vulkan surface and a swapchain. It
/// draws with the offscreen Vulkan renderer's passes (shadow map, MSAA surface pass resolved to one
/// sample) and blits the resolved picture into the acquired swapchain image, so the window shows
/// exactly what `weft run --capture vulkan` writes (docs/rendering.md, "The window: weft view").
///
/// Input: left drag orbits the camera round its target, right or middle drag pans, the scroll
/// wheel zooms, R resets the camera. The keys for the application (pause, single step, time scale,
/// screenshot) are collected as `ViewerRequests`; Esc, Q and the close button end `poll_events()`.
#include <memory>
#include <string>

#include "weft/render/image.h"
#include "weft/render/render_scene.h"
#include "weft/render/renderer.h"

namespace weft::render {

class WindowOverlay;
struct OverlayVulkan;  // window_overlay.h, for Vulkan-aware clients

/// What the viewer's keys asked of the application since the last `Window::take_requests()`.
struct ViewerRequests {
    bool toggle_pause = false;  ///< Space pressed an odd number of times
    int single_steps = 0;       ///< Right arrow or N presses (meant for a paused simulation)
    int time_scale_steps = 0;   ///< +1 per '+' (time scale ×2), −1 per '-' (÷2)
    bool screenshot = false;    ///< S pressed
};

/// The keys and gamepad a game reads each frame (Window::game_input), polled, not queued: what is
/// held now. Keyboard: W/Up forward, S/Down back, A/Left and D/Right turn, Space jump, Shift run.
/// The first gamepad GLFW maps (SDL's mapping database) adds its left stick, A button and right
/// bumper. The viewer's own keys (weft view) still act: a game ignores take_requests().
struct GameInput {
    float forward = 0.0F;  ///< −1 (back) … 1 (forward)
    float turn = 0.0F;     ///< −1 (left) … 1 (right)
    bool jump = false;
    bool run = false;
    bool gamepad = false;  ///< a gamepad is connected and was read
};

class Window {
public:
    /// Opens a window of `options.width`×`options.height` screen pixels titled `title` and creates
    /// the Vulkan renderer for it (`options` as for create_renderer; the picture follows the
    /// window's framebuffer size from then on). Throws weft::Error:
    /// - "no display: set DISPLAY or run under xvfb-run" when GLFW cannot open the display;
    /// - when GLFW finds no Vulkan loader, or no device can present to the window;
    /// - for the renderer's own reasons (create_renderer).
    Window(const RendererOptions& options, const std::string& title);
    ~Window();
    Window(const Window&) = delete;
    Window& operator=(const Window&) = delete;

    /// The device and driver it renders on.
    [[nodiscard]] std::string device_description() const;
    /// Uploads `scene`'s static geometry (Renderer::load) and puts the camera at `scene.camera`,
    /// which R returns to.
    void load(const RenderScene& scene);
    /// Handles the window's events: input, resizing, closing. While the window is minimised it
    /// waits for events instead. Returns false once the window should close (Esc, Q, the close
    /// button).
    [[nodiscard]] bool poll_events();
    /// The requests gathered since the last call, then cleared.
    [[nodiscard]] ViewerRequests take_requests();
    /// Draws `frame` from the current camera into the next swapchain image and presents it. The
    /// frame is not waited for: the next call waits for it (one frame in flight), so the caller's
    /// work between calls overlaps the drawing. Recreates the swapchain and the picture's targets
    /// when the window changed size or the swapchain is out of date; skips the frame while the
    /// window is minimised.
    void present(const RenderFrame& frame);
    /// The last presented picture, read back from the renderer's resolved target (RGBA, rows top
    /// to bottom, the window's framebuffer size). Throws weft::Error before the first present.
    [[nodiscard]] Image screenshot();
    void set_title(const std::string& title);
    [[nodiscard]] const Camera& camera() const;
    void reset_camera();
    /// Puts the camera at `camera` (a game's follow camera; mouse orbiting starts from there).
    void set_camera(const Camera& camera);
    /// What the player holds now (GameInput).
    [[nodiscard]] GameInput game_input() const;
    /// The picture's size, pixels (the window's framebuffer size at the last present).
    [[nodiscard]] int width() const;
    [[nodiscard]] int height() const;
    /// Draws `overlay` over every presented picture from the next present on (nullptr: none); it
    /// also gets the mouse and keys while it wants them (window_overlay.h). Not owned: it must
    /// outlive the window or be unset first.
    void set_overlay(WindowOverlay* overlay);
    /// The Vulkan objects an overlay is made with (window_overlay.h; creates the overlay pass on
    /// the first call).
    [[nodiscard]] OverlayVulkan overlay_vulkan();
    /// The Vulkan renderer that draws the window's pictures: what a ClothFeed (cloth_feed.h) links
    /// the world to. Frames go through present(), not its submit().
    [[nodiscard]] Renderer& renderer();
    /// As Renderer::validation_messages and Renderer::transfer.
    [[nodiscard]] int validation_messages() const;
    [[nodiscard]] TransferStats transfer() const;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace weft::render
