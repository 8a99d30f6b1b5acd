#pragma once
// Errors are returned, never thrown across the API and never swallowed (VMA style): a Status is
// empty on success and carries a message naming what failed otherwise.
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vulkan/vulkan.h>

namespace canopy {

class [[nodiscard]] Status {
 public:
  Status() = default;
  static Status error(std::string message) { Status s; s.message_ = std::move(message); s.failed_ = true; return s; }
  bool ok() const { return !failed_; }
  explicit operator bool() const { return ok(); }
  const std::string& message() const { return message_; }
  // Prefixes context ("while creating X: ") so the message reads outermost first.
  Status context(const std::string& what) const { return ok() ? *this : error(what + ": " + message_); }

 private:
  std::string message_;
  bool failed_ = false;
};

// Progress of long work (scene generation, leaf roots, mesh upload): (stage, done, total), called
// on the calling thread now and then (about every million items), last with done == total.
using Progress = std::function<void(const char* stage, uint64_t done, uint64_t total)>;

const char* vkResultName(VkResult r);
// "vkCreateDevice failed: VK_ERROR_INITIALIZATION_FAILED"
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
