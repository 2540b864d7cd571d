#pragma once
// The Vulkan renderer: see vulkan_renderer.cpp. Offscreen (Renderer::draw, the picture read back at
// once: vulkan_renderer_capture.cpp) and, for the window (vulkan_window.cpp), the same passes with
// the resolved picture blitted into a swapchain image instead (draw_to_swapchain, not waited for:
// vulkan_renderer_present.cpp); the cloth slots exported to CUDA in vulkan_renderer_export.cpp.
#include <vulkan/vulkan.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "weft/render/renderer.h"

#include "vulkan/vulkan_context.h"
#include "vulkan/vulkan_resources.h"

namespace weft::render::detail {

struct DrawUniforms;

/// Where draw_to_swapchain puts the picture: an acquired swapchain image, in any layout, left in
/// VK_IMAGE_LAYOUT_PRESENT_SRC_KHR. The submission waits for `acquired` (at the transfer stage,
/// before the blit) and signals `rendered` for the present to wait on.
struct SwapchainTarget {
    VkImage image = VK_NULL_HANDLE;
    VkExtent2D extent{};
    VkSemaphore acquired = VK_NULL_HANDLE;
    VkSemaphore rendered = VK_NULL_HANDLE;
    /// Recorded inside the overlay pass over the resolved picture, before the blit (none: empty).
    std::function<void(VkCommandBuffer, VkExtent2D)> overlay;
};

class VulkanRenderer final : public Renderer {
public:
    /// `surface`: see VulkanContext (the window path); nullptr offscreen.
    explicit VulkanRenderer(const RendererOptions& options, const SurfaceRequest* surface = nullptr);
    ~VulkanRenderer() override;

    [[nodiscard]] std::string_view name() const override { return "vulkan"; }
    [[nodiscard]] std::string device_description() const override { return context_.description(); }
    void load(const RenderScene& scene) override;
    void submit(const RenderFrame& frame) override;
    [[nodiscard]] Image collect() override;
    [[nodiscard]] TransferStats transfer() const override { return transfer_; }
    [[nodiscard]] int validation_messages() const override { return context_.validation_messages(); }
    [[nodiscard]] std::optional<ClothInterop> export_cloth(std::string& why) override;
    [[nodiscard]] std::vector<RenderVertex> read_cloth(int slot) override;

    // ---- the window path ---------------------------------------------------------------------
    [[nodiscard]] const VulkanContext& context() const { return context_; }
    /// The colour format of the resolved picture (what is blitted to the swapchain).
    [[nodiscard]] static VkFormat colour_format();
    /// The camera of the loaded scene, replaced for the next frames (the viewer's orbit camera).
    void set_camera(const Camera& camera);
    /// Recreates the size-dependent targets (MSAA colour, depth, resolved picture, read-back buffer,
    /// surface framebuffer and pipeline) for `width`×`height` pixels. Waits for the frame in flight.
    void resize(int width, int height);
    [[nodiscard]] int width() const { return options_.width; }
    [[nodiscard]] int height() const { return options_.height; }
    /// Waits until the last submitted frame is done with its command buffer and mapped buffers
    /// (its fence), and takes its frame stamps into transfer(). A no-op when none is in flight.
    void wait_frame();
    /// Draws `frame` like draw() and blits the resolved picture into `target` (scaled when the sizes
    /// differ), without waiting: the next frame, wait_frame() or read_back() waits for it.
    void draw_to_swapchain(const RenderFrame& frame, const SwapchainTarget& target);
    /// (Renderer::skip_frame) The wait and signal values go through an empty submission.
    void skip_frame(const RenderFrame& frame) override;
    /// The overlay pass (vulkan_pipelines.h), made on the first call with its framebuffer over the
    /// resolved picture (remade on resize()).
    [[nodiscard]] VkRenderPass overlay_pass();
    /// The picture of the last frame drawn (from the resolved target, through the read-back buffer).
    /// Throws weft::Error before the first frame.
    [[nodiscard]] Image read_back();

private:
    void create_targets();
    void create_size_targets();
    void destroy_size_targets() noexcept;
    void create_overlay_framebuffer();
    void create_surface_pipeline();
    void create_pipelines();
    void create_descriptors();
    /// Writes the frame's uniforms and staged vertices and records its command buffer: upload, the
    /// shadow and surface passes, then `finish` (the copy to the host, or the blit to a swapchain
    /// image), then the copy of the slot's frame stamps. Returns whether the cloth was uploaded;
    /// sets `external`.
    bool record_frame(const RenderFrame& frame, bool& external, const std::function<void(VkCommandBuffer)>& finish);
    /// Submits the recorded frame with its timeline values and the window's semaphores (may be null).
    /// `with_commands` false: no command buffer, only the semaphore operations (skip_frame).
    void submit_frame(const RenderFrame& frame, VkSemaphore wait_binary, VkSemaphore signal_binary,
                      bool with_commands = true);
    void record(VkCommandBuffer commands, const std::vector<DrawUniforms>& draws, bool upload) const;
    void record_stamp_copy(VkCommandBuffer commands) const;
    void record_readback(VkCommandBuffer commands) const;
    /// The queue-family ownership transfer of exported cloth slot `slot`: acquired from the external
    /// writer (CUDA) before the frame reads it, released back after.
    void external_barrier(VkCommandBuffer commands, int slot, bool acquire) const;
    void draw_all(VkCommandBuffer commands, const std::vector<DrawUniforms>& draws, bool casters_only) const;
    /// The frame's overlay lines (frame_lines_) from the cloth slot, in the surface pass after the
    /// scene's `scene_draws` draws (their uniforms follow).
    void draw_lines(VkCommandBuffer commands, std::size_t scene_draws) const;
    void destroy_scene() noexcept;
    void destroy() noexcept;

