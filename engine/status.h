#pragma once
// Errors are returned, never thrown across the API and never swallowed (VMA style): a Status is
// empty on success and carries a message naming what failed otherwise.
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vulkan/vulkan.h>

// Status, Result and Progress are the public API's (one definition for the library and hosts).
#include <canopy/canopy.h>

namespace canopy {

const char* vkResultName(VkResult r);
// "vkCreateDevice failed: VK_ERROR_INITIALIZATION_FAILED", with the Result the VkResult maps to
// (out of host/device memory, device lost, else VulkanError).
Result resultOf(VkResult r);
Status vkError(const char* call, VkResult r);

}  // namespace canopy

// Evaluates a Vulkan call; on failure returns a Status naming the call and the VkResult.
#define CANOPY_VK(call)                                            \
  do {                                                             \
    VkResult canopy_vk_result_ = (call);                           \
    if (canopy_vk_result_ < 0) return ::canopy::vkError(#call, canopy_vk_result_); \
  } while (0)

// Propagates a failed Status.
#define CANOPY_TRY(expr)                       \
  do {                                         \
    ::canopy::Status canopy_status_ = (expr);  \
    if (!canopy_status_.ok()) return canopy_status_; \
  } while (0)
