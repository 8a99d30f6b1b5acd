#pragma once
// A device made the way an engine makes its own, not through Canopy's createDevice: the test's own
// instance (validation + synchronization validation, every message to `sink`), its own choice of
// physical device and queue family, Canopy's requirements asked for and enabled through the
// public API (queryDeviceRequirements, enableDeviceFeatures), then adopted (adoptDevice).
#include <functional>
#include <string>
#include <vector>

#include <canopy/canopy.h>

namespace canopy::test {

struct HostDevice {
  std::function<void(bool error, const char* id, const char* message)> sink;  // set before creation
  VkInstance instance = VK_NULL_HANDLE;
  VkDebugUtilsMessengerEXT messenger = VK_NULL_HANDLE;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  uint32_t family = 0;
  Device* adopted = nullptr;  // Canopy's view of it
};

// What a device created for Canopy at instance version `api` enables: the feature chain (head
// `features`) with Canopy's features switched on (enableDeviceFeatures) and the extensions its
// requirements name (queryDeviceRequirements). Links to itself: not copyable.
struct CanopyDeviceFeatures {
  VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
  VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  VkPhysicalDeviceSynchronization2Features sync2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES};
  VkPhysicalDeviceDynamicRenderingFeatures dynamicRendering{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES};
  DeviceRequirements requirements;
  std::vector<const char*> extensions;  // into requirements.deviceExtensions
  CanopyDeviceFeatures() = default;
  CanopyDeviceFeatures(const CanopyDeviceFeatures&) = delete;
  CanopyDeviceFeatures& operator=(const CanopyDeviceFeatures&) = delete;
  Status fill(VkInstance instance, VkPhysicalDevice physical, uint32_t api);
};
// The instance version a test host asks for: 1.3 when the loader has it, else 1.2.
uint32_t hostApiVersion();

// Creates instance and device and adopts the device with `framesInFlight`; the instance at
// `apiVersion` (0: hostApiVersion()). A missing validation layer is an error, never a skip.
Status createHostDevice(uint32_t framesInFlight, HostDevice* host, uint32_t apiVersion = 0);
// Only the instance (validation + synchronization validation, messages to host->sink) at `apiVersion`.
Status createHostInstance(HostDevice* host, uint32_t apiVersion);
// Releases Canopy's view, waits for the device, destroys device and instance.
void destroyHostDevice(HostDevice& host);

}  // namespace canopy::test
