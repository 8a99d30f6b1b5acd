#pragma once
// Errors are returned, never thrown across the API and never swallowed (VMA style): a Status is
// empty on success and carries a message naming what failed otherwise.
#include <cstdint>
#include <exception>
#include <functional>
#include <new>
#include <string>
#include <utility>
#include <vulkan/vulkan.h>

// Status, Result and Progress are the public API's (one definition for the library and hosts),
// from the core header the public one includes.
#include <canopy/canopy_core.h>

namespace canopy {

const char* vkResultName(VkResult r);
// "vkCreateDevice failed: VK_ERROR_INITIALIZATION_FAILED", with the Result the VkResult maps to
// (out of host/device memory, device lost, else VulkanError).
Result resultOf(VkResult r);
Status vkError(const char* call, VkResult r);

// The public API's boundary (docs/design.md "Errors and hostile input"): whatever the standard library,
// nlohmann-json or tinygltf throws below a public function comes back as a Status naming the
// function, never as an exception in the host.
template <class F>
Status guardApi(const char* function, F&& body) noexcept {
  try {
    return body();
  } catch (const std::bad_alloc&) {
    return Status::error(Result::OutOfHostMemory, std::string(function) + ": out of host memory");
  } catch (const std::exception& e) {
    return Status::error(Result::InvalidArgument, std::string(function) + ": " + e.what());
  } catch (...) {
    return Status::error(Result::InvalidArgument, std::string(function) + ": unknown exception");
  }
}

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
