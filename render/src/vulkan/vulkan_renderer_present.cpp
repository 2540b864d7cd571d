// The Vulkan renderer's presentation in a window (see vulkan_renderer.cpp; the window loop is
// vulkan_window.cpp): the frame's resolved picture, with the window's overlay drawn over it, blitted
// into an acquired swapchain image and not waited for (the next frame waits for its fence first).
#include "vulkan/vulkan_renderer.h"

#include <cstdint>

#include "weft/error.h"

#include "vulkan/vulkan_check.h"
#include "vulkan/vulkan_pipelines.h"

namespace weft::render::detail {

void VulkanRenderer::create_overlay_framebuffer() {
    VkFramebufferCreateInfo fb{};
    fb.sType = VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO;
    fb.layers = 1;
    fb.renderPass = overlay_pass_;
    fb.attachmentCount = 1;
    fb.pAttachments = &resolved_.view;
    fb.width = extent_.width;
    fb.height = extent_.height;
    WEFT_VK_CHECK(vkCreateFramebuffer(context_.device(), &fb, nullptr, &overlay_framebuffer_));
}

VkRenderPass VulkanRenderer::overlay_pass() {
    if (overlay_pass_ == VK_NULL_HANDLE) {
        overlay_pass_ = create_overlay_pass(context_.device(), kColourFormat);
        create_overlay_framebuffer();
    }
    return overlay_pass_;
}

void VulkanRenderer::draw_to_swapchain(const RenderFrame& frame, const SwapchainTarget& target) {
    if (target.image == VK_NULL_HANDLE || target.extent.width == 0 || target.extent.height == 0)
        throw Error("vulkan renderer: draw_to_swapchain without a swapchain image");
    // Scaling only happens for a frame drawn while the window changes size; linear where allowed.
    VkFormatProperties props{};
    vkGetPhysicalDeviceFormatProperties(context_.physical_device(), kColourFormat, &props);
    const bool same_size = target.extent.width == extent_.width && target.extent.height == extent_.height;
    const VkFilter filter =
        !same_size && (props.optimalTilingFeatures & VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT) != 0
            ? VK_FILTER_LINEAR
            : VK_FILTER_NEAREST;
    bool external = false;
    if (target.overlay && overlay_pass_ == VK_NULL_HANDLE)
        throw Error("vulkan renderer: an overlay without overlay_pass()");
    const bool upload = record_frame(frame, external, [&](VkCommandBuffer commands) {
        if (target.overlay) {
            // Drawn into the resolved picture, so that the read-back (screenshots) shows it too.
            VkRenderPassBeginInfo pass{};
            pass.sType = VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO;
            pass.renderPass = overlay_pass_;
            pass.framebuffer = overlay_framebuffer_;
            pass.renderArea.extent = extent_;
            vkCmdBeginRenderPass(commands, &pass, VK_SUBPASS_CONTENTS_INLINE);
            target.overlay(commands, extent_);
            vkCmdEndRenderPass(commands);
        }
        // The swapchain image's old contents are not needed: UNDEFINED → TRANSFER_DST. The stage
        // is the one the acquire semaphore is waited at, so the transition comes after the acquire.
        VkImageMemoryBarrier barrier{};
        barrier.sType = VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER;
        barrier.srcAccessMask = 0;
        barrier.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        barrier.oldLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        barrier.newLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
        barrier.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        barrier.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
        barrier.image = target.image;
        barrier.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
        vkCmdPipelineBarrier(commands, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_TRANSFER_BIT, 0, 0, nullptr,
                             0, nullptr, 1, &barrier);
        // The surface pass left the resolved picture in TRANSFER_SRC_OPTIMAL, its writes visible to
        // transfers; rows run top to bottom in both images.
        VkImageBlit blit{};
        blit.srcSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
        blit.srcOffsets[1] = {static_cast<std::int32_t>(extent_.width), static_cast<std::int32_t>(extent_.height), 1};
        blit.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
        blit.dstOffsets[1] = {static_cast<std::int32_t>(target.extent.width),
                              static_cast<std::int32_t>(target.extent.height), 1};
        vkCmdBlitImage(commands, resolved_.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, target.image,
                       VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &blit, filter);
        barrier.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
        barrier.dstAccessMask = 0;  // the present waits on the semaphore signalled after this submission
        barrier.oldLayout = VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL;
        barrier.newLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
        vkCmdPipelineBarrier(commands, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, 0, 0,
                             nullptr, 0, nullptr, 1, &barrier);
    });
    submit_frame(frame, target.acquired, target.rendered);
    have_picture_ = true;
    submitted_ = false;  // the picture went to the window, not to collect()
    // The stamps stay those of the last frame waited for until this one is (wait_frame).
    transfer_.path = external ? "interop" : "host upload";
    transfer_.bytes_uploaded = upload ? static_cast<std::uint64_t>(frame.cloth.size_bytes()) : 0;
}

}  // namespace weft::render::detail