    /// The resolved picture's format: it holds sRGB-encoded values (the shader encodes).
    static constexpr VkFormat kColourFormat = VK_FORMAT_R8G8B8A8_UNORM;
    /// The stages that read a cloth slot: the draws' vertex input and the copy of its frame stamps.
    static constexpr VkPipelineStageFlags kSlotReadStages =
        VK_PIPELINE_STAGE_VERTEX_INPUT_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;

    RendererOptions options_;
    VulkanContext context_;
    VkSampleCountFlagBits samples_ = VK_SAMPLE_COUNT_1_BIT;  ///< what the device allowed of options_.samples
    VkFormat depth_format_ = VK_FORMAT_UNDEFINED;
    VkFormat shadow_format_ = VK_FORMAT_UNDEFINED;
    VkFilter shadow_filter_ = VK_FILTER_LINEAR;
    VkExtent2D extent_{};
    VkExtent2D shadow_extent_{};

    // Targets and pipelines, made once (the size-dependent ones again on resize()).
    DeviceImage shadow_map_, colour_, depth_, resolved_;
    VkSampler shadow_sampler_ = VK_NULL_HANDLE;
    VkRenderPass shadow_pass_ = VK_NULL_HANDLE, surface_pass_ = VK_NULL_HANDLE;
    VkFramebuffer shadow_framebuffer_ = VK_NULL_HANDLE, surface_framebuffer_ = VK_NULL_HANDLE;
    VkRenderPass overlay_pass_ = VK_NULL_HANDLE;         ///< made by overlay_pass(), for the window
    VkFramebuffer overlay_framebuffer_ = VK_NULL_HANDLE;  ///< over resolved_, while overlay_pass_ exists
    VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
    VkPipelineLayout pipeline_layout_ = VK_NULL_HANDLE;
    VkPipeline shadow_pipeline_ = VK_NULL_HANDLE, surface_pipeline_ = VK_NULL_HANDLE;
    /// The overlay lines (OverlayLines): the wireframe's indexed line list, the normals' instanced one.
    VkPipeline wireframe_pipeline_ = VK_NULL_HANDLE, normals_pipeline_ = VK_NULL_HANDLE;
    VkPipeline points_pipeline_ = VK_NULL_HANDLE;  ///< the overlay's points (point.vert)
    VkDescriptorPool descriptor_pool_ = VK_NULL_HANDLE;
    VkDescriptorSet descriptor_set_ = VK_NULL_HANDLE;
    VkCommandBuffer commands_ = VK_NULL_HANDLE;
    VkFence fence_ = VK_NULL_HANDLE;
    bool in_flight_ = false;     ///< a submitted frame whose fence has not been waited for
    bool have_picture_ = false;  ///< resolved_ holds a drawn frame (read_back)
    bool submitted_ = false;     ///< submit() without collect() yet
    DeviceBuffer readback_;      ///< the resolved picture, width·height·4 bytes

    // The scene, made by load().
    bool loaded_ = false;
    RenderScene scene_;
    DeviceBuffer static_geometry_;   ///< the colliders' vertices, then the cloth indices, then the colliders'
    VkDeviceSize index_offset_ = 0;  ///< of the first index in static_geometry_
    std::vector<std::uint32_t> collider_first_index_;  ///< into the index range, per collider
    std::vector<std::int32_t> collider_first_vertex_;  ///< into the colliders' vertices (static or deforming), per collider
    std::uint32_t edges_first_index_ = 0;  ///< RenderScene::cloth_edges in the index range, after the colliders'
    OverlayLines frame_lines_;             ///< the lines of the frame being recorded
    /// The frame's overlay point lists, one after another (host-visible: rewritten by each frame that
    /// has points, after the previous frame is done; grown as needed).
    DeviceBuffer points_;
    DeviceBuffer deforming_;  ///< the deforming colliders' vertices, host-visible: rewritten by a frame that brings them
    /// A cloth vertex buffer: RenderScene::cloth_vertices vertices, then kSlotStampBytes of stamps.
    /// One until export_cloth(); then kSharedSlots, exported, each with a timeline that orders the
    /// writer's writes against this renderer's reads.
    struct ClothSlot {
        DeviceBuffer buffer;
        VkSemaphore timeline = VK_NULL_HANDLE;
        std::uint64_t last_signal = 0;
        bool dedicated = false;
    };
    static constexpr int kSharedSlots = 2;
    std::vector<ClothSlot> slots_;
    DeviceBuffer cloth_staging_;   ///< host → slot uploads (vertices and stamps)
    DeviceBuffer stamp_readback_;  ///< the drawn slot's stamps, copied after the frame's draws
    bool exported_ = false;
    int frame_slot_ = 0;               ///< the slot the frame being recorded or in flight draws from
    bool frame_reads_stamps_ = false;  ///< it copies the slot's stamps to stamp_readback_
    DeviceBuffer uniforms_;  ///< Frame at 0, Draw i at draw_base_ + i·draw_stride_ (the scene's, then the overlay's draws, kOverlayDraws)
    VkDeviceSize draw_base_ = 0, draw_stride_ = 0;
    TransferStats transfer_{"host upload", 0};
};

/// Throws weft::Error when no Vulkan device can render (no loader, no ICD, no validation layer
/// when asked for).
[[nodiscard]] std::unique_ptr<Renderer> create_vulkan_renderer(const RendererOptions& options);

}  // namespace weft::render::detail
