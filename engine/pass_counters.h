#pragma once
// Work counted per pass (issue 56; docs/performance.md "Work per frame, counted"): Vulkan's
// pipeline statistics queries around each pass of a render graph — vertex shader invocations,
// primitives entering clipping, fragment shader invocations, compute shader invocations — and the
// bytes of the images and buffers the pass declares it reads and writes (an estimate from their
// sizes and formats: a pass may touch less of a resource than all of it). Properties of the
// algorithm, not of the driver, so they transfer to any device. Needs the device's
// pipelineStatisticsQuery feature (Device::pipelineStatistics; Canopy's own device enables it when
// the device has it).
#include <cstdint>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/status.h"
#include "engine/vulkan_functions.h"

namespace canopy {
struct Device;

struct PassCounts {
  std::string name;
  uint64_t vertexInvocations = 0, clippingPrimitives = 0, fragmentInvocations = 0, computeInvocations = 0;
  uint64_t bytesRead = 0, bytesWritten = 0;  // the declared accesses' resources, whole (an estimate)
};

class PassCounters {
 public:
  // Room for `maxPasses` passes per frame; refused when the device has no pipeline statistics.
  Status init(Device& device, uint32_t maxPasses = 128);
  void destroy(Device& device);
  // Resets the queries of this frame; call on the command buffer before the first begin().
  void reset(VkCommandBuffer cmd);
  void begin(VkCommandBuffer cmd, const std::string& name, uint64_t bytesRead, uint64_t bytesWritten);
  void end(VkCommandBuffer cmd);
  // After the frame's fence: the counts of the passes recorded since reset().
  Status read(Device& device, std::vector<PassCounts>* out);

 private:
  const VulkanFunctions* vk_ = nullptr;
  VkQueryPool pool_ = VK_NULL_HANDLE;
  uint32_t capacity_ = 0, used_ = 0, open_ = ~0u;
  std::vector<PassCounts> passes_;
};

}  // namespace canopy
