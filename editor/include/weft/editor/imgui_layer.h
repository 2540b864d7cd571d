#pragma once
/// @file
/// Dear ImGui (Debian's 1.86: GLFW and Vulkan backends) in the live window: an overlay
/// (weft/render/window_overlay.h) that records ImGui's draw data into the window's overlay pass.
/// One per process (ImGui's backends keep global state).
#include <filesystem>
#include <memory>

#include "weft/render/window.h"
#include "weft/render/window_overlay.h"

namespace weft::editor {

class ImGuiLayer final : public render::WindowOverlay {
public:
    /// Creates the ImGui context and its backends on `window` and registers itself as its overlay.
    /// `ini_file`: where ImGui keeps the panels' layout between runs; empty: nowhere (scripted runs,
    /// so that a test never depends on a layout a person left behind). Throws weft::Error when a
    /// backend cannot start or the fonts cannot be uploaded. `scale`: the panels' size against
    /// ImGui's defaults (font pixels and every padding and spacing); 0: the monitor's content scale
    /// as GLFW reports it (1 on a 96-dpi screen, 2 on a "200 %" one).
    ImGuiLayer(render::Window& window, const std::filesystem::path& ini_file, float scale = 0.0F);
    /// The scale in use (see the constructor).
    [[nodiscard]] float scale() const;
    /// Unregisters from the window, waits for the device, shuts the backends down.
    ~ImGuiLayer() override;

    /// Starts an ImGui frame (call before any ImGui widget, once per displayed frame).
    void begin_frame();
    /// Ends it: ImGui::Render(). The draw data is recorded by the next Window::present().
    void end_frame();

    /// The left button and the cursor as ImGui saw them in the current frame (between begin_frame
    /// and the next one), in picture pixels: what the editor's loop turns into grabs and pins.
    struct Mouse {
        double x = 0.0, y = 0.0;
        bool on_panels = false;  ///< over a panel (ImGui takes the mouse)
        bool pressed = false, down = false, released = false, moved = false;
        bool ctrl = false, shift = false;
    };
    [[nodiscard]] Mouse mouse() const;

    void record(VkCommandBuffer commands, VkExtent2D extent) override;
    [[nodiscard]] bool wants_mouse() const override;
    [[nodiscard]] bool wants_keyboard() const override;

private:
    struct Impl;
    std::unique_ptr<Impl> impl_;
};

}  // namespace weft::editor
