#pragma once
// The window's swapchain (vulkan_window.cpp): images the resolved picture is blitted into, one
// "rendered" semaphore per image for the present to wait on, and recreation when the window changes
// size or the swapchain goes out of date.
#include <vulkan/vulkan.h>

#include <cstdint>
#include <vector>

#include "vulkan/vulkan_context.h"

namespace weft::render::detail {

class Swapchain {
public:
    enum class Status : unsigned char {
        ok,
        suboptimal,   ///< usable, but should be recreated (VK_SUBOPTIMAL_KHR)
        out_of_date,  ///< not usable: recreate first (VK_ERROR_OUT_OF_DATE_KHR)
    };

    /// A swapchain on `context`'s surface sized to `framebuffer` where the surface leaves the size to
    /// the application. Format B8G8R8A8_UNORM or R8G8B8A8_UNORM (not sRGB: the shader already
    /// encodes), usable as a blit destination; FIFO presentation (every device has it). Throws
    /// weft::Error when the surface offers neither format or no transfer-destination images.
    Swapchain(const VulkanContext& context, VkExtent2D framebuffer);
    ~Swapchain();
    Swapchain(const Swapchain&) = delete;
    Swapchain& operator=(const Swapchain&) = delete;

    /// Waits for the device to go idle (nothing may use the old images), then makes a new swapchain
    /// from the old one for the window's current size.
    void recreate(VkExtent2D framebuffer);

    [[nodiscard]] VkExtent2D extent() const { return extent_; }
    [[nodiscard]] VkFormat format() const { return format_; }
    [[nodiscard]] VkImage image(std::uint32_t index) const { return images_.at(index); }
    [[nodiscard]] VkSemaphore rendered(std::uint32_t index) const { return rendered_.at(index); }

    /// vkAcquireNextImageKHR, signalling `acquired`. On out_of_date nothing was acquired or
    /// signalled.
    [[nodiscard]] Status acquire(VkSemaphore acquired, std::uint32_t& index);
    /// vkQueuePresentKHR of image `index` after its rendered() semaphore.
    [[nodiscard]] Status present(std::uint32_t index);

private:
    void create(VkExtent2D framebuffer, VkSwapchainKHR old);
    void destroy_semaphores() noexcept;

    const VulkanContext& context_;
    VkSwapchainKHR swapchain_ = VK_NULL_HANDLE;
    VkFormat format_ = VK_FORMAT_UNDEFINED;
    VkExtent2D extent_{};
    std::vector<VkImage> images_;
    std::vector<VkSemaphore> rendered_;
};

}  // namespace weft::render::detail
