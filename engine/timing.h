#pragma once
// GPU timestamp queries around named passes, read back as milliseconds.
// On CPU drivers (lavapipe) timestamps around non-draw work read near zero once anything was
// drawn (docs/design.md): callers that publish figures cross-check against wall clock.
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/status.h"

#include "engine/vulkan_functions.h"

namespace canopy {
struct Device;

struct PassTiming {
  std::string name;
  double milliseconds = 0.0;
};

class GpuTimer {
 public:
  // Room for `maxPasses` begin/end pairs per frame.
  Status init(Device& device, uint32_t maxPasses = 64);
  void destroy(Device& device);
  // Resets the queries of this frame; call on the command buffer before the first begin().
  void reset(VkCommandBuffer cmd);
  void begin(VkCommandBuffer cmd, const std::string& name);
  void end(VkCommandBuffer cmd);
  // After the frame's fence: the timings of the passes recorded since reset().
  Status read(Device& device, std::vector<PassTiming>* out);

 private:
  const VulkanFunctions* vk_ = nullptr;
  VkQueryPool pool_ = VK_NULL_HANDLE;
  uint32_t capacity_ = 0;
  uint32_t used_ = 0;
  uint32_t open_ = ~0u;
  double periodNs_ = 1.0;
  uint64_t mask_ = ~0ull;
  std::vector<std::string> names_;
};

// Median of a sample (copies; empty -> 0).
double median(std::vector<double> v);

}  // namespace canopy
