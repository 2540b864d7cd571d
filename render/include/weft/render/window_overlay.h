#pragma once
/// @file
/// A hook for drawing over the live window's picture (the editor's ImGui panels), for Vulkan-aware
/// clients only: this header includes the Vulkan API, window.h does not.
///
/// Where the overlay goes: after the scene's passes, into the resolved picture (RGBA8 UNORM holding
/// sRGB-encoded values, one sample, the window's framebuffer size), before that picture is blitted
/// into the swapchain image. Drawing there rather than into the swapchain image means that
/// `Window::screenshot()` shows the overlay too, and that the overlay's pipeline does not depend on
/// the swapchain's format. The window runs one render pass over that picture (load op LOAD, no MSAA,
/// no depth: `OverlayVulkan::render_pass`), recreated with the picture when the window changes size,
/// and calls `WindowOverlay::record` inside it once per presented frame.
#include <vulkan/vulkan.h>

#include <cstdint>
#include <functional>

struct GLFWwindow;

namespace weft::render {

/// What an overlay needs to create its Vulkan objects (pipelines for `render_pass`, descriptor
/// pools, textures) and to hook into the window's input. Valid while the window lives.
struct OverlayVulkan {
    VkInstance instance = VK_NULL_HANDLE;
    VkPhysicalDevice physical_device = VK_NULL_HANDLE;
    VkDevice device = VK_NULL_HANDLE;
    std::uint32_t queue_family = 0;
    VkQueue queue = VK_NULL_HANDLE;
    /// The overlay pass: subpass 0, one colour attachment of `format`, 1 sample, no depth.
    VkRenderPass render_pass = VK_NULL_HANDLE;
    VkFormat format = VK_FORMAT_UNDEFINED;
    /// Frames that may be in flight at once is 1 (the window waits for the previous frame before
    /// recording the next); this is the number of per-frame buffer sets an overlay should keep
    /// (2: one being recorded, one possibly still read by the device).
    std::uint32_t frames = 2;
    /// The GLFW window, for input backends that install callbacks (they must chain to the ones
    /// already installed: the viewer's camera and keys).
    GLFWwindow* window = nullptr;
    /// Records commands with `record`, submits them on `queue` and waits for them (uploads).
    std::function<void(const std::function<void(VkCommandBuffer)>&)> submit_and_wait;
};

/// Implemented by the client (editor/), registered with `Window::set_overlay`.
class WindowOverlay {
public:
    WindowOverlay() = default;
    virtual ~WindowOverlay() = default;
    WindowOverlay(const WindowOverlay&) = delete;
    WindowOverlay& operator=(const WindowOverlay&) = delete;

    /// Records the overlay's draws into `commands`, inside the overlay pass over a picture of
    /// `extent` pixels. Called from `Window::present`, after the window waited for the previous
    /// frame (so buffers the previous frame used may be rewritten).
    virtual void record(VkCommandBuffer commands, VkExtent2D extent) = 0;
    /// While true, the viewer's mouse (orbit, pan, zoom) and keys ignore input: it is the overlay's.
    [[nodiscard]] virtual bool wants_mouse() const { return false; }
    [[nodiscard]] virtual bool wants_keyboard() const { return false; }
};

}  // namespace weft::render
