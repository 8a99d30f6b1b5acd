#pragma once
// Vulkan instance + device + queue: the one object every other engine/ function takes.
#include <functional>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/status.h"

namespace canopy {

struct Allocator;

// Receives every validation-layer message of severity warning or error (the test helper turns
// them into test failures). messageId is e.g. "SYNC-HAZARD-READ-AFTER-WRITE" or "VUID-...".
using ValidationSink = std::function<void(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                          const char* messageId, const char* message)>;

struct DeviceDesc {
  const char* applicationName = "canopy";
  // Enable VK_LAYER_KHRONOS_validation. With requireValidation a missing layer is an error
  // (tests); otherwise it is skipped with a note in DeviceInfo.
  bool enableValidation = false;
  bool requireValidation = false;
  // Also enable synchronization validation (hazard detection between unsynchronized accesses).
  bool enableSyncValidation = true;
  ValidationSink validationSink;  // required when enableValidation
  // Substring (case-insensitive) of the device name to pick; empty = $CANOPY_DEVICE if set, else
  // prefer discrete > integrated > virtual > CPU (lavapipe).
  std::string preferredDevice;
  // Instance extensions the host needs in addition (e.g. from glfwGetRequiredInstanceExtensions).
  std::vector<const char*> instanceExtensions;
  std::vector<const char*> deviceExtensions;
  // Behave as a device without shaderOutputLayer (tests and benchmarks of the per-layer fallback).
  bool disableShaderOutputLayer = false;
};

struct Device {
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;  // graphics + compute + transfer
  uint32_t queueFamily = 0;
  VkPhysicalDeviceProperties properties{};
  VkPhysicalDeviceMemoryProperties memoryProperties{};
  bool validationEnabled = false;
  bool shaderOutputLayer = false;  // gl_Layer from the vertex shader (single-pass layered draw)
  bool shaderClipDistance = false; // gl_ClipDistance (the per-layer-draw fallback)
  bool fragmentPrimitiveId = false; // gl_PrimitiveID in fragment shaders (geometryShader feature)
  bool independentBlend = false;
  uint32_t timestampValidBits = 0;
  Allocator* allocator = nullptr;
  VkCommandPool oneShotPool = VK_NULL_HANDLE;  // for submitAndWait()

  // Entry points resolved at creation (sync2 may be core 1.3 or the KHR extension on 1.2).
  PFN_vkCmdPipelineBarrier2 cmdPipelineBarrier2 = nullptr;
  PFN_vkCmdPushDescriptorSetKHR cmdPushDescriptorSet = nullptr;
  PFN_vkCmdBeginRendering cmdBeginRendering = nullptr;  // dynamic rendering (core 1.3 or KHR on 1.2)
  PFN_vkCmdEndRendering cmdEndRendering = nullptr;
  PFN_vkSetDebugUtilsObjectNameEXT setObjectName = nullptr;

  ValidationSink* sink = nullptr;  // owned; the messenger's user data
};

// Creates instance, picks the physical device, creates the logical device with one queue.
// Requires Vulkan 1.2, synchronization2, dynamic rendering, push descriptors, scalar block layout,
// timestamps.
Status createDevice(const DeviceDesc& desc, Device* out);
void destroyDevice(Device& device);

// Records with `record` into a fresh command buffer, submits it and waits for completion.
Status submitAndWait(Device& device, const std::function<Status(VkCommandBuffer)>& record);

// Attaches a debug name (seen in validation messages and captures) when debug utils is present.
void setDebugName(const Device& device, VkObjectType type, uint64_t handle, const char* name);

}  // namespace canopy
