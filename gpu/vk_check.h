#pragma once
// Turns a failed Vulkan call into a RuntimeFailure naming the call.

#include <vulkan/vulkan_core.h>

#include <string>

namespace vox::gpu {

const char* resultName(VkResult r);
[[noreturn]] void throwVulkanFailure(const char* call, VkResult r);

inline void vkCheck(VkResult r, const char* call) {
  if (r != VK_SUCCESS) throwVulkanFailure(call, r);
}

}  // namespace vox::gpu

#define VOX_VK(call) ::vox::gpu::vkCheck((call), #call)
