#pragma once
// Canopy's own Vulkan instance + device + queue, for the demo, the tools, the benchmark and the
// tests (a host engine adopts its own device instead: adoptDevice() in <canopy/canopy.h>). It
// creates the objects through the system loader and then adopts them through the same path a
// host uses, so both are one code path past creation.
#include <string>
#include <vector>

#include "engine/device.h"

namespace canopy {

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
  // Take the GPU-class defaults on any device (Device::forceGpuClass); also set by the environment
  // variable CANOPY_GPU_CLASS=1 (the tests' GPU paths on lavapipe, ctest CorrectnessSubsetGpuClass).
  bool forceGpuClass = false;
  uint32_t framesInFlight = 2;
  // Record uploads into the next recordCanopy() command buffer as on a host's device (adoptDevice),
  // instead of submitting them at once (Canopy's own tools, the render-graph path).
  bool deferUploads = false;
  // The loader Canopy's entry points come from (null: the system loader's vkGetInstanceProcAddr);
  // e.g. tools/fault_loader.h for fault injection.
  PFN_vkGetInstanceProcAddr getInstanceProcAddr = nullptr;
};

// Creates instance, picks the physical device, creates the logical device with one queue and the
// features Canopy needs (enableDeviceFeatures), then adoptDeviceInto().
Status createDevice(const DeviceDesc& desc, Device* out);
// Waits for the device to be idle (it is Canopy's own), releases and destroys everything.
void destroyDevice(Device& device);

}  // namespace canopy
