#pragma once
// Private to engine/gpu: the Vulkan headers and the checked-call macro. Nothing outside engine/gpu
// includes this file (the house rule: Vulkan stays in engine/gpu); the public headers expose no Vulkan type.
#include <vulkan/vulkan.h>

#include <string>

namespace nf::gpu::detail {

const char* result_name(VkResult result);
const char* driver_name(VkDriverId id);

// Throws DeviceError naming the call, the VkResult and file:line; device loss gets its own advice.
[[noreturn]] void throw_vk_error(VkResult result, const char* call, const char* file, int line);

inline void check_vk(VkResult result, const char* call, const char* file, int line) {
  if (result != VK_SUCCESS) throw_vk_error(result, call, file, line);
}

}  // namespace nf::gpu::detail

#define NF_VK_CHECK(call) ::nf::gpu::detail::check_vk((call), #call, __FILE__, __LINE__)
