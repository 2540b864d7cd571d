#pragma once
// VkResult checks: every Vulkan call that can fail goes through WEFT_VK_CHECK, which turns a failure
// into a weft::Error naming the call, the result and where it was made.
#include <vulkan/vulkan.h>

namespace weft::render::detail {

/// The enumerator's name ("VK_ERROR_OUT_OF_DEVICE_MEMORY"); nullptr for results this build does
/// not know (vk_check then prints the number).
[[nodiscard]] const char* vk_result_name(VkResult result);

/// Throws weft::Error("vulkan renderer: <call> failed: <result> (<file>:<line>)") unless `result` is
/// VK_SUCCESS.
void vk_check(VkResult result, const char* call, const char* file, int line);

}  // namespace weft::render::detail

/// Checks the VkResult of `call` (a Vulkan function call expression).
#define WEFT_VK_CHECK(call) ::weft::render::detail::vk_check((call), #call, __FILE__, __LINE__)
