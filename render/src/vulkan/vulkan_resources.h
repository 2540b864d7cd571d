#pragma once
// Buffers and images with their own device memory: the renderer holds few of them (targets, the
// cloth and static geometry, uniforms, staging and read-back), so one allocation each is enough and
// no allocator is needed.
#include <vulkan/vulkan.h>

#include "vulkan/vulkan_context.h"

namespace weft::render::detail {

/// Where a buffer's memory lives and how the host reaches it.
enum class MemoryUse {
    device_local,  ///< the GPU's own memory; filled by copies
    upload,        ///< host-visible and coherent, mapped for the buffer's lifetime: staging, uniforms
    readback,      ///< host-visible, cached where the device has it, mapped: images read back
};

struct DeviceBuffer {
    VkBuffer buffer = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkDeviceSize size = 0;   ///< bytes asked for
    VkDeviceSize allocation_size = 0;  ///< bytes of the memory allocation (exported buffers)
    void* mapped = nullptr;  ///< host address of byte 0 (upload and readback buffers)
    bool coherent = true;    ///< false: device writes need vkInvalidateMappedMemoryRanges (`invalidate`)
};

/// A buffer of `size` bytes (> 0) for `usage`, its memory bound (and mapped, for host uses).
[[nodiscard]] DeviceBuffer create_buffer(const VulkanContext& context, VkDeviceSize size, VkBufferUsageFlags usage,
                                         MemoryUse use);
/// Makes the device's writes to a mapped buffer visible to the host: nothing to do on coherent memory.
void invalidate(const VulkanContext& context, const DeviceBuffer& buffer);
/// Destroys `buffer` and frees its memory; leaves it empty. A no-op on an empty buffer.
void destroy_buffer(VkDevice device, DeviceBuffer& buffer) noexcept;
/// Records a barrier that makes a transfer's writes into `buffer` visible to the host once the
/// submission's fence signals.
void to_host_barrier(VkCommandBuffer commands, VkBuffer buffer);

struct DeviceImage {
    VkImage image = VK_NULL_HANDLE;
    VkDeviceMemory memory = VK_NULL_HANDLE;
    VkImageView view = VK_NULL_HANDLE;
};

/// A 2D image in device-local memory (lazily allocated where the device has it and `usage` is
/// transient) with a view of `aspect`, in VK_IMAGE_LAYOUT_UNDEFINED.
[[nodiscard]] DeviceImage create_image(const VulkanContext& context, VkExtent2D extent, VkFormat format,
                                       VkSampleCountFlagBits samples, VkImageUsageFlags usage,
                                       VkImageAspectFlags aspect);
/// Destroys the view, the image and its memory; leaves it empty. A no-op on an empty image.
void destroy_image(VkDevice device, DeviceImage& image) noexcept;

}  // namespace weft::render::detail
