#include "tests/host_device.h"

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "engine/status.h"

namespace canopy::test {
namespace {

#define HOST_VK(call)                                                                              \
  do {                                                                                             \
    const VkResult r_ = (call);                                                                    \
    if (r_ != VK_SUCCESS) return Status::error(std::string(#call) + ": VkResult " + std::to_string(int(r_))); \
  } while (0)

VKAPI_ATTR VkBool32 VKAPI_CALL onMessage(VkDebugUtilsMessageSeverityFlagBitsEXT severity, VkDebugUtilsMessageTypeFlagsEXT,
                                         const VkDebugUtilsMessengerCallbackDataEXT* data, void* user) {
  const auto* host = static_cast<const HostDevice*>(user);
  if (host->sink)
    host->sink(severity >= VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT, data->pMessageIdName ? data->pMessageIdName : "",
               data->pMessage ? data->pMessage : "");
  return VK_FALSE;
}

Status createInstance(HostDevice& h, uint32_t apiVersion) {
  const char* layer = "VK_LAYER_KHRONOS_validation";
  uint32_t n = 0;
  vkEnumerateInstanceLayerProperties(&n, nullptr);
  std::vector<VkLayerProperties> layers(n);
  vkEnumerateInstanceLayerProperties(&n, layers.data());
  bool found = false;
  for (const VkLayerProperties& l : layers) found |= std::strcmp(l.layerName, layer) == 0;
  if (!found) return Status::error("VK_LAYER_KHRONOS_validation is not installed (apt-get install vulkan-validationlayers)");
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "canopy-tests host device";
  app.apiVersion = apiVersion;
  const VkValidationFeatureEnableEXT sync = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
  VkValidationFeaturesEXT features{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
  features.enabledValidationFeatureCount = 1;
  features.pEnabledValidationFeatures = &sync;
  const char* ext = VK_EXT_DEBUG_UTILS_EXTENSION_NAME;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO, &features};
  ici.pApplicationInfo = &app;
  ici.enabledLayerCount = 1;
  ici.ppEnabledLayerNames = &layer;
  ici.enabledExtensionCount = 1;
  ici.ppEnabledExtensionNames = &ext;
  HOST_VK(vkCreateInstance(&ici, nullptr, &h.instance));
  VkDebugUtilsMessengerCreateInfoEXT mci{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  mci.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
  mci.pfnUserCallback = onMessage;
  mci.pUserData = &h;
  auto create = reinterpret_cast<PFN_vkCreateDebugUtilsMessengerEXT>(
      vkGetInstanceProcAddr(h.instance, "vkCreateDebugUtilsMessengerEXT"));
  if (!create) return Status::error("vkCreateDebugUtilsMessengerEXT is not available");
  HOST_VK(create(h.instance, &mci, nullptr, &h.messenger));
  return Status();
}

}  // namespace

uint32_t hostApiVersion() {
  uint32_t loader = VK_API_VERSION_1_0;
  vkEnumerateInstanceVersion(&loader);
  return loader >= VK_API_VERSION_1_3 ? VK_API_VERSION_1_3 : VK_API_VERSION_1_2;
}

Status CanopyDeviceFeatures::fill(VkInstance instance, VkPhysicalDevice physical, uint32_t api) {
  CANOPY_TRY(queryDeviceRequirements(vkGetInstanceProcAddr, instance, api, physical, &requirements));
  features.pNext = &f11;
  f11.pNext = &f12;
  if (api >= VK_API_VERSION_1_3) {
    f12.pNext = &f13;
  } else {
    f12.pNext = &sync2;
    sync2.pNext = &dynamicRendering;
  }
  // The device runs the lower of the instance's version and the physical device's.
  VkPhysicalDeviceProperties props;
  vkGetPhysicalDeviceProperties(physical, &props);
  CANOPY_TRY(enableDeviceFeatures(vkGetInstanceProcAddr, instance, physical, std::min(api, props.apiVersion), &features));
  extensions.clear();
  for (const std::string& e : requirements.deviceExtensions) extensions.push_back(e.c_str());
  return Status();
}

Status createHostInstance(HostDevice* host, uint32_t apiVersion) { return createInstance(*host, apiVersion); }

Status createHostDevice(uint32_t framesInFlight, HostDevice* out, uint32_t apiVersion) {
  HostDevice& h = *out;
  const uint32_t api = apiVersion ? apiVersion : hostApiVersion();
  CANOPY_TRY(createInstance(h, api));

  // The first physical device Canopy can run on, as an engine would pick among its candidates.
  uint32_t n = 0;
  vkEnumeratePhysicalDevices(h.instance, &n, nullptr);
  std::vector<VkPhysicalDevice> devices(n);
  vkEnumeratePhysicalDevices(h.instance, &n, devices.data());
  std::string why;
  for (VkPhysicalDevice pd : devices) {
    DeviceRequirements r;
    const Status s = queryDeviceRequirements(vkGetInstanceProcAddr, h.instance, api, pd, &r);
    if (!s.ok()) {
      why += s.message() + "; ";
      continue;
    }
    h.physical = pd;
    break;
  }
  if (!h.physical) return Status::error("no physical device can run Canopy: " + why);
  vkGetPhysicalDeviceQueueFamilyProperties(h.physical, &n, nullptr);
  std::vector<VkQueueFamilyProperties> families(n);
  vkGetPhysicalDeviceQueueFamilyProperties(h.physical, &n, families.data());
  const VkQueueFlags want = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
  h.family = n;
  for (uint32_t i = 0; i < n && h.family == n; ++i)
    if ((families[i].queueFlags & want) == want) h.family = i;
  if (h.family == n) return Status::error("no graphics + compute queue family");

  // The host's feature chain for its API version; Canopy switches its features on in it.
  CanopyDeviceFeatures chain;
  CANOPY_TRY(chain.fill(h.instance, h.physical, api));
  const float priority = 1.0f;
  VkDeviceQueueCreateInfo qci{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
  qci.queueFamilyIndex = h.family;
  qci.queueCount = 1;
  qci.pQueuePriorities = &priority;
  VkDeviceCreateInfo dci{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO, &chain.features};
  dci.queueCreateInfoCount = 1;
  dci.pQueueCreateInfos = &qci;
  dci.enabledExtensionCount = uint32_t(chain.extensions.size());
  dci.ppEnabledExtensionNames = chain.extensions.data();
  HOST_VK(vkCreateDevice(h.physical, &dci, nullptr, &h.device));
  vkGetDeviceQueue(h.device, h.family, 0, &h.queue);

  AdoptDeviceDesc ad;
  ad.getInstanceProcAddr = vkGetInstanceProcAddr;
  ad.instance = h.instance;
  ad.instanceApiVersion = api;
  ad.physicalDevice = h.physical;
  ad.device = h.device;
  ad.deviceCreateInfo = &dci;
  ad.queue = h.queue;
  ad.queueFamily = h.family;
  ad.framesInFlight = framesInFlight;
  ad.debugName = "test host device";
  return adoptDevice(ad, &h.adopted);
}

void destroyHostDevice(HostDevice& h) {
  if (h.device) vkDeviceWaitIdle(h.device);  // the host's own shutdown
  releaseDevice(h.adopted);
  h.adopted = nullptr;
  if (h.device) vkDestroyDevice(h.device, nullptr);
  if (h.messenger) {
    auto destroy = reinterpret_cast<PFN_vkDestroyDebugUtilsMessengerEXT>(
        vkGetInstanceProcAddr(h.instance, "vkDestroyDebugUtilsMessengerEXT"));
    if (destroy) destroy(h.instance, h.messenger, nullptr);
  }
  if (h.instance) vkDestroyInstance(h.instance, nullptr);
  h = HostDevice{std::move(h.sink)};
}

}  // namespace canopy::test
