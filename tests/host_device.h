#pragma once
// A device made the way an engine makes its own, not through Canopy's createDevice: the test's own
// instance (validation + synchronization validation, every message to `sink`), its own choice of
// physical device and queue family, Canopy's requirements asked for and enabled through the
// public API (queryDeviceRequirements, enableDeviceFeatures), then adopted (adoptDevice).
#include <functional>

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

// Creates instance and device and adopts the device with `framesInFlight`. A missing validation
// layer is an error, never a skip.
Status createHostDevice(uint32_t framesInFlight, HostDevice* host);
// Releases Canopy's view, waits for the device, destroys device and instance.
void destroyHostDevice(HostDevice& host);

}  // namespace canopy::test
