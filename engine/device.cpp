#include "engine/device.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>

#include "engine/memory.h"

namespace canopy {
namespace {

const char* kValidationLayer = "VK_LAYER_KHRONOS_validation";

VKAPI_ATTR VkBool32 VKAPI_CALL debugCallback(VkDebugUtilsMessageSeverityFlagBitsEXT severity,
                                             VkDebugUtilsMessageTypeFlagsEXT,
                                             const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  auto* sink = static_cast<ValidationSink*>(user);
  if (sink && *sink) (*sink)(severity, data->pMessageIdName ? data->pMessageIdName : "", data->pMessage ? data->pMessage : "");
  return VK_FALSE;
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

bool hasLayer(const char* name) {
  uint32_t n = 0;
  vkEnumerateInstanceLayerProperties(&n, nullptr);
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  for (auto& l : layers)
    if (std::strcmp(l.layerName, name) == 0) return true;
  return false;
}

bool hasDeviceExtension(VkPhysicalDevice pd, const char* name) {
  uint32_t n = 0;
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, nullptr);
  std::vector<VkExtensionProperties> exts(n);
  vkEnumerateDeviceExtensionProperties(pd, nullptr, &n, exts.data());
  for (auto& e : exts)
    if (std::strcmp(e.extensionName, name) == 0) return true;
  return false;
}

int typeScore(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 4;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 3;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 1;
    default: return 0;
  }
}

// Why a device cannot run Canopy, or "" when it can.
std::string unsuitableReason(VkPhysicalDevice pd, uint32_t* family) {
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(pd, &props);
  if (props.apiVersion < VK_API_VERSION_1_2) return "Vulkan 1.2 is required";
  if (!hasDeviceExtension(pd, VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME)) return "VK_KHR_push_descriptor is missing";
  if (props.apiVersion < VK_API_VERSION_1_3 && !hasDeviceExtension(pd, VK_KHR_SYNCHRONIZATION_2_EXTENSION_NAME))
    return "synchronization2 is missing";
  if (props.apiVersion < VK_API_VERSION_1_3 && !hasDeviceExtension(pd, VK_KHR_DYNAMIC_RENDERING_EXTENSION_NAME))
    return "dynamic rendering is missing";
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceSynchronization2Features fs2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES};
  VkPhysicalDeviceDynamicRenderingFeatures fdr{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES};
  fs2.pNext = &fdr;
  f12.pNext = &fs2;
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
  vkGetPhysicalDeviceFeatures2(pd, &f2);
  if (!f12.scalarBlockLayout) return "scalarBlockLayout is not supported";
  if (!fs2.synchronization2) return "synchronization2 feature is not supported";
  if (!fdr.dynamicRendering) return "dynamicRendering feature is not supported";
  if (!f12.hostQueryReset) return "hostQueryReset is not supported";
  if (!props.limits.timestampComputeAndGraphics) return "timestamps on compute/graphics queues are not supported";
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> fams(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, fams.data());
  for (uint32_t i = 0; i < n; ++i) {
    const VkQueueFlags need = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
    if ((fams[i].queueFlags & need) == need && fams[i].timestampValidBits > 0) {
      *family = i;
      return "";
    }
  }
  return "no queue family with graphics + compute + timestamps";
}

}  // namespace

