#pragma once
// Zero-copy interop on the Vulkan side (docs/rendering.md): the cloth vertex buffer in exportable
// device memory and a timeline semaphore, both handed out as opaque fds for CUDA to import
// (weft/cuda/external_memory.h). Only on a context whose interop_available() is true.
#include <vulkan/vulkan.h>

#include "vulkan/vulkan_context.h"
#include "vulkan/vulkan_resources.h"
#include "weft/backend/interop.h"

namespace weft::render::detail {

/// A device-local buffer of `size` bytes for `usage` whose memory (a dedicated allocation) can be
/// exported as an opaque fd. `dedicated` reports whether the allocation is dedicated (the importer
/// must say so).
[[nodiscard]] DeviceBuffer create_exportable_buffer(const VulkanContext& context, VkDeviceSize size,
                                                    VkBufferUsageFlags usage, bool& dedicated);
/// A timeline semaphore at value 0 that can be exported as an opaque fd.
[[nodiscard]] VkSemaphore create_exportable_timeline(const VulkanContext& context);

/// A new fd for `buffer`'s memory; the caller (or the importer) owns it.
[[nodiscard]] ExternalMemoryHandle export_memory(const VulkanContext& context, const DeviceBuffer& buffer,
                                                 bool dedicated);
/// A new fd for `semaphore`; the caller (or the importer) owns it.
[[nodiscard]] ExternalTimelineHandle export_timeline(const VulkanContext& context, VkSemaphore semaphore);

}  // namespace weft::render::detail
