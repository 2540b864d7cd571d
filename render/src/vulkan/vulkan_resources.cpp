// Buffers and images with their own memory (see vulkan_resources.h).
#include "vulkan/vulkan_resources.h"

#include "vulkan/vulkan_check.h"

namespace weft::render::detail {

DeviceBuffer create_buffer(const VulkanContext& context, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUse use) {
    const VkDevice device = context.device();
    DeviceBuffer b;
    b.size = size;
    try {
        VkBufferCreateInfo info{};
        info.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        info.size = size;
        info.usage = usage;
        info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
        WEFT_VK_CHECK(vkCreateBuffer(device, &info, nullptr, &b.buffer));
        VkMemoryRequirements needs{};
        vkGetBufferMemoryRequirements(device, b.buffer, &needs);
        std::uint32_t type = 0;
        switch (use) {
            case MemoryUse::device_local:
                type = context.memory_type(needs.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
                break;
            case MemoryUse::upload:
                type = context.memory_type(needs.memoryTypeBits,
                                           VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
                break;
            case MemoryUse::readback:
                // Cached memory reads fast from the CPU; it may not be coherent (then `invalidate`).
                type = context.memory_type(needs.memoryTypeBits, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT,
                                           VK_MEMORY_PROPERTY_HOST_CACHED_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
                break;
        }
        b.coherent = context.memory_type_has(type, VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
        VkMemoryAllocateInfo alloc{};
        alloc.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
        alloc.allocationSize = needs.size;
        alloc.memoryTypeIndex = type;
        WEFT_VK_CHECK(vkAllocateMemory(device, &alloc, nullptr, &b.memory));
        WEFT_VK_CHECK(vkBindBufferMemory(device, b.buffer, b.memory, 0));
        if (use != MemoryUse::device_local)
            WEFT_VK_CHECK(vkMapMemory(device, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped));
    } catch (...) {
        destroy_buffer(device, b);
        throw;
    }
    return b;
}

void invalidate(const VulkanContext& context, const DeviceBuffer& buffer) {
    if (buffer.coherent || buffer.mapped == nullptr) return;
    VkMappedMemoryRange range{};
    range.sType = VK_STRUCTURE_TYPE_MAPPED_MEMORY_RANGE;
    range.memory = buffer.memory;
    range.offset = 0;
    range.size = VK_WHOLE_SIZE;
    WEFT_VK_CHECK(vkInvalidateMappedMemoryRanges(context.device(), 1, &range));
}

void destroy_buffer(VkDevice device, DeviceBuffer& buffer) noexcept {
    if (buffer.buffer != VK_NULL_HANDLE) vkDestroyBuffer(device, buffer.buffer, nullptr);
    // Freeing mapped memory unmaps it.
    if (buffer.memory != VK_NULL_HANDLE) vkFreeMemory(device, buffer.memory, nullptr);
    buffer = DeviceBuffer{};
}

void to_host_barrier(VkCommandBuffer commands, VkBuffer buffer) {
    VkBufferMemoryBarrier to_host{};
    to_host.sType = VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER;
    to_host.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    to_host.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    to_host.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    to_host.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
    to_host.buffer = buffer;
    to_host.offset = 0;
    to_host.size = VK_WHOLE_SIZE;
    vkCmdPipelineBarrier(commands, VK_PIPELINE_STAGE_TRANSFER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 0, nullptr, 1,
                         &to_host, 0, nullptr);
}

DeviceImage create_image(const VulkanContext& context, VkExtent2D extent, VkFormat format,
                         VkSampleCountFlagBits samples, VkImageUsageFlags usage, VkImageAspectFlags aspect) {
    const VkDevice device = context.device();
    DeviceImage image;
    try {
        VkImageCreateInfo info{};
        info.sType = VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO;
        info.imageType = VK_IMAGE_TYPE_2D;
        info.format = format;
        info.extent = {extent.width, extent.height, 1};
        info.mipLevels = 1;
        info.arrayLayers = 1;
        info.samples = samples;
        info.tiling = VK_IMAGE_TILING_OPTIMAL;
        info.usage = usage;
        info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
        info.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
        WEFT_VK_CHECK(vkCreateImage(device, &info, nullptr, &image.image));
        VkMemoryRequirements needs{};
        vkGetImageMemoryRequirements(device, image.image, &needs);
        // Multisampled attachments that are resolved and never stored can live in tile memory only.
        const VkMemoryPropertyFlags preferred =
            (usage & VK_IMAGE_USAGE_TRANSIENT_ATTACHMENT_BIT) != 0 ? VK_MEMORY_PROPERTY_LAZILY_ALLOCATED_BIT : 0;
        VkMemoryAllocateInfo alloc{};
        alloc.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
        alloc.allocationSize = needs.size;
        alloc.memoryTypeIndex =
            context.memory_type(needs.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, preferred);
        WEFT_VK_CHECK(vkAllocateMemory(device, &alloc, nullptr, &image.memory));
        WEFT_VK_CHECK(vkBindImageMemory(device, image.image, image.memory, 0));

        VkImageViewCreateInfo view{};
        view.sType = VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO;
        view.image = image.image;
        view.viewType = VK_IMAGE_VIEW_TYPE_2D;
        view.format = format;
        view.subresourceRange = {aspect, 0, 1, 0, 1};
        WEFT_VK_CHECK(vkCreateImageView(device, &view, nullptr, &image.view));
    } catch (...) {
        destroy_image(device, image);
        throw;
    }
    return image;
}

void destroy_image(VkDevice device, DeviceImage& image) noexcept {
    if (image.view != VK_NULL_HANDLE) vkDestroyImageView(device, image.view, nullptr);
    if (image.image != VK_NULL_HANDLE) vkDestroyImage(device, image.image, nullptr);
    if (image.memory != VK_NULL_HANDLE) vkFreeMemory(device, image.memory, nullptr);
    image = DeviceImage{};
}

}  // namespace weft::render::detail