Status createDevice(const DeviceDesc& desc, Device* out) {
  *out = Device{};
  Device& d = *out;
  uint32_t loaderVersion = VK_API_VERSION_1_0;
  vkEnumerateInstanceVersion(&loaderVersion);
  if (loaderVersion < VK_API_VERSION_1_2)
    return Status::error("the Vulkan loader supports only " + std::to_string(VK_API_VERSION_MAJOR(loaderVersion)) + "." +
                         std::to_string(VK_API_VERSION_MINOR(loaderVersion)) + "; Canopy needs 1.2");

  std::vector<const char*> layers;
  std::vector<const char*> instExts = desc.instanceExtensions;
  bool validation = false;
  if (desc.enableValidation) {
    if (hasLayer(kValidationLayer)) {
      validation = true;
      layers.push_back(kValidationLayer);
      instExts.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
    } else if (desc.requireValidation) {
      return Status::error(std::string(kValidationLayer) +
                           " is not installed (apt-get install vulkan-validationlayers)");
    }
    if (validation && !desc.validationSink) return Status::error("DeviceDesc.validationSink is required with validation");
  }
  d.sink = new ValidationSink(desc.validationSink);

  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = desc.applicationName;
  app.pEngineName = "canopy";
  app.apiVersion = loaderVersion >= VK_API_VERSION_1_3 ? VK_API_VERSION_1_3 : VK_API_VERSION_1_2;

  VkValidationFeatureEnableEXT enables[] = {VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT};
  VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
  features.enabledValidationFeatureCount = desc.enableSyncValidation ? 1 : 0;
  features.pEnabledValidationFeatures = enables;

  VkDebugUtilsMessengerCreateInfoEXT mci{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  mci.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT |
                    VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT;
  mci.pfnUserCallback = debugCallback;
  mci.pUserData = d.sink;
  if (validation) {
    mci.pNext = &features;
  }

  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pNext = validation ? &mci : nullptr;
  ici.pApplicationInfo = &app;
  ici.enabledLayerCount = uint32_t(layers.size());
  ici.ppEnabledLayerNames = layers.data();
  ici.enabledExtensionCount = uint32_t(instExts.size());
  ici.ppEnabledExtensionNames = instExts.data();
  CANOPY_VK(vkCreateInstance(&ici, nullptr, &d.instance));
  d.validationEnabled = validation;
  if (validation) {
    auto create = (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(d.instance, "vkCreateDebugUtilsMessengerEXT");
    mci.pNext = nullptr;
    if (!create) return Status::error("vkCreateDebugUtilsMessengerEXT is unavailable");
    CANOPY_VK(create(d.instance, &mci, nullptr, &d.messenger));
    d.setObjectName = (PFN_vkSetDebugUtilsObjectNameEXT)vkGetInstanceProcAddr(d.instance, "vkSetDebugUtilsObjectNameEXT");
  }

  // Device selection: explicit name (option or $CANOPY_DEVICE) first, else best type.
  uint32_t n = 0;
  CANOPY_VK(vkEnumeratePhysicalDevices(d.instance, &n, nullptr));
  std::vector<VkPhysicalDevice> pds(n);
  CANOPY_VK(vkEnumeratePhysicalDevices(d.instance, &n, pds.data()));
  if (n == 0) return Status::error("no Vulkan device found (on a machine without a GPU install mesa-vulkan-drivers for lavapipe)");
  std::string want = desc.preferredDevice;
  if (want.empty())
    if (const char* env = std::getenv("CANOPY_DEVICE")) want = env;
  want = lower(want);
  int bestScore = -1;
  std::string rejected;
  for (auto pd : pds) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(pd, &p);
    uint32_t family = 0;
    std::string why = unsuitableReason(pd, &family);
    bool nameOk = want.empty() || lower(p.deviceName).find(want) != std::string::npos;
    if (!nameOk) {
      rejected += std::string(rejected.empty() ? "" : "; ") + p.deviceName + ": name does not match '" + want + "'";
      continue;
    }
    if (!why.empty()) {
      rejected += std::string(rejected.empty() ? "" : "; ") + p.deviceName + ": " + why;
      continue;
    }
    int score = typeScore(p.deviceType);
    if (score > bestScore) {
      bestScore = score;
      d.physical = pd;
      d.queueFamily = family;
    }
  }
  if (!d.physical) return Status::error("no suitable Vulkan device (" + rejected + ")");
  vkGetPhysicalDeviceProperties(d.physical, &d.properties);
  vkGetPhysicalDeviceMemoryProperties(d.physical, &d.memoryProperties);
  {
    uint32_t qn = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(d.physical, &qn, nullptr);
    std::vector<VkQueueFamilyProperties> fams(qn);
    vkGetPhysicalDeviceQueueFamilyProperties(d.physical, &qn, fams.data());
    d.timestampValidBits = fams[d.queueFamily].timestampValidBits;
  }
  const bool core13 = d.properties.apiVersion >= VK_API_VERSION_1_3 && app.apiVersion >= VK_API_VERSION_1_3;

  VkPhysicalDeviceVulkan11Features have11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES};
  VkPhysicalDeviceFeatures2 have{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &have11};
  vkGetPhysicalDeviceFeatures2(d.physical, &have);
  VkPhysicalDeviceVulkan12Features have12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceFeatures2 have2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &have12};
  vkGetPhysicalDeviceFeatures2(d.physical, &have2);
  d.shaderOutputLayer = have12.shaderOutputLayer && !desc.disableShaderOutputLayer;

  // Layers and the background are drawn with dynamic rendering (core 1.3, KHR extension on 1.2).
  VkPhysicalDeviceDynamicRenderingFeatures dynRender{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES};
  dynRender.dynamicRendering = VK_TRUE;
  VkPhysicalDeviceSynchronization2Features sync2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES, &dynRender};
  sync2.synchronization2 = VK_TRUE;
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES, &sync2};
  f12.scalarBlockLayout = VK_TRUE;
  f12.hostQueryReset = VK_TRUE;
  f12.shaderOutputLayer = d.shaderOutputLayer;
  f12.shaderFloat16 = have12.shaderFloat16;
  f12.storageBuffer8BitAccess = have12.storageBuffer8BitAccess;
  VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES, &f12};
  f11.storageBuffer16BitAccess = have11.storageBuffer16BitAccess;
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f11};
  f2.features.fragmentStoresAndAtomics = have.features.fragmentStoresAndAtomics;
  f2.features.shaderInt16 = have.features.shaderInt16;
  f2.features.samplerAnisotropy = have.features.samplerAnisotropy;
  // The per-layer fallback clips leaves with gl_ClipDistance (near/far planes on the leaf root).
  f2.features.shaderClipDistance = have.features.shaderClipDistance;
  d.shaderClipDistance = have.features.shaderClipDistance;
  // gl_PrimitiveID in a fragment shader needs the Geometry capability (the layer-id debug output).
  f2.features.geometryShader = have.features.geometryShader;
  d.fragmentPrimitiveId = have.features.geometryShader;
  // The layer-id debug output is an integer attachment beside a blended colour attachment.
  f2.features.independentBlend = have.features.independentBlend;
  d.independentBlend = have.features.independentBlend;

  std::vector<const char*> devExts = desc.deviceExtensions;
  devExts.push_back(VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME);
  if (!core13) devExts.push_back(VK_KHR_SYNCHRONIZATION_2_EXTENSION_NAME);
  if (!core13) devExts.push_back(VK_KHR_DYNAMIC_RENDERING_EXTENSION_NAME);

  float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = d.queueFamily;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &f2};
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  dci.enabledExtensionCount = uint32_t(devExts.size());
  dci.ppEnabledExtensionNames = devExts.data();
  CANOPY_VK(vkCreateDevice(d.physical, &dci, nullptr, &d.device));
  vkGetDeviceQueue(d.device, d.queueFamily, 0, &d.queue);

  d.cmdPipelineBarrier2 = (PFN_vkCmdPipelineBarrier2)vkGetDeviceProcAddr(
      d.device, core13 ? "vkCmdPipelineBarrier2" : "vkCmdPipelineBarrier2KHR");
  d.cmdPushDescriptorSet = (PFN_vkCmdPushDescriptorSetKHR)vkGetDeviceProcAddr(d.device, "vkCmdPushDescriptorSetKHR");
  d.cmdBeginRendering = (PFN_vkCmdBeginRendering)vkGetDeviceProcAddr(
      d.device, core13 ? "vkCmdBeginRendering" : "vkCmdBeginRenderingKHR");
  d.cmdEndRendering = (PFN_vkCmdEndRendering)vkGetDeviceProcAddr(
      d.device, core13 ? "vkCmdEndRendering" : "vkCmdEndRenderingKHR");
  if (!d.cmdPipelineBarrier2 || !d.cmdPushDescriptorSet || !d.cmdBeginRendering || !d.cmdEndRendering)
    return Status::error("device did not return vkCmdPipelineBarrier2 / vkCmdPushDescriptorSetKHR / vkCmdBeginRendering");

  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT | VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = d.queueFamily;
  CANOPY_VK(vkCreateCommandPool(d.device, &pci, nullptr, &d.oneShotPool));

  d.allocator = new Allocator();
  CANOPY_TRY(initAllocator(d, d.allocator));
  return Status();
}

