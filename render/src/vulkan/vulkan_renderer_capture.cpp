// The Vulkan renderer's offscreen capture (see vulkan_renderer.cpp): the frame ends with a copy of
// the resolved picture to a host-visible buffer, and collect() waits for the frame's fence and hands
// the picture out (capture, not presentation: the frame is needed on the host at once).
#include "vulkan/vulkan_renderer.h"

#include <cstring>

#include "weft/error.h"

#include "vulkan/vulkan_resources.h"

namespace weft::render::detail {

void VulkanRenderer::submit(const RenderFrame& frame) {
    bool external = false;
    const bool upload = record_frame(frame, external, [&](VkCommandBuffer commands) { record_readback(commands); });
    submit_frame(frame, VK_NULL_HANDLE, VK_NULL_HANDLE);
    have_picture_ = true;
    submitted_ = true;
    // The stamps stay those of the last frame waited for until this one is (wait_frame).
    transfer_.path = external ? "interop" : "host upload";
    transfer_.bytes_uploaded = upload ? static_cast<std::uint64_t>(frame.cloth.size_bytes()) : 0;
}

Image VulkanRenderer::collect() {
    if (!submitted_) throw Error("vulkan renderer: collect() without a submitted frame");
    wait_frame();
    submitted_ = false;
    invalidate(context_, readback_);
    Image image(options_.width, options_.height);
    std::memcpy(image.rgba.data(), readback_.mapped, image.rgba.size());
    return image;
}

Image VulkanRenderer::read_back() {
    if (!have_picture_) throw Error("vulkan renderer: read_back() before a frame was drawn");
    wait_frame();
    context_.submit_and_wait([&](VkCommandBuffer commands) { record_readback(commands); });
    invalidate(context_, readback_);
    Image image(options_.width, options_.height);
    std::memcpy(image.rgba.data(), readback_.mapped, image.rgba.size());
    return image;
}

void VulkanRenderer::record_readback(VkCommandBuffer commands) const {
    // The render pass left the picture in TRANSFER_SRC_OPTIMAL; rows come out top to bottom because
    // the viewport is flipped.
    VkBufferImageCopy copy{};
    copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
    copy.imageExtent = {extent_.width, extent_.height, 1};
    vkCmdCopyImageToBuffer(commands, resolved_.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, readback_.buffer, 1, &copy);
    to_host_barrier(commands, readback_.buffer);
}

}  // namespace weft::render::detail
