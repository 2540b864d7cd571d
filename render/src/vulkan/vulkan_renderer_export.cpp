// The Vulkan renderer's interop export (docs/rendering.md; see vulkan_renderer.cpp): the cloth
// vertex buffer replaced by kSharedSlots exportable slots, each with a timeline semaphore, handed to
// CUDA as fds; the queue-family ownership transfers around every frame that reads a slot; frames
// that only pass their timeline values on (skip_frame); and a slot read back (tests).
#include "vulkan/vulkan_renderer.h"

#include <algorithm>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "weft/error.h"

#include "vulkan/vulkan_interop.h"
#include "vulkan/vulkan_resources.h"

namespace weft::render::detail {

std::optional<ClothInterop> VulkanRenderer::export_cloth(std::string& why) {
    if (!loaded_) throw Error("vulkan renderer: export_cloth() before load()");
    if (!context_.interop_available()) {
        why = context_.interop_unavailable_reason();  // the device is in device_description()
        return std::nullopt;
    }
    if (slots_.empty()) {
        why = "the scene has no cloth";
        return std::nullopt;
    }
    const VkDevice device = context_.device();
    wait_frame();  // a window's frame may still read the buffer replaced below
    if (!exported_) {
        // Replace the cloth buffer by kSharedSlots exportable ones (zeros, as load() leaves it), each
        // with its timeline.
        std::vector<ClothSlot> shared(kSharedSlots);
        try {
            for (ClothSlot& slot : shared) {
                slot.buffer = create_exportable_buffer(context_, slots_[0].buffer.size,
                                                       VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                                                           VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                                                       slot.dedicated);
                slot.timeline = create_exportable_timeline(context_);
            }
            // No fill here: the writer zeroes a slot when it imports it, on its own stream, so the
            // zeros are ordered before its first frame. Only the ownership goes to the writer, so
            // that every frame's acquire matches a release.
            context_.submit_and_wait([&](VkCommandBuffer commands) {
                for (const ClothSlot& slot : shared) {
                    VkBufferMemoryBarrier release{};
                    release.sType = VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER;
                    release.srcQueueFamilyIndex = context_.queue_family();
                    release.dstQueueFamilyIndex = VK_QUEUE_FAMILY_EXTERNAL;
                    release.buffer = slot.buffer.buffer;
                    release.size = VK_WHOLE_SIZE;
                    vkCmdPipelineBarrier(commands, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT,
                                         0, 0, nullptr, 1, &release, 0, nullptr);
                }
            });
        } catch (...) {
            for (ClothSlot& slot : shared) {
                destroy_buffer(device, slot.buffer);
                if (slot.timeline != VK_NULL_HANDLE) vkDestroySemaphore(device, slot.timeline, nullptr);
            }
            throw;
        }
        destroy_buffer(device, slots_[0].buffer);
        slots_ = std::move(shared);
        exported_ = true;
    }
    ClothInterop link;
    try {
        for (const ClothSlot& slot : slots_) {
            SharedSlotHandle handle;
            handle.memory = export_memory(context_, slot.buffer, slot.dedicated);
            link.slots.push_back(handle);
            link.slots.back().timeline = export_timeline(context_, slot.timeline);
            // The last value this renderer signalled is the highest any access asked for (a draw
            // or skip_frame ends every access), and wait_frame() above saw it reached.
            link.timeline_values.push_back(slot.last_signal);
        }
    } catch (...) {
        close_slot_handles(link.slots);
        throw;
    }
    std::copy(context_.device_uuid().begin(), context_.device_uuid().end(), link.device_uuid.begin());
    return link;
}

std::vector<RenderVertex> VulkanRenderer::read_cloth(int slot) {
    if (!loaded_) throw Error("vulkan renderer: read_cloth() before load()");
    std::vector<RenderVertex> out(scene_.cloth_vertices);
    if (out.empty()) return out;
    if (slot < 0 || slot >= static_cast<int>(slots_.size()))
        throw Error("vulkan renderer: read_cloth(" + std::to_string(slot) + ") of " + std::to_string(slots_.size()) +
                    " slots");
    wait_frame();
    const DeviceBuffer& source = slots_[static_cast<std::size_t>(slot)].buffer;
    DeviceBuffer host = create_buffer(context_, source.size, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUse::readback);
    try {
        context_.submit_and_wait([&](VkCommandBuffer commands) {
            if (exported_) external_barrier(commands, slot, true);
            const VkBufferCopy copy{0, 0, source.size};
            vkCmdCopyBuffer(commands, source.buffer, host.buffer, 1, &copy);
            VkMemoryBarrier to_host{};
            to_host.sType = VK_STRUCTURE_TYPE_MEMORY_BARRIER;
            to_host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
            to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
            vkCmdPipelineBarrier(commands, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &to_host, 0,
                                 nullptr, 0, nullptr);
            if (exported_) external_barrier(commands, slot, false);
        });
        invalidate(context_, host);
        std::memcpy(out.data(), host.mapped, out.size() * sizeof(RenderVertex));
    } catch (...) {
        destroy_buffer(context_.device(), host);
        throw;
    }
    destroy_buffer(context_.device(), host);
    return out;
}

void VulkanRenderer::external_barrier(VkCommandBuffer commands, int slot, bool acquire) const {
    VkBufferMemoryBarrier barrier{};
    barrier.sType = VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER;
    // Transfer writes too: an upload frame on an exported renderer copies into the slot.
    const VkAccessFlags access =
        VK_ACCESS_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
    barrier.srcAccessMask = acquire ? 0 : access;
    barrier.dstAccessMask = acquire ? access : 0;
    barrier.srcQueueFamilyIndex = acquire ? VK_QUEUE_FAMILY_EXTERNAL : context_.queue_family();
    barrier.dstQueueFamilyIndex = acquire ? context_.queue_family() : VK_QUEUE_FAMILY_EXTERNAL;
    barrier.buffer = slots_[static_cast<std::size_t>(slot)].buffer.buffer;
    barrier.offset = 0;
    barrier.size = VK_WHOLE_SIZE;
    // The acquire's first scope is the stages the timeline wait blocks (submit_frame), so that it
    // comes after the writer's signal; the release follows every read of the frame.
    const VkPipelineStageFlags all = VK_PIPELINE_STAGE_ALL_COMMANDS_BIT, bottom = VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT;
    vkCmdPipelineBarrier(commands, acquire ? kSlotReadStages : all, acquire ? kSlotReadStages : bottom,
                         0, 0, nullptr, 1, &barrier, 0, nullptr);
}

void VulkanRenderer::skip_frame(const RenderFrame& frame) {
    if (frame.wait_value == 0 && frame.signal_value == 0) return;
    if (!exported_ || frame.cloth_slot < 0 || frame.cloth_slot >= static_cast<int>(slots_.size()))
        throw Error("vulkan renderer: skip_frame() of a frame that names no exported slot");
    wait_frame();
    frame_reads_stamps_ = false;  // nothing read: transfer() keeps the last drawn frame's stamps
    submit_frame(frame, VK_NULL_HANDLE, VK_NULL_HANDLE, false);
}

}  // namespace weft::render::detail
