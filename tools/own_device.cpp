#include "tools/own_device.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <cstring>

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

int typeScore(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return 4;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return 3;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return 2;
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return 1;
    default: return 0;
  }
}

uint32_t graphicsComputeFamily(VkPhysicalDevice pd) {
  uint32_t n = 0;
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> fams(n);
  vkGetPhysicalDeviceQueueFamilyProperties(pd, &n, fams.data());
  const VkQueueFlags need = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
  for (uint32_t i = 0; i < n; ++i)
    if ((fams[i].queueFlags & need) == need && fams[i].timestampValidBits > 0) return i;
  for (uint32_t i = 0; i < n; ++i)
    if ((fams[i].queueFlags & need) == need) return i;
  return 0;
}

}  // namespace

// Device selection: explicit name (option or $CANOPY_DEVICE) first, else best type, among those
// that can run Canopy (queryDeviceRequirements).
static Status choosePhysicalDevice(VkInstance instance, uint32_t apiVersion, const DeviceDesc& desc, VkPhysicalDevice* out) {
  uint32_t n = 0;
  CANOPY_VK(vkEnumeratePhysicalDevices(instance, &n, nullptr));
  std::vector<VkPhysicalDevice> pds(n);
  CANOPY_VK(vkEnumeratePhysicalDevices(instance, &n, pds.data()));
  if (n == 0)
    return Status::error(Result::UnsupportedDevice,
                         "no Vulkan device found (on a machine without a GPU install mesa-vulkan-drivers for lavapipe)");
  std::string want = desc.preferredDevice;
  if (want.empty())
    if (const char* env = std::getenv("CANOPY_DEVICE")) want = env;
  want = lower(want);
  int bestScore = -1;
  std::string rejected;
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  for (auto pd : pds) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(pd, &p);
    if (!want.empty() && lower(p.deviceName).find(want) == std::string::npos) {
      rejected += std::string(rejected.empty() ? "" : "; ") + p.deviceName + ": name does not match '" + want + "'";
      continue;
    }
    DeviceRequirements req;
    const Status rs = queryDeviceRequirements(vkGetInstanceProcAddr, instance, apiVersion, pd, &req);
    if (!rs.ok()) {
      rejected += std::string(rejected.empty() ? "" : "; ") + rs.message();
      continue;
    }
    if (typeScore(p.deviceType) > bestScore) {
      bestScore = typeScore(p.deviceType);
      physical = pd;
    }
  }
  if (!physical) return Status::error(Result::UnsupportedDevice, "no suitable Vulkan device (" + rejected + ")");
  *out = physical;
  return Status();
}