void destroyDevice(Device& d) {
  if (d.device) vkDeviceWaitIdle(d.device);
  if (d.allocator) {
    destroyAllocator(d, *d.allocator);
    delete d.allocator;
  }
  if (d.oneShotPool) vkDestroyCommandPool(d.device, d.oneShotPool, nullptr);
  if (d.device) vkDestroyDevice(d.device, nullptr);
  if (d.messenger) {
    auto destroy = (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(d.instance, "vkDestroyDebugUtilsMessengerEXT");
    if (destroy) destroy(d.instance, d.messenger, nullptr);
  }
  if (d.instance) vkDestroyInstance(d.instance, nullptr);
  delete d.sink;
  d = Device{};
}

Status submitAndWait(Device& d, const std::function<Status(VkCommandBuffer)>& record) {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = d.oneShotPool;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd;
  CANOPY_VK(vkAllocateCommandBuffers(d.device, &ai, &cmd));
  VkFence fence = VK_NULL_HANDLE;
  auto cleanup = [&] {
    if (fence) vkDestroyFence(d.device, fence, nullptr);
    vkFreeCommandBuffers(d.device, d.oneShotPool, 1, &cmd);
  };
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  Status s = [&]() -> Status {
    CANOPY_VK(vkBeginCommandBuffer(cmd, &bi));
    CANOPY_TRY(record(cmd));
    CANOPY_VK(vkEndCommandBuffer(cmd));
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    CANOPY_VK(vkCreateFence(d.device, &fci, nullptr, &fence));
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd;
    CANOPY_VK(vkQueueSubmit(d.queue, 1, &si, fence));
    CANOPY_VK(vkWaitForFences(d.device, 1, &fence, VK_TRUE, UINT64_MAX));
    return Status();
  }();
  if (!s.ok() && fence == VK_NULL_HANDLE) {
    // Recording failed: nothing was submitted, safe to free.
  } else if (!s.ok()) {
    vkQueueWaitIdle(d.queue);
  }
  cleanup();
  return s;
}

void setDebugName(const Device& d, VkObjectType type, uint64_t handle, const char* name) {
  if (!d.setObjectName || !name) return;
  VkDebugUtilsObjectNameInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_OBJECT_NAME_INFO_EXT};
  info.objectType = type;
  info.objectHandle = handle;
  info.pObjectName = name;
  d.setObjectName(d.device, &info);
}

}  // namespace canopy
