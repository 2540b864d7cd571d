// The window's swapchain (see vulkan_swapchain.h).
#include "vulkan/vulkan_swapchain.h"

#include <algorithm>
#include <string>

#include "weft/error.h"

#include "vulkan/vulkan_check.h"

namespace weft::render::detail {
namespace {

Swapchain::Status status_of(VkResult result, const char* call) {
    if (result == VK_SUCCESS) return Swapchain::Status::ok;
    if (result == VK_SUBOPTIMAL_KHR) return Swapchain::Status::suboptimal;
    if (result == VK_ERROR_OUT_OF_DATE_KHR) return Swapchain::Status::out_of_date;
    vk_check(result, call, __FILE__, __LINE__);
    return Swapchain::Status::ok;  // not reached: vk_check threw
}

}  // namespace

Swapchain::Swapchain(const VulkanContext& context, VkExtent2D framebuffer) : context_(context) {
    try {
        create(framebuffer, VK_NULL_HANDLE);
    } catch (...) {
        destroy_semaphores();
        if (swapchain_ != VK_NULL_HANDLE) vkDestroySwapchainKHR(context_.device(), swapchain_, nullptr);
        throw;
    }
}

Swapchain::~Swapchain() {
    const VkDevice device = context_.device();
    vkDeviceWaitIdle(device);
    destroy_semaphores();
    if (swapchain_ != VK_NULL_HANDLE) vkDestroySwapchainKHR(device, swapchain_, nullptr);
}

void Swapchain::destroy_semaphores() noexcept {
    for (VkSemaphore s : rendered_) vkDestroySemaphore(context_.device(), s, nullptr);
    rendered_.clear();
}

void Swapchain::recreate(VkExtent2D framebuffer) {
    WEFT_VK_CHECK(vkDeviceWaitIdle(context_.device()));
    const VkSwapchainKHR old = swapchain_;
    swapchain_ = VK_NULL_HANDLE;
    destroy_semaphores();
    images_.clear();
    try {
        create(framebuffer, old);
    } catch (...) {
        vkDestroySwapchainKHR(context_.device(), old, nullptr);
        throw;
    }
    vkDestroySwapchainKHR(context_.device(), old, nullptr);
}

void Swapchain::create(VkExtent2D framebuffer, VkSwapchainKHR old) {
    const VkPhysicalDevice physical = context_.physical_device();
    const VkDevice device = context_.device();
    const VkSurfaceKHR surface = context_.surface();
    if (surface == VK_NULL_HANDLE) throw Error("vulkan renderer: a swapchain on a context without a surface");

    VkSurfaceCapabilitiesKHR caps{};
    WEFT_VK_CHECK(vkGetPhysicalDeviceSurfaceCapabilitiesKHR(physical, surface, &caps));
    if ((caps.supportedUsageFlags & VK_IMAGE_USAGE_TRANSFER_DST_BIT) == 0)
        throw Error("vulkan renderer: the window's swapchain images cannot be transfer destinations on " +
                    context_.description());

    std::uint32_t count = 0;
    WEFT_VK_CHECK(vkGetPhysicalDeviceSurfaceFormatsKHR(physical, surface, &count, nullptr));
    std::vector<VkSurfaceFormatKHR> formats(count);
    WEFT_VK_CHECK(vkGetPhysicalDeviceSurfaceFormatsKHR(physical, surface, &count, formats.data()));
    formats.resize(count);
    // UNORM, not SRGB: the shader writes sRGB-encoded values, which must reach the screen as they are.
    format_ = VK_FORMAT_UNDEFINED;
    VkColorSpaceKHR colour_space = VK_COLOR_SPACE_SRGB_NONLINEAR_KHR;
    for (const VkFormat wanted : {VK_FORMAT_B8G8R8A8_UNORM, VK_FORMAT_R8G8B8A8_UNORM}) {
        for (const VkSurfaceFormatKHR& f : formats) {
            if (f.format != wanted || f.colorSpace != VK_COLOR_SPACE_SRGB_NONLINEAR_KHR) continue;
            VkFormatProperties props{};
            vkGetPhysicalDeviceFormatProperties(physical, f.format, &props);
            if ((props.optimalTilingFeatures & VK_FORMAT_FEATURE_BLIT_DST_BIT) == 0) continue;
            format_ = f.format;
            colour_space = f.colorSpace;
            break;
        }
        if (format_ != VK_FORMAT_UNDEFINED) break;
    }
    if (format_ == VK_FORMAT_UNDEFINED)
        throw Error(
            "vulkan renderer: the window's surface offers neither B8G8R8A8_UNORM nor R8G8B8A8_UNORM "
            "(sRGB non-linear, blit destination) on " +
            context_.description());

    // The surface decides the size, unless it says 0xFFFFFFFF (then the framebuffer's, clamped).
    if (caps.currentExtent.width != UINT32_MAX) {
        extent_ = caps.currentExtent;
    } else {
        extent_.width = std::clamp(framebuffer.width, caps.minImageExtent.width, caps.maxImageExtent.width);
        extent_.height = std::clamp(framebuffer.height, caps.minImageExtent.height, caps.maxImageExtent.height);
    }
    // One more image than the minimum, so that acquiring need not wait for the presentation engine.
    std::uint32_t images = caps.minImageCount + 1;
    if (caps.maxImageCount != 0) images = std::min(images, caps.maxImageCount);

    VkSwapchainCreateInfoKHR info{};
    info.sType = VK_STRUCTURE_TYPE_SWAPCHAIN_CREATE_INFO_KHR;
    info.surface = surface;
    info.minImageCount = images;
    info.imageFormat = format_;
    info.imageColorSpace = colour_space;
    info.imageExtent = extent_;
    info.imageArrayLayers = 1;
    info.imageUsage = VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    info.imageSharingMode = VK_SHARING_MODE_EXCLUSIVE;  // one queue draws and presents
    info.preTransform = (caps.supportedTransforms & VK_SURFACE_TRANSFORM_IDENTITY_BIT_KHR) != 0
                            ? VK_SURFACE_TRANSFORM_IDENTITY_BIT_KHR
                            : caps.currentTransform;
    info.compositeAlpha = VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR;
    for (const VkCompositeAlphaFlagBitsKHR a :
         {VK_COMPOSITE_ALPHA_OPAQUE_BIT_KHR, VK_COMPOSITE_ALPHA_INHERIT_BIT_KHR,
          VK_COMPOSITE_ALPHA_PRE_MULTIPLIED_BIT_KHR, VK_COMPOSITE_ALPHA_POST_MULTIPLIED_BIT_KHR})
        if ((caps.supportedCompositeAlpha & a) != 0) {
            info.compositeAlpha = a;
            break;
        }
    // FIFO: paced by the display, and the only mode every device has.
    info.presentMode = VK_PRESENT_MODE_FIFO_KHR;
    info.clipped = VK_TRUE;
    info.oldSwapchain = old;
    WEFT_VK_CHECK(vkCreateSwapchainKHR(device, &info, nullptr, &swapchain_));

    WEFT_VK_CHECK(vkGetSwapchainImagesKHR(device, swapchain_, &count, nullptr));
    images_.resize(count);
    WEFT_VK_CHECK(vkGetSwapchainImagesKHR(device, swapchain_, &count, images_.data()));
    images_.resize(count);
    VkSemaphoreCreateInfo semaphore{};
    semaphore.sType = VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO;
    for (std::uint32_t i = 0; i < count; ++i) {
        VkSemaphore s = VK_NULL_HANDLE;
        WEFT_VK_CHECK(vkCreateSemaphore(device, &semaphore, nullptr, &s));
        rendered_.push_back(s);
    }
}

Swapchain::Status Swapchain::acquire(VkSemaphore acquired, std::uint32_t& index) {
    return status_of(vkAcquireNextImageKHR(context_.device(), swapchain_, UINT64_MAX, acquired, VK_NULL_HANDLE, &index),
                     "vkAcquireNextImageKHR");
}

Swapchain::Status Swapchain::present(std::uint32_t index) {
    VkPresentInfoKHR info{};
    info.sType = VK_STRUCTURE_TYPE_PRESENT_INFO_KHR;
    info.waitSemaphoreCount = 1;
    info.pWaitSemaphores = &rendered_.at(index);
    info.swapchainCount = 1;
    info.pSwapchains = &swapchain_;
    info.pImageIndices = &index;
    return status_of(vkQueuePresentKHR(context_.queue(), &info), "vkQueuePresentKHR");
}

}  // namespace weft::render::detail