Status createDevice(const DeviceDesc& desc, Device* out) {
  *out = Device{};
  Device& d = *out;
  uint32_t loaderVersion = VK_API_VERSION_1_0;
  vkEnumerateInstanceVersion(&loaderVersion);
  if (loaderVersion < VK_API_VERSION_1_2)
    return Status::error(Result::UnsupportedDevice, "the Vulkan loader supports only " +
                                                        std::to_string(VK_API_VERSION_MAJOR(loaderVersion)) + "." +
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
      return Status::error(Result::UnsupportedDevice,
                           std::string(kValidationLayer) + " is not installed (apt-get install vulkan-validationlayers)");
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
  if (validation) mci.pNext = &features;

  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  ici.pNext = validation ? &mci : nullptr;
  ici.pApplicationInfo = &app;
  ici.enabledLayerCount = uint32_t(layers.size());
  ici.ppEnabledLayerNames = layers.data();
  ici.enabledExtensionCount = uint32_t(instExts.size());
  ici.ppEnabledExtensionNames = instExts.data();
  CANOPY_VK(vkCreateInstance(&ici, nullptr, &d.instance));
  if (validation) {
    auto create = (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(d.instance, "vkCreateDebugUtilsMessengerEXT");
    mci.pNext = nullptr;
    if (!create) return Status::error("vkCreateDebugUtilsMessengerEXT is unavailable");
    CANOPY_VK(create(d.instance, &mci, nullptr, &d.messenger));
  }

  VkPhysicalDevice physical = VK_NULL_HANDLE;
  CANOPY_TRY(choosePhysicalDevice(d.instance, app.apiVersion, desc, &physical));
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(physical, &props);
  const bool core13 = props.apiVersion >= VK_API_VERSION_1_3 && app.apiVersion >= VK_API_VERSION_1_3;
  const uint32_t family = graphicsComputeFamily(physical);

  // The features: exactly what a host does (enableDeviceFeatures on its own chain).
  VkPhysicalDeviceDynamicRenderingFeatures dynRender{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES};
  VkPhysicalDeviceSynchronization2Features sync2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES, &dynRender};
  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  f12.pNext = core13 ? static_cast<void*>(&f13) : static_cast<void*>(&sync2);
  VkPhysicalDeviceVulkan11Features f11{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES, &f12};
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f11};
  CANOPY_TRY(enableDeviceFeatures(vkGetInstanceProcAddr, d.instance, physical, core13 ? VK_API_VERSION_1_3 : VK_API_VERSION_1_2, &f2));
  // Canopy's own programs count work per pass when the device can (engine/pass_counters.h); a
  // host's device has what the host enabled.
  VkPhysicalDeviceFeatures supported{};
  vkGetPhysicalDeviceFeatures(physical, &supported);
  if (supported.pipelineStatisticsQuery) f2.features.pipelineStatisticsQuery = VK_TRUE;
  if (desc.disableShaderOutputLayer) {
    f12.shaderOutputLayer = VK_FALSE;
    if (!f2.features.shaderClipDistance)
      return Status::error(Result::UnsupportedDevice, "disableShaderOutputLayer: the device has no shaderClipDistance fallback");
  }

  std::vector<const char*> devExts = desc.deviceExtensions;
  devExts.push_back(VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME);
  if (!core13) devExts.push_back(VK_KHR_SYNCHRONIZATION_2_EXTENSION_NAME);
  if (!core13) devExts.push_back(VK_KHR_DYNAMIC_RENDERING_EXTENSION_NAME);

  float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = family;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &f2};
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  dci.enabledExtensionCount = uint32_t(devExts.size());
  dci.ppEnabledExtensionNames = devExts.data();
  VkDevice device = VK_NULL_HANDLE;
  CANOPY_VK(vkCreateDevice(physical, &dci, nullptr, &device));
  d.device = device;  // destroyDevice() destroys it even if adoption fails
  VkQueue queue = VK_NULL_HANDLE;
  vkGetDeviceQueue(device, family, 0, &queue);

  AdoptDeviceDesc ad;
  ad.getInstanceProcAddr = desc.getInstanceProcAddr ? desc.getInstanceProcAddr : vkGetInstanceProcAddr;
  ad.instance = d.instance;
  ad.instanceApiVersion = app.apiVersion;
  ad.physicalDevice = physical;
  ad.device = device;
  ad.deviceCreateInfo = &dci;
  ad.queue = queue;
  ad.queueFamily = family;
  ad.framesInFlight = desc.framesInFlight;
  // adoptDeviceInto() fills the Device in place; keep what createDevice owns across it.
  const VkInstance instance = d.instance;
  const VkDebugUtilsMessengerEXT messenger = d.messenger;
  ValidationSink* sink = d.sink;
  Status s = adoptDeviceInto(ad, &d);
  d.instance = instance;
  d.device = device;
  d.messenger = messenger;
  d.sink = sink;
  d.validationEnabled = validation;
  d.deferUploads = desc.deferUploads;
  const char* gpuClass = std::getenv("CANOPY_GPU_CLASS");
  d.forceGpuClass = desc.forceGpuClass || (gpuClass && std::string(gpuClass) == "1");
  return s.context("createDevice");
}

void destroyDevice(Device& d) {
  if (d.device) vkDeviceWaitIdle(d.device);  // Canopy's own device: nothing else runs on it
  releaseAdoptedDevice(d);
  if (d.device) vkDestroyDevice(d.device, nullptr);
  if (d.messenger) {
    auto destroy = (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(d.instance, "vkDestroyDebugUtilsMessengerEXT");
    if (destroy) destroy(d.instance, d.messenger, nullptr);
  }
  if (d.instance) vkDestroyInstance(d.instance, nullptr);
  delete d.sink;
  d = Device{};
}

}  // namespace canopy
