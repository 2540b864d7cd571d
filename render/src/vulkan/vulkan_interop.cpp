// Exportable cloth buffer and timeline semaphore (see vulkan_interop.h).
#include "vulkan/vulkan_interop.h"

#include "vulkan/vulkan_check.h"
#include "weft/error.h"

namespace weft::render::detail {

DeviceBuffer create_exportable_buffer(const VulkanContext& context, VkDeviceSize size, VkBufferUsageFlags usage,
                                      bool& dedicated) {
    if (!context.interop_available())
        throw Error("vulkan renderer: no interop on " + context.description() + ": " +
                    context.interop_unavailable_reason());
    const VkDevice device = context.device();
    DeviceBuffer b;
    b.size = size;
    try {
        VkExternalMemoryBufferCreateInfo external{};
        external.sType = VK_STRUCTURE_TYPE_EXTERNAL_MEMORY_BUFFER_CREATE_INFO;
        external.handleTypes = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
        VkBufferCreateInfo info{};
        info.sType = VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO;
        info.pNext = &external;
        info.size = size;
        info.usage = usage;
        info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
        WEFT_VK_CHECK(vkCreateBuffer(device, &info, nullptr, &b.buffer));
        VkMemoryRequirements needs{};
        vkGetBufferMemoryRequirements(device, b.buffer, &needs);
        // Dedicated: one buffer per allocation, as CUDA's import is told (cudaExternalMemoryDedicated);
        // drivers prefer it for exported memory, some require it.
        VkMemoryDedicatedAllocateInfo dedicated_info{};
        dedicated_info.sType = VK_STRUCTURE_TYPE_MEMORY_DEDICATED_ALLOCATE_INFO;
        dedicated_info.buffer = b.buffer;
        VkExportMemoryAllocateInfo export_info{};
        export_info.sType = VK_STRUCTURE_TYPE_EXPORT_MEMORY_ALLOCATE_INFO;
        export_info.pNext = &dedicated_info;
        export_info.handleTypes = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
        VkMemoryAllocateInfo alloc{};
        alloc.sType = VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO;
        alloc.pNext = &export_info;
        alloc.allocationSize = needs.size;
        alloc.memoryTypeIndex = context.memory_type(needs.memoryTypeBits, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
        WEFT_VK_CHECK(vkAllocateMemory(device, &alloc, nullptr, &b.memory));
        WEFT_VK_CHECK(vkBindBufferMemory(device, b.buffer, b.memory, 0));
        b.allocation_size = needs.size;
        dedicated = true;
    } catch (...) {
        destroy_buffer(device, b);
        throw;
    }
    return b;
}

VkSemaphore create_exportable_timeline(const VulkanContext& context) {
    VkSemaphoreTypeCreateInfo type{};
    type.sType = VK_STRUCTURE_TYPE_SEMAPHORE_TYPE_CREATE_INFO;
    type.semaphoreType = VK_SEMAPHORE_TYPE_TIMELINE;
    type.initialValue = 0;
    VkExportSemaphoreCreateInfo export_info{};
    export_info.sType = VK_STRUCTURE_TYPE_EXPORT_SEMAPHORE_CREATE_INFO;
    export_info.pNext = &type;
    export_info.handleTypes = VK_EXTERNAL_SEMAPHORE_HANDLE_TYPE_OPAQUE_FD_BIT;
    VkSemaphoreCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO;
    info.pNext = &export_info;
    VkSemaphore semaphore = VK_NULL_HANDLE;
    WEFT_VK_CHECK(vkCreateSemaphore(context.device(), &info, nullptr, &semaphore));
    return semaphore;
}

ExternalMemoryHandle export_memory(const VulkanContext& context, const DeviceBuffer& buffer, bool dedicated) {
    VkMemoryGetFdInfoKHR get{};
    get.sType = VK_STRUCTURE_TYPE_MEMORY_GET_FD_INFO_KHR;
    get.memory = buffer.memory;
    get.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
    ExternalMemoryHandle h;
    WEFT_VK_CHECK(context.get_memory_fd()(context.device(), &get, &h.fd));
    h.allocation_size = buffer.allocation_size;
    h.offset = 0;
    h.size = buffer.size;
    h.dedicated = dedicated;
    return h;
}

ExternalTimelineHandle export_timeline(const VulkanContext& context, VkSemaphore semaphore) {
    VkSemaphoreGetFdInfoKHR get{};
    get.sType = VK_STRUCTURE_TYPE_SEMAPHORE_GET_FD_INFO_KHR;
    get.semaphore = semaphore;
    get.handleType = VK_EXTERNAL_SEMAPHORE_HANDLE_TYPE_OPAQUE_FD_BIT;
    ExternalTimelineHandle h;
    WEFT_VK_CHECK(context.get_semaphore_fd()(context.device(), &get, &h.fd));
    return h;
}

}  // namespace weft::render::detail
