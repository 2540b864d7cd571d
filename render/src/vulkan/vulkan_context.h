#pragma once
// The Vulkan instance, the chosen physical device, the logical device with its graphics queue and a
// command pool: what every Vulkan object of the renderer is made from. The validation layer and its
// message counter live here too, so that messages about the device's own destruction are counted.
// For the window (vulkan_window.cpp) it also owns the window's surface and picks a queue that can
// present to it.
#include <vulkan/vulkan.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace weft::render::detail {

/// What a context needs to draw into a window: the instance extensions of the window system
/// (glfwGetRequiredInstanceExtensions) and a function that creates the window's surface on the new
/// instance (glfwCreateWindowSurface). The context owns the surface from then on.
struct SurfaceRequest {
    std::vector<std::string> instance_extensions;
    std::function<VkSurfaceKHR(VkInstance)> create_surface;
};

class VulkanContext {
public:
    /// Creates the instance (API 1.1 or newer), picks a device (discrete GPU, then integrated, then
    /// virtual, then CPU, each with a graphics queue) and creates it with one graphics queue. With
    /// `validation`, enables VK_LAYER_KHRONOS_validation and VK_EXT_debug_utils with a messenger that
    /// counts warnings and errors and prints them to stderr ("vulkan validation: ..."). Throws
    /// weft::Error when there is no Vulkan device or no validation layer when asked for.
    ///
    /// With `surface`, the instance also enables its extensions, the surface is created right after
    /// the instance, and only devices with VK_KHR_swapchain and a graphics queue family that can
    /// present to the surface qualify; the device is created with VK_KHR_swapchain.
    explicit VulkanContext(bool validation, const SurfaceRequest* surface = nullptr);
    ~VulkanContext();
    VulkanContext(const VulkanContext&) = delete;
    VulkanContext& operator=(const VulkanContext&) = delete;

    [[nodiscard]] VkInstance instance() const { return instance_; }
    [[nodiscard]] VkPhysicalDevice physical_device() const { return physical_device_; }
    [[nodiscard]] VkDevice device() const { return device_; }
    [[nodiscard]] VkQueue queue() const { return queue_; }
    [[nodiscard]] std::uint32_t queue_family() const { return queue_family_; }
    /// The window's surface (VK_NULL_HANDLE without a SurfaceRequest); the queue can present to it.
    [[nodiscard]] VkSurfaceKHR surface() const { return surface_; }
    /// Command buffers from it can be reset one by one.
    [[nodiscard]] VkCommandPool command_pool() const { return command_pool_; }
    [[nodiscard]] const VkPhysicalDeviceProperties& properties() const { return properties_; }
    /// VkPhysicalDeviceIDProperties::deviceUUID: matches the CUDA device (cudaDeviceProp::uuid) that
    /// shares memory with this one.
    [[nodiscard]] const std::array<std::uint8_t, VK_UUID_SIZE>& device_uuid() const { return device_uuid_; }
    /// "<device name>, Vulkan <major.minor.patch>, driver <name> <info>".
    [[nodiscard]] const std::string& description() const { return description_; }
    /// Validation warnings and errors reported on this instance so far (0 without validation).
    [[nodiscard]] int validation_messages() const { return messages_.load(); }

    /// Zero-copy interop (vulkan_interop.h): the device exports memory and timeline semaphores as
    /// opaque fds, and the extensions for it are enabled. False on lavapipe (no exportable
    /// semaphores); `interop_unavailable_reason()` says what is missing.
    [[nodiscard]] bool interop_available() const { return interop_; }
    /// The device draws points wider than a pixel (VkPhysicalDeviceFeatures::largePoints, enabled
    /// where it has it): the overlay's marks.
    [[nodiscard]] bool large_points() const { return large_points_; }
    [[nodiscard]] const std::string& interop_unavailable_reason() const { return interop_reason_; }
    [[nodiscard]] PFN_vkGetMemoryFdKHR get_memory_fd() const { return get_memory_fd_; }
    [[nodiscard]] PFN_vkGetSemaphoreFdKHR get_semaphore_fd() const { return get_semaphore_fd_; }

    /// Index of a memory type among `type_bits` with every flag of `required`, the one with most of
    /// `preferred` first. Throws weft::Error when none has `required`.
    [[nodiscard]] std::uint32_t memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags required,
                                            VkMemoryPropertyFlags preferred = 0) const;
    /// Whether memory type `index` has every flag of `flags`.
    [[nodiscard]] bool memory_type_has(std::uint32_t index, VkMemoryPropertyFlags flags) const;

    /// Records `record` into a one-time command buffer, submits it and waits for it: load-time
    /// uploads, not the per-frame path.
    void submit_and_wait(const std::function<void(VkCommandBuffer)>& record) const;

private:
    void create_instance(bool validation, const SurfaceRequest* surface);
    void choose_physical_device();
    void create_device();
    void destroy() noexcept;

    VkInstance instance_ = VK_NULL_HANDLE;
    VkDebugUtilsMessengerEXT messenger_ = VK_NULL_HANDLE;
    VkSurfaceKHR surface_ = VK_NULL_HANDLE;
    VkPhysicalDevice physical_device_ = VK_NULL_HANDLE;
    VkDevice device_ = VK_NULL_HANDLE;
    VkQueue queue_ = VK_NULL_HANDLE;
    std::uint32_t queue_family_ = 0;
    VkCommandPool command_pool_ = VK_NULL_HANDLE;
    std::uint32_t instance_version_ = 0;  ///< the API version the instance was created with
    VkPhysicalDeviceProperties properties_{};
    VkPhysicalDeviceMemoryProperties memory_properties_{};
    std::array<std::uint8_t, VK_UUID_SIZE> device_uuid_{};
    std::string description_;
    std::atomic<int> messages_{0};  ///< written from the layer's callback, on any thread
    bool interop_ = false;
    bool large_points_ = false;
    std::string interop_reason_ = "not checked";
    PFN_vkGetMemoryFdKHR get_memory_fd_ = nullptr;
    PFN_vkGetSemaphoreFdKHR get_semaphore_fd_ = nullptr;
};

/// Validation warnings and errors of every VulkanContext of the process, including those reported
/// while one was being destroyed (leaked objects): what a test checks after a renderer is gone.
[[nodiscard]] int vulkan_validation_messages_total();

}  // namespace weft::render::detail
