// Instance, validation messenger, device choice, device, queue and command pool (see vulkan_context.h).
#include "vulkan/vulkan_context.h"

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>
#include <vector>

#include "weft/error.h"

#include "vulkan/vulkan_check.h"

namespace weft::render::detail {
namespace {

constexpr const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

std::atomic<int> g_validation_messages{0};

// Counts and prints warnings and errors; returns VK_FALSE so that the call goes on as it would
// without the layer (the spec's rule for the callback).
VKAPI_ATTR VkBool32 VKAPI_CALL on_validation_message(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                                     VkDebugUtilsMessageTypeFlagsEXT /*types*/,
                                                     const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
    constexpr VkDebugUtilsMessageSeverityFlagsEXT counted =
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    if ((severity & counted) == 0) return VK_FALSE;
    ++*static_cast<std::atomic<int>*>(user);
    ++g_validation_messages;
    std::fprintf(stderr, "vulkan validation: %s\n",
                 data != nullptr && data->pMessage != nullptr ? data->pMessage : "?");
    return VK_FALSE;
}

bool has_layer(const char* name) {
    std::uint32_t count = 0;
    WEFT_VK_CHECK(vkEnumerateInstanceLayerProperties(&count, nullptr));
    std::vector<VkLayerProperties> layers(count);
    WEFT_VK_CHECK(vkEnumerateInstanceLayerProperties(&count, layers.data()));
    return std::any_of(layers.begin(), layers.begin() + count,
                       [&](const VkLayerProperties& l) { return std::strcmp(l.layerName, name) == 0; });
}

// Instance extensions of the loader and its implicit layers, or of `layer`.
bool has_instance_extension(const char* layer, const char* name) {
    std::uint32_t count = 0;
    WEFT_VK_CHECK(vkEnumerateInstanceExtensionProperties(layer, &count, nullptr));
    std::vector<VkExtensionProperties> extensions(count);
    WEFT_VK_CHECK(vkEnumerateInstanceExtensionProperties(layer, &count, extensions.data()));
    return std::any_of(extensions.begin(), extensions.begin() + count,
                       [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

bool has_device_extension(VkPhysicalDevice device, const char* name) {
    std::uint32_t count = 0;
    WEFT_VK_CHECK(vkEnumerateDeviceExtensionProperties(device, nullptr, &count, nullptr));
    std::vector<VkExtensionProperties> extensions(count);
    WEFT_VK_CHECK(vkEnumerateDeviceExtensionProperties(device, nullptr, &count, extensions.data()));
    return std::any_of(extensions.begin(), extensions.begin() + count,
                       [&](const VkExtensionProperties& e) { return std::strcmp(e.extensionName, name) == 0; });
}

// Why `device` cannot share its cloth buffer and a timeline semaphore with CUDA through opaque fds,
// or "" when it can (docs/rendering.md, zero-copy interop).
std::string interop_support(VkPhysicalDevice device, std::uint32_t version) {
    for (const char* ext : {VK_KHR_EXTERNAL_MEMORY_FD_EXTENSION_NAME, VK_KHR_EXTERNAL_SEMAPHORE_FD_EXTENSION_NAME})
        if (!has_device_extension(device, ext)) return std::string("no ") + ext;
    if (version < VK_API_VERSION_1_2 && !has_device_extension(device, VK_KHR_TIMELINE_SEMAPHORE_EXTENSION_NAME))
        return "no timeline semaphores";
    VkPhysicalDeviceTimelineSemaphoreFeatures timeline{};
    timeline.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_TIMELINE_SEMAPHORE_FEATURES;
    VkPhysicalDeviceFeatures2 features{};
    features.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2;
    features.pNext = &timeline;
    vkGetPhysicalDeviceFeatures2(device, &features);
    if (timeline.timelineSemaphore != VK_TRUE) return "no timeline semaphores";
    VkSemaphoreTypeCreateInfo type{};
    type.sType = VK_STRUCTURE_TYPE_SEMAPHORE_TYPE_CREATE_INFO;
    type.semaphoreType = VK_SEMAPHORE_TYPE_TIMELINE;
    VkPhysicalDeviceExternalSemaphoreInfo semaphore{};
    semaphore.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_EXTERNAL_SEMAPHORE_INFO;
    semaphore.pNext = &type;
    semaphore.handleType = VK_EXTERNAL_SEMAPHORE_HANDLE_TYPE_OPAQUE_FD_BIT;
    VkExternalSemaphoreProperties semaphore_props{};
    semaphore_props.sType = VK_STRUCTURE_TYPE_EXTERNAL_SEMAPHORE_PROPERTIES;
    vkGetPhysicalDeviceExternalSemaphoreProperties(device, &semaphore, &semaphore_props);
    if ((semaphore_props.externalSemaphoreFeatures & VK_EXTERNAL_SEMAPHORE_FEATURE_EXPORTABLE_BIT) == 0)
        return "timeline semaphores cannot be exported as opaque fds";
    VkPhysicalDeviceExternalBufferInfo buffer{};
    buffer.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_EXTERNAL_BUFFER_INFO;
    buffer.usage = VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
    buffer.handleType = VK_EXTERNAL_MEMORY_HANDLE_TYPE_OPAQUE_FD_BIT;
    VkExternalBufferProperties buffer_props{};
    buffer_props.sType = VK_STRUCTURE_TYPE_EXTERNAL_BUFFER_PROPERTIES;
    vkGetPhysicalDeviceExternalBufferProperties(device, &buffer, &buffer_props);
    if ((buffer_props.externalMemoryProperties.externalMemoryFeatures & VK_EXTERNAL_MEMORY_FEATURE_EXPORTABLE_BIT) == 0)
        return "vertex buffers cannot be exported as opaque fds";
    return {};
}

// Higher is preferred: a GPU of its own draws fastest, lavapipe (CPU) is the fallback.
int type_rank(VkPhysicalDeviceType type) {
    switch (type) {
        case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 4;
        case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 3;
        case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
        case VK_PHYSICAL_DEVICE_TYPE_CPU: return 1;
        default: return 0;
    }
}

std::string version_string(std::uint32_t v) {
    return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) + "." +
           std::to_string(VK_API_VERSION_PATCH(v));
}

constexpr const char* kNoDevice =
    "vulkan renderer: no Vulkan device (the Vulkan loader found no driver that can render; on Debian, "
    "mesa-vulkan-drivers provides lavapipe, a CPU device)";

}  // namespace

int vulkan_validation_messages_total() { return g_validation_messages.load(); }

VulkanContext::VulkanContext(bool validation, const SurfaceRequest* surface) {
    try {
        create_instance(validation, surface);
        if (surface != nullptr) {
            if (!surface->create_surface) throw Error("vulkan renderer: a surface request without a create function");
            surface_ = surface->create_surface(instance_);
            if (surface_ == VK_NULL_HANDLE) throw Error("vulkan renderer: the window system gave no Vulkan surface");
        }
        choose_physical_device();
        create_device();
    } catch (...) {
        destroy();
        throw;
    }
}

VulkanContext::~VulkanContext() { destroy(); }

void VulkanContext::destroy() noexcept {
    if (device_ != VK_NULL_HANDLE) {
        // Nothing of ours is in flight once the renderer is gone; waiting keeps a half-built
        // renderer's submissions from outliving their objects.
        vkDeviceWaitIdle(device_);
        if (command_pool_ != VK_NULL_HANDLE) vkDestroyCommandPool(device_, command_pool_, nullptr);
        vkDestroyDevice(device_, nullptr);
    }
    if (surface_ != VK_NULL_HANDLE) vkDestroySurfaceKHR(instance_, surface_, nullptr);
    surface_ = VK_NULL_HANDLE;
    if (messenger_ != VK_NULL_HANDLE) {
        const auto destroy_messenger = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(instance_, "vkDestroyDebugUtilsMessengerEXT"));
        if (destroy_messenger != nullptr) destroy_messenger(instance_, messenger_, nullptr);
    }
    if (instance_ != VK_NULL_HANDLE) vkDestroyInstance(instance_, nullptr);
    command_pool_ = VK_NULL_HANDLE;
    device_ = VK_NULL_HANDLE;
    messenger_ = VK_NULL_HANDLE;
    instance_ = VK_NULL_HANDLE;
}

void VulkanContext::create_instance(bool validation, const SurfaceRequest* surface) {
    if (vkEnumerateInstanceVersion(&instance_version_) != VK_SUCCESS || instance_version_ < VK_API_VERSION_1_1)
        throw Error("vulkan renderer: the Vulkan loader is older than Vulkan 1.1 (" +
                    version_string(instance_version_) + ")");
    // 1.3 at most: what this code was written against; the device's own version caps it further.
    instance_version_ = std::min<std::uint32_t>(instance_version_, VK_API_VERSION_1_3);

    std::vector<const char*> layers, extensions;
    VkDebugUtilsMessengerCreateInfoEXT messenger_info{};
    messenger_info.sType = VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT;
    messenger_info.messageSeverity =
        VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
    messenger_info.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT |
                                 VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                                 VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
    messenger_info.pfnUserCallback = on_validation_message;
    messenger_info.pUserData = &messages_;
    if (validation) {
        if (!has_layer(kValidationLayer))
            throw Error(std::string("vulkan renderer: validation was asked for but the layer ") + kValidationLayer +
                        " is not installed (Debian package vulkan-validationlayers)");
        if (!has_instance_extension(nullptr, VK_EXT_DEBUG_UTILS_EXTENSION_NAME) &&
            !has_instance_extension(kValidationLayer, VK_EXT_DEBUG_UTILS_EXTENSION_NAME))
            throw Error(
                "vulkan renderer: validation was asked for but the instance "
                "extension " VK_EXT_DEBUG_UTILS_EXTENSION_NAME " is missing");
        layers.push_back(kValidationLayer);
        extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    }
    if (surface != nullptr) {
        for (const std::string& ext : surface->instance_extensions) {
            if (!has_instance_extension(nullptr, ext.c_str()))
                throw Error("vulkan renderer: the window needs the instance extension " + ext +
                            ", which the Vulkan loader does not offer");
            extensions.push_back(ext.c_str());
        }
    }

    VkApplicationInfo app{};
    app.sType = VK_STRUCTURE_TYPE_APPLICATION_INFO;
    app.pApplicationName = "weft";
    app.pEngineName = "weft";
    app.apiVersion = instance_version_;
    VkInstanceCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO;
    // Chained, the messenger also sees what the layer says during vkCreateInstance and
    // vkDestroyInstance, where the one created below does not exist yet or any more.
    info.pNext = validation ? &messenger_info : nullptr;
    info.pApplicationInfo = &app;
    info.enabledLayerCount = static_cast<std::uint32_t>(layers.size());
    info.ppEnabledLayerNames = layers.data();
    info.enabledExtensionCount = static_cast<std::uint32_t>(extensions.size());
    info.ppEnabledExtensionNames = extensions.data();
    const VkResult created = vkCreateInstance(&info, nullptr, &instance_);
    if (created == VK_ERROR_INCOMPATIBLE_DRIVER) throw Error(kNoDevice);
    vk_check(created, "vkCreateInstance", __FILE__, __LINE__);

    if (validation) {
        const auto create_messenger = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
            vkGetInstanceProcAddr(instance_, "vkCreateDebugUtilsMessengerEXT"));
        if (create_messenger == nullptr)
            throw Error(
                "vulkan renderer: vkCreateDebugUtilsMessengerEXT is missing although " VK_EXT_DEBUG_UTILS_EXTENSION_NAME
                " is enabled");
        WEFT_VK_CHECK(create_messenger(instance_, &messenger_info, nullptr, &messenger_));
    }
}

void VulkanContext::choose_physical_device() {
    std::uint32_t count = 0;
    // The loader lists every installed driver; one without its hardware (an Intel or Radeon driver on
    // a machine without that GPU) gives no device or fails on its own, so a failure here with
    // nothing found reads as "no device" rather than as an error of ours.
    const VkResult listed = vkEnumeratePhysicalDevices(instance_, &count, nullptr);
    if ((listed != VK_SUCCESS && listed != VK_INCOMPLETE) || count == 0) throw Error(kNoDevice);
    std::vector<VkPhysicalDevice> devices(count);
    const VkResult got = vkEnumeratePhysicalDevices(instance_, &count, devices.data());
    vk_check(got == VK_INCOMPLETE ? VK_SUCCESS : got, "vkEnumeratePhysicalDevices", __FILE__, __LINE__);
    devices.resize(count);

    int best_rank = -1;
    std::string rejected;
    for (VkPhysicalDevice device : devices) {
        VkPhysicalDeviceProperties p{};
        vkGetPhysicalDeviceProperties(device, &p);
        if (p.apiVersion < VK_API_VERSION_1_1) {
            rejected +=
                std::string(rejected.empty() ? "" : "; ") + p.deviceName + ": Vulkan " + version_string(p.apiVersion);
            continue;
        }
        std::uint32_t families = 0;
        vkGetPhysicalDeviceQueueFamilyProperties(device, &families, nullptr);
        std::vector<VkQueueFamilyProperties> family(families);
        vkGetPhysicalDeviceQueueFamilyProperties(device, &families, family.data());
        if (surface_ != VK_NULL_HANDLE && !has_device_extension(device, VK_KHR_SWAPCHAIN_EXTENSION_NAME)) {
            rejected += std::string(rejected.empty() ? "" : "; ") + p.deviceName + ": no " +
                        VK_KHR_SWAPCHAIN_EXTENSION_NAME;
            continue;
        }
        // With a window, the one queue both draws and presents.
        std::uint32_t graphics = families;
        for (std::uint32_t f = 0; f < families; ++f) {
            if ((family[f].queueFlags & VK_QUEUE_GRAPHICS_BIT) == 0 || family[f].queueCount == 0) continue;
            if (surface_ != VK_NULL_HANDLE) {
                VkBool32 present = VK_FALSE;
                WEFT_VK_CHECK(vkGetPhysicalDeviceSurfaceSupportKHR(device, f, surface_, &present));
                if (present != VK_TRUE) continue;
            }
            graphics = f;
            break;
        }
        if (graphics == families) {
            rejected += std::string(rejected.empty() ? "" : "; ") + p.deviceName +
                        (surface_ != VK_NULL_HANDLE ? ": no graphics queue that can present to the window"
                                                    : ": no graphics queue");
            continue;
        }
        if (type_rank(p.deviceType) > best_rank) {
            best_rank = type_rank(p.deviceType);
            physical_device_ = device;
            queue_family_ = graphics;
        }
    }
    if (physical_device_ == VK_NULL_HANDLE) throw Error(std::string(kNoDevice) + " (rejected: " + rejected + ")");

    vkGetPhysicalDeviceProperties(physical_device_, &properties_);
    vkGetPhysicalDeviceMemoryProperties(physical_device_, &memory_properties_);
    // Properties2 with the ID (core 1.1) and, where the device has it, the driver's name (core 1.2,
    // VK_KHR_driver_properties before): only structures the device knows may be chained.
    const std::uint32_t version = std::min(instance_version_, properties_.apiVersion);
    VkPhysicalDeviceIDProperties id{};
    id.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_ID_PROPERTIES;
    VkPhysicalDeviceDriverProperties driver{};
    driver.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DRIVER_PROPERTIES;
    const bool has_driver = version >= VK_API_VERSION_1_2 ||
                            has_device_extension(physical_device_, VK_KHR_DRIVER_PROPERTIES_EXTENSION_NAME);
    if (has_driver) id.pNext = &driver;
    VkPhysicalDeviceProperties2 p2{};
    p2.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2;
    p2.pNext = &id;
    vkGetPhysicalDeviceProperties2(physical_device_, &p2);
    std::copy(std::begin(id.deviceUUID), std::end(id.deviceUUID), device_uuid_.begin());

    description_ = std::string(properties_.deviceName) + ", Vulkan " + version_string(properties_.apiVersion);
    if (has_driver) {
        // Appended piecewise: GCC 12 warns (-Wrestrict, a known false positive) on "literal" + string.
        description_.append(", driver ").append(driver.driverName);
        if (driver.driverInfo[0] != '\0') description_.append(" ").append(driver.driverInfo);
    }
}

void VulkanContext::create_device() {
    const float priority = 1.0F;
    VkDeviceQueueCreateInfo queue{};
    queue.sType = VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO;
    queue.queueFamilyIndex = queue_family_;
    queue.queueCount = 1;
    queue.pQueuePriorities = &priority;
    VkDeviceCreateInfo info{};
    info.sType = VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO;
    info.queueCreateInfoCount = 1;
    info.pQueueCreateInfos = &queue;
    // Interop needs fd export of memory and semaphores and timeline semaphores (core in 1.2, an
    // extension before): enabled only when the device can export both, else the renderer uploads.
    std::vector<const char*> extensions;
    VkPhysicalDeviceTimelineSemaphoreFeatures timeline{};
    timeline.sType = VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_TIMELINE_SEMAPHORE_FEATURES;
    interop_reason_ = interop_support(physical_device_, std::min(instance_version_, properties_.apiVersion));
    if (interop_reason_.empty()) {
        extensions = {VK_KHR_EXTERNAL_MEMORY_FD_EXTENSION_NAME, VK_KHR_EXTERNAL_SEMAPHORE_FD_EXTENSION_NAME};
        if (std::min(instance_version_, properties_.apiVersion) < VK_API_VERSION_1_2)
            extensions.push_back(VK_KHR_TIMELINE_SEMAPHORE_EXTENSION_NAME);
        timeline.timelineSemaphore = VK_TRUE;
        info.pNext = &timeline;
    }
    // Points wider than a pixel (the overlay's marks), where the device has them.
    VkPhysicalDeviceFeatures supported{};
    vkGetPhysicalDeviceFeatures(physical_device_, &supported);
    VkPhysicalDeviceFeatures enabled{};
    enabled.largePoints = supported.largePoints;
    large_points_ = supported.largePoints == VK_TRUE;
    info.pEnabledFeatures = &enabled;
    // The window presents through a swapchain (choose_physical_device checked the device has it).
    if (surface_ != VK_NULL_HANDLE) extensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
    if (!extensions.empty()) {
        info.enabledExtensionCount = static_cast<std::uint32_t>(extensions.size());
        info.ppEnabledExtensionNames = extensions.data();
    }
    WEFT_VK_CHECK(vkCreateDevice(physical_device_, &info, nullptr, &device_));
    vkGetDeviceQueue(device_, queue_family_, 0, &queue_);
    if (interop_reason_.empty()) {
        get_memory_fd_ = reinterpret_cast<PFN_vkGetMemoryFdKHR>(vkGetDeviceProcAddr(device_, "vkGetMemoryFdKHR"));
        get_semaphore_fd_ =
            reinterpret_cast<PFN_vkGetSemaphoreFdKHR>(vkGetDeviceProcAddr(device_, "vkGetSemaphoreFdKHR"));
        if (get_memory_fd_ == nullptr || get_semaphore_fd_ == nullptr)
            interop_reason_ = "vkGetMemoryFdKHR or vkGetSemaphoreFdKHR missing although the extensions are enabled";
    }
    interop_ = interop_reason_.empty();

    VkCommandPoolCreateInfo pool{};
    pool.sType = VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO;
    // The frame's command buffer is recorded anew each frame.
    pool.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool.queueFamilyIndex = queue_family_;
    WEFT_VK_CHECK(vkCreateCommandPool(device_, &pool, nullptr, &command_pool_));
}

std::uint32_t VulkanContext::memory_type(std::uint32_t type_bits, VkMemoryPropertyFlags required,
                                         VkMemoryPropertyFlags preferred) const {
    std::uint32_t best = UINT32_MAX;
    int best_score = -1;
    for (std::uint32_t i = 0; i < memory_properties_.memoryTypeCount; ++i) {
        const VkMemoryPropertyFlags flags = memory_properties_.memoryTypes[i].propertyFlags;
        if ((type_bits & (1U << i)) == 0 || (flags & required) != required) continue;
        const int score = std::popcount(flags & preferred);
        if (score > best_score) {
            best_score = score;
            best = i;
        }
    }
    if (best == UINT32_MAX)
        throw Error("vulkan renderer: no memory type with VkMemoryPropertyFlags " + std::to_string(required) +
                    " among memory type bits " + std::to_string(type_bits) + " on " + description_);
    return best;
}

bool VulkanContext::memory_type_has(std::uint32_t index, VkMemoryPropertyFlags flags) const {
    return index < memory_properties_.memoryTypeCount &&
           (memory_properties_.memoryTypes[index].propertyFlags & flags) == flags;
}

void VulkanContext::submit_and_wait(const std::function<void(VkCommandBuffer)>& record) const {
    VkCommandBufferAllocateInfo alloc{};
    alloc.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO;
    alloc.commandPool = command_pool_;
    alloc.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
    alloc.commandBufferCount = 1;
    VkCommandBuffer commands = VK_NULL_HANDLE;
    WEFT_VK_CHECK(vkAllocateCommandBuffers(device_, &alloc, &commands));
    VkFence fence = VK_NULL_HANDLE;
    try {
        VkCommandBufferBeginInfo begin{};
        begin.sType = VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO;
        begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
        WEFT_VK_CHECK(vkBeginCommandBuffer(commands, &begin));
        record(commands);
        WEFT_VK_CHECK(vkEndCommandBuffer(commands));
        VkFenceCreateInfo fence_info{};
        fence_info.sType = VK_STRUCTURE_TYPE_FENCE_CREATE_INFO;
        WEFT_VK_CHECK(vkCreateFence(device_, &fence_info, nullptr, &fence));
        VkSubmitInfo submit{};
        submit.sType = VK_STRUCTURE_TYPE_SUBMIT_INFO;
        submit.commandBufferCount = 1;
        submit.pCommandBuffers = &commands;
        WEFT_VK_CHECK(vkQueueSubmit(queue_, 1, &submit, fence));
        WEFT_VK_CHECK(vkWaitForFences(device_, 1, &fence, VK_TRUE, UINT64_MAX));
    } catch (...) {
        vkQueueWaitIdle(queue_);
        if (fence != VK_NULL_HANDLE) vkDestroyFence(device_, fence, nullptr);
        vkFreeCommandBuffers(device_, command_pool_, 1, &commands);
        throw;
    }
    vkDestroyFence(device_, fence, nullptr);
    vkFreeCommandBuffers(device_, command_pool_, 1, &commands);
}

}  // namespace weft::render::detail
