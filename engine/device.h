#pragma once
// canopy::Device: Canopy's view of one VkDevice, the object every other engine/ function takes.
// It is made by adoptDevice() from the host's instance, device and queue (the public API), or by
// createDevice() (tools/own_device.h) for the demo, tools and tests, which creates its own
// Vulkan objects and then adopts them through the same path.
#include <functional>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/status.h"
#include "engine/vulkan_functions.h"

namespace canopy {

struct Allocator;

// Receives every validation-layer message of severity warning or error (the test helper turns
// them into test failures). messageId is e.g. "SYNC-HAZARD-READ-AFTER-WRITE" or "VUID-...".
using ValidationSink = std::function<void(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                          const char* messageId, const char* message)>;

struct Device {
  VkInstance instance = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;  // graphics + compute + transfer
  uint32_t queueFamily = 0;
  VulkanFunctions vk;              // every entry point, through the host's loader
  const VkAllocationCallbacks* allocationCallbacks = nullptr;
  VkPipelineCache pipelineCache = VK_NULL_HANDLE;
  DeviceMemoryAllocator hostAllocator;  // allocate == null: Canopy's own sub-allocator
  VkPhysicalDeviceProperties properties{};
  VkPhysicalDeviceMemoryProperties memoryProperties{};
  bool validationEnabled = false;
  bool shaderOutputLayer = false;  // gl_Layer from the vertex shader (single-pass layered draw)
  bool shaderClipDistance = false; // gl_ClipDistance (the per-layer-draw fallback)
  bool fragmentPrimitiveId = false; // gl_PrimitiveID in fragment shaders (geometryShader feature)
  bool independentBlend = false;
  bool pipelineStatistics = false; // pipelineStatisticsQuery enabled (Canopy's own device: engine/pass_counters.h)
  // Choose what a GPU gets on any device (tests: the GPU paths on lavapipe): the widest single-workgroup
  // solver kernels, no lane kernels, one composite tile per workgroup (cpuClass()).
  bool forceGpuClass = false;
  uint32_t timestampValidBits = 0;
  // Compute subgroups (Vulkan 1.1 core): the lane-blocked simulation kernels (compute/simulation.cpp)
  // need shuffles and arithmetic reductions in compute shaders.
  uint32_t subgroupSize = 0;
  bool computeSubgroupShuffle = false;
  Allocator* allocator = nullptr;
  VkCommandPool oneShotPool = VK_NULL_HANDLE;  // for submitAndWait()

  // Shorthands of vk.* (sync2 and dynamic rendering may be core 1.3 or KHR on 1.2).
  PFN_vkCmdPipelineBarrier2 cmdPipelineBarrier2 = nullptr;
  PFN_vkCmdPushDescriptorSetKHR cmdPushDescriptorSet = nullptr;
  PFN_vkCmdBeginRendering cmdBeginRendering = nullptr;
  PFN_vkCmdEndRendering cmdEndRendering = nullptr;
  PFN_vkSetDebugUtilsObjectNameEXT setObjectName = nullptr;

  // Frames in flight (docs/design.md, "Embedding contract"): objects replaced or destroyed while
  // host frames may still use them wait here, tagged with the newest host frame number seen, and
  // are released once the host records frame tag + framesInFlight.
  struct PendingRelease {
    uint64_t frame = 0;
    std::function<void()> release;
  };
  uint32_t framesInFlight = 2;
  uint64_t frameNumber = 0;     // the newest host frame number recorded
  bool anyFrame = false;        // a frame was recorded on this device
  std::vector<PendingRelease> pendingReleases;
  // Work prepared outside a frame is recorded into the host's next command buffer instead of being
  // submitted (engine/transfer.h, submitOrDefer: into the list its caller passes).
  bool deferUploads = false;

  // Only for a device made by createDevice(): what it created beside the adopted objects.
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  ValidationSink* sink = nullptr;  // the messenger's user data
};

// The internal form of the public adoptDevice(): fills `out` in place (the tools keep a Device by
// value). Checks the version, extensions and features the host enabled, loads every entry point
// and creates Canopy's command pool and allocator.
Status adoptDeviceInto(const AdoptDeviceDesc& desc, Device* out);
// Destroys what adoptDeviceInto created (and everything still pending release).
void releaseAdoptedDevice(Device& device);

// Runs `release` once no host frame in flight can use what it frees (at once when no frame was
// ever recorded on the device).
void deferRelease(Device& device, std::function<void()> release);
// A host frame with this number is being recorded: frees what its frames in flight no longer use.
// Refuses a number smaller than the newest seen.
Status beginDeviceFrame(Device& device, uint64_t frameNumber);
// Whether Canopy takes its CPU-device defaults on `device` (docs/performance.md): a CPU device not
// forced to the GPU class.
inline bool cpuClass(const Device& device) {
  return device.properties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU && !device.forceGpuClass;
}
// Frees everything pending (the host's frames have completed: destroy, releaseDevice).
void releaseAllPending(Device& device);

// Records with `record` into a fresh command buffer, submits it to the device's queue and waits
// for that submission's own fence (never for the queue or device to be idle).
Status submitAndWait(Device& device, const std::function<Status(VkCommandBuffer)>& record);

// Attaches a debug name (seen in validation messages and captures) when debug utils is present.
void setDebugName(const Device& device, VkObjectType type, uint64_t handle, const char* name);

}  // namespace canopy
