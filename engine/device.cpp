#include "engine/device.h"

#include <algorithm>
#include <cstring>

#include "engine/memory.h"

namespace canopy {
namespace {

// What Canopy needs (docs/design.md, "Embedding contract"): Vulkan 1.2, push descriptors,
// synchronization2 and dynamic rendering (core in 1.3), scalar block layout; and one way to put a
// triangle in a layer: gl_Layer from the vertex shader (single pass) or gl_ClipDistance (one draw
// per layer).
struct FeatureView {
  VkPhysicalDeviceFeatures core{};
  bool scalarBlockLayout = false, shaderOutputLayer = false;
  bool synchronization2 = false, dynamicRendering = false;
  bool has11 = false, has12 = false, has13 = false, hasSync2 = false, hasDynRender = false;
};

// Reads the booleans out of a feature chain (VkPhysicalDeviceFeatures2 and what hangs from it).
FeatureView readChain(const void* chain, const VkPhysicalDeviceFeatures* plain) {
  FeatureView v;
  if (plain) v.core = *plain;
  for (auto* s = static_cast<const VkBaseInStructure*>(chain); s; s = s->pNext) {
    switch (s->sType) {
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2:
        v.core = reinterpret_cast<const VkPhysicalDeviceFeatures2*>(s)->features;
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_1_FEATURES: v.has11 = true; break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES: {
        auto* f = reinterpret_cast<const VkPhysicalDeviceVulkan12Features*>(s);
        v.has12 = true;
        v.scalarBlockLayout |= f->scalarBlockLayout == VK_TRUE;
        v.shaderOutputLayer |= f->shaderOutputLayer == VK_TRUE;
        break;
      }
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES: {
        auto* f = reinterpret_cast<const VkPhysicalDeviceVulkan13Features*>(s);
        v.has13 = true;
        v.synchronization2 |= f->synchronization2 == VK_TRUE;
        v.dynamicRendering |= f->dynamicRendering == VK_TRUE;
        break;
      }
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SCALAR_BLOCK_LAYOUT_FEATURES:
        v.scalarBlockLayout |= reinterpret_cast<const VkPhysicalDeviceScalarBlockLayoutFeatures*>(s)->scalarBlockLayout == VK_TRUE;
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES:
        v.hasSync2 = true;
        v.synchronization2 |= reinterpret_cast<const VkPhysicalDeviceSynchronization2Features*>(s)->synchronization2 == VK_TRUE;
        break;
      case VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES:
        v.hasDynRender = true;
        v.dynamicRendering |= reinterpret_cast<const VkPhysicalDeviceDynamicRenderingFeatures*>(s)->dynamicRendering == VK_TRUE;
        break;
      default: break;
    }
  }
  return v;
}

// What the physical device supports.
FeatureView supported(const VulkanFunctions& vk, VkPhysicalDevice pd, uint32_t apiVersion) {
  VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
  VkPhysicalDeviceSynchronization2Features fs2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES};
  VkPhysicalDeviceDynamicRenderingFeatures fdr{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES};
  VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
  VkPhysicalDeviceFeatures2 f2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2, &f12};
  if (apiVersion >= VK_API_VERSION_1_3) {
    f12.pNext = &f13;
  } else {
    f12.pNext = &fs2;
    fs2.pNext = &fdr;
  }
  vk.GetPhysicalDeviceFeatures2(pd, &f2);
  return readChain(&f2, nullptr);
}

std::vector<std::string> deviceExtensions(const VulkanFunctions& vk, VkPhysicalDevice pd) {
  uint32_t n = 0;
  vk.EnumerateDeviceExtensionProperties(pd, nullptr, &n, nullptr);
  std::vector<VkExtensionProperties> exts(n);
  vk.EnumerateDeviceExtensionProperties(pd, nullptr, &n, exts.data());
  std::vector<std::string> names;
  for (auto& e : exts) names.push_back(e.extensionName);
  return names;
}

bool contains(const std::vector<std::string>& v, const std::string& s) { return std::find(v.begin(), v.end(), s) != v.end(); }

std::string versionName(uint32_t v) { return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)); }

// The requirements of one physical device (`props`, read with a 1.0 entry point) for an instance of
// `instanceApi`; `core13` when both run 1.3. Returns what is missing, "" when the device can run
// Canopy. Entry points beyond 1.0 are called only when both run 1.2.
std::string fillRequirements(const VulkanFunctions& vk, VkPhysicalDevice pd, const VkPhysicalDeviceProperties& props,
                             uint32_t instanceApi, DeviceRequirements* r, bool* core13Out) {
  *r = DeviceRequirements{};
  const bool core13 = props.apiVersion >= VK_API_VERSION_1_3 && instanceApi >= VK_API_VERSION_1_3;
  if (core13Out) *core13Out = core13;
  r->optionalInstanceExtensions = {{VK_EXT_DEBUG_UTILS_EXTENSION_NAME, "names Canopy's Vulkan objects for debuggers and validation messages"}};
  r->deviceExtensions = {VK_KHR_PUSH_DESCRIPTOR_EXTENSION_NAME};
  if (!core13) {
    r->deviceExtensions.push_back(VK_KHR_SYNCHRONIZATION_2_EXTENSION_NAME);
    r->deviceExtensions.push_back(VK_KHR_DYNAMIC_RENDERING_EXTENSION_NAME);
  }
  r->features = {"VkPhysicalDeviceVulkan12Features.scalarBlockLayout",
                 core13 ? "VkPhysicalDeviceVulkan13Features.synchronization2"
                        : "VkPhysicalDeviceSynchronization2Features.synchronization2",
                 core13 ? "VkPhysicalDeviceVulkan13Features.dynamicRendering"
                        : "VkPhysicalDeviceDynamicRenderingFeatures.dynamicRendering"};
  r->featuresAnyOf = {{"VkPhysicalDeviceVulkan12Features.shaderOutputLayer", "VkPhysicalDeviceFeatures.shaderClipDistance"}};
  r->optionalFeatures = {{"VkPhysicalDeviceVulkan12Features.shaderOutputLayer", "draws all layers in one pass (gl_Layer from the vertex shader)"},
                         {"VkPhysicalDeviceFeatures.shaderClipDistance", "one draw per layer, and geometry slicing (SliceMode::Geometry)"},
                         {"VkPhysicalDeviceFeatures.geometryShader", "with independentBlend: the layer-id debug output"},
                         {"VkPhysicalDeviceFeatures.independentBlend", "with geometryShader: the layer-id debug output"}};
  r->featureStructs = core13 ? std::vector<std::string>{"VkPhysicalDeviceFeatures2", "VkPhysicalDeviceVulkan12Features",
                                                        "VkPhysicalDeviceVulkan13Features"}
                             : std::vector<std::string>{"VkPhysicalDeviceFeatures2", "VkPhysicalDeviceVulkan12Features",
                                                        "VkPhysicalDeviceSynchronization2Features",
                                                        "VkPhysicalDeviceDynamicRenderingFeatures"};
  std::vector<std::string> why;
  if (instanceApi < VK_API_VERSION_1_2)
    why.push_back("the instance's API version is " + versionName(instanceApi) + " (VkApplicationInfo.apiVersion; Vulkan 1.2 is required)");
  if (props.apiVersion < VK_API_VERSION_1_2)
    why.push_back("the device supports Vulkan " + versionName(props.apiVersion) + " (1.2 is required)");
  uint32_t n = 0;
  vk.GetPhysicalDeviceQueueFamilyProperties(pd, &n, nullptr);
  std::vector<VkQueueFamilyProperties> fams(n);
  vk.GetPhysicalDeviceQueueFamilyProperties(pd, &n, fams.data());
  bool queue = false;
  for (auto& q : fams) queue |= (q.queueFlags & r->queueFlags) == r->queueFlags;
  if (!queue) why.push_back("no queue family has graphics + compute");
  if (why.empty()) {  // 1.1+ entry points are valid only now
    const std::vector<std::string> have = deviceExtensions(vk, pd);
    for (const std::string& e : r->deviceExtensions)
      if (!contains(have, e)) why.push_back("device extension " + e + " is not supported");
    const FeatureView f = supported(vk, pd, core13 ? VK_API_VERSION_1_3 : VK_API_VERSION_1_2);
    if (!f.scalarBlockLayout) why.push_back("feature scalarBlockLayout is not supported");
    if (!f.synchronization2) why.push_back("feature synchronization2 is not supported");
    if (!f.dynamicRendering) why.push_back("feature dynamicRendering is not supported");
    if (!f.shaderOutputLayer && !f.core.shaderClipDistance)
      why.push_back("neither shaderOutputLayer nor shaderClipDistance is supported (no way to draw into a layer)");
  }
  std::string all;
  for (const std::string& w : why) all += (all.empty() ? "" : "; ") + w;
  return all;
}

}  // namespace

Status queryDeviceRequirements(PFN_vkGetInstanceProcAddr gipa, VkInstance instance, uint32_t instanceApiVersion,
                               VkPhysicalDevice pd, DeviceRequirements* out) {
  return guardApi("queryDeviceRequirements", [&]() -> Status {
    if (!out || !pd || !instance) return Status::error("queryDeviceRequirements: instance, physicalDevice and out are required");
    if (!gipa) return Status::error("queryDeviceRequirements: getInstanceProcAddr is required");
    VulkanFunctions vk;
    const std::string missing = loadInstanceFunctions(gipa, instance, &vk);
    // A 1.0 instance may lack the 1.1 entry points: its version is the error, not a function.
    if (!missing.empty() && instanceApiVersion >= VK_API_VERSION_1_2)
      return Status::error(Result::UnsupportedDevice, "queryDeviceRequirements: " + missing + " is unavailable");
    auto props10 = reinterpret_cast<PFN_vkGetPhysicalDeviceProperties>(gipa(instance, "vkGetPhysicalDeviceProperties"));
    auto families10 = reinterpret_cast<PFN_vkGetPhysicalDeviceQueueFamilyProperties>(gipa(instance, "vkGetPhysicalDeviceQueueFamilyProperties"));
    if (!props10 || !families10)
      return Status::error(Result::UnsupportedDevice, "queryDeviceRequirements: vkGetPhysicalDeviceProperties is unavailable");
    vk.GetPhysicalDeviceQueueFamilyProperties = families10;
    VkPhysicalDeviceProperties props{};
    props10(pd, &props);
    const std::string why = fillRequirements(vk, pd, props, instanceApiVersion, out, nullptr);
    if (!why.empty())
      return Status::error(Result::UnsupportedDevice, std::string("queryDeviceRequirements: ") + props.deviceName +
                                                          " cannot run Canopy: " + why);
    return Status();
  });
}

Status enableDeviceFeatures(PFN_vkGetInstanceProcAddr gipa, VkInstance instance, VkPhysicalDevice pd, uint32_t deviceApiVersion,
                            VkPhysicalDeviceFeatures2* chain) {
  return guardApi("enableDeviceFeatures", [&]() -> Status {
    if (!chain || chain->sType != VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2)
      return Status::error(Result::InvalidArgument, "enableDeviceFeatures: chain must start with a VkPhysicalDeviceFeatures2");
    if (deviceApiVersion < VK_API_VERSION_1_2)
      return Status::error(Result::UnsupportedDevice, "enableDeviceFeatures: deviceApiVersion " + versionName(deviceApiVersion) +
                                                          " is below Vulkan 1.2, which Canopy requires");
    VulkanFunctions vk;
    const std::string missing = loadInstanceFunctions(gipa, instance, &vk);
    if (!missing.empty()) return Status::error(Result::UnsupportedDevice, "enableDeviceFeatures: " + missing + " is unavailable");
    VkPhysicalDeviceProperties props;
    vk.GetPhysicalDeviceProperties(pd, &props);
    if (VK_API_VERSION_MAJOR(deviceApiVersion) > VK_API_VERSION_MAJOR(props.apiVersion) ||
        (VK_API_VERSION_MAJOR(deviceApiVersion) == VK_API_VERSION_MAJOR(props.apiVersion) &&
         VK_API_VERSION_MINOR(deviceApiVersion) > VK_API_VERSION_MINOR(props.apiVersion)))
      return Status::error(Result::InvalidArgument, "enableDeviceFeatures: deviceApiVersion " + versionName(deviceApiVersion) +
                                                        " is above the physical device's " + versionName(props.apiVersion) +
                                                        " (pass the lower of the two)");
    const bool is13 = deviceApiVersion >= VK_API_VERSION_1_3;
    const FeatureView have = supported(vk, pd, is13 ? VK_API_VERSION_1_3 : VK_API_VERSION_1_2);
    VkPhysicalDeviceVulkan12Features* f12 = nullptr;
    VkPhysicalDeviceVulkan13Features* f13 = nullptr;
    VkPhysicalDeviceSynchronization2Features* fs2 = nullptr;
    VkPhysicalDeviceDynamicRenderingFeatures* fdr = nullptr;
    for (auto* s = reinterpret_cast<VkBaseOutStructure*>(chain); s; s = s->pNext) {
      if (s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES) f12 = reinterpret_cast<VkPhysicalDeviceVulkan12Features*>(s);
      if (s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES) f13 = reinterpret_cast<VkPhysicalDeviceVulkan13Features*>(s);
      if (s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES) fs2 = reinterpret_cast<VkPhysicalDeviceSynchronization2Features*>(s);
      if (s->sType == VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES) fdr = reinterpret_cast<VkPhysicalDeviceDynamicRenderingFeatures*>(s);
    }
    const std::string want = is13 ? "VkPhysicalDeviceVulkan12Features and VkPhysicalDeviceVulkan13Features"
                                  : "VkPhysicalDeviceVulkan12Features, VkPhysicalDeviceSynchronization2Features and "
                                    "VkPhysicalDeviceDynamicRenderingFeatures";
    const std::string forVersion = " (a Vulkan " + versionName(deviceApiVersion) + " device's chain holds " + want + ")";
    if (!f12) return Status::error(Result::InvalidArgument, "enableDeviceFeatures: the chain has no VkPhysicalDeviceVulkan12Features" + forVersion);
    if (!is13 && f13)
      return Status::error(Result::InvalidArgument, "enableDeviceFeatures: the chain holds VkPhysicalDeviceVulkan13Features, which a "
                                                    "Vulkan 1.2 device refuses (VUID-VkDeviceCreateInfo-pNext-pNext)" + forVersion);
    if (is13 && f13 && (fs2 || fdr))
      return Status::error(Result::InvalidArgument, "enableDeviceFeatures: the chain holds VkPhysicalDeviceVulkan13Features and " +
                                                        std::string(fs2 ? "VkPhysicalDeviceSynchronization2Features" : "VkPhysicalDeviceDynamicRenderingFeatures") +
                                                        ", which Vulkan forbids together" + forVersion);
    if (!f13 && (!fs2 || !fdr))
      return Status::error(Result::InvalidArgument, std::string("enableDeviceFeatures: the chain has no ") +
                                                        (is13 ? "VkPhysicalDeviceVulkan13Features"
                                                              : !fs2 ? "VkPhysicalDeviceSynchronization2Features"
                                                                     : "VkPhysicalDeviceDynamicRenderingFeatures") + forVersion);
    f12->scalarBlockLayout = VK_TRUE;
    f12->shaderOutputLayer = have.shaderOutputLayer ? VK_TRUE : f12->shaderOutputLayer;
    if (f13) {
      f13->synchronization2 = VK_TRUE;
      f13->dynamicRendering = VK_TRUE;
    } else {
      fs2->synchronization2 = VK_TRUE;
      fdr->dynamicRendering = VK_TRUE;
    }
    if (have.core.shaderClipDistance) chain->features.shaderClipDistance = VK_TRUE;
    if (have.core.geometryShader) chain->features.geometryShader = VK_TRUE;
    if (have.core.independentBlend) chain->features.independentBlend = VK_TRUE;
    return Status();
  });
}

Status adoptDeviceInto(const AdoptDeviceDesc& desc, Device* out) {
  Device& d = *out;
  if (!desc.getInstanceProcAddr || !desc.instance || !desc.physicalDevice || !desc.device || !desc.queue)
    return Status::error("AdoptDeviceDesc: getInstanceProcAddr, instance, physicalDevice, device and queue are required");
  if (!desc.deviceCreateInfo)
    return Status::error("AdoptDeviceDesc.deviceCreateInfo is required (the VkDeviceCreateInfo the device was created with)");
  if (desc.framesInFlight < 1 || desc.framesInFlight > 3)
    return Status::error("AdoptDeviceDesc.framesInFlight = " + std::to_string(desc.framesInFlight) + " is outside [1, 3]");
  if (desc.memoryAllocator && (!desc.memoryAllocator->allocate || !desc.memoryAllocator->free))
    return Status::error("AdoptDeviceDesc.memoryAllocator needs both allocate and free");
  if (desc.instanceApiVersion < VK_API_VERSION_1_2)
    return Status::error(Result::UnsupportedDevice, "AdoptDeviceDesc.instanceApiVersion is " + versionName(desc.instanceApiVersion) +
                                                        " (VkApplicationInfo.apiVersion); Canopy requires Vulkan 1.2");
  VulkanFunctions probe;
  std::string missing = loadInstanceFunctions(desc.getInstanceProcAddr, desc.instance, &probe);
  if (!missing.empty()) return Status::error(Result::UnsupportedDevice, "adoptDevice: " + missing + " is unavailable");
  DeviceRequirements req;
  bool core13 = false;
  VkPhysicalDeviceProperties props{};
  probe.GetPhysicalDeviceProperties(desc.physicalDevice, &props);
  const std::string why = fillRequirements(probe, desc.physicalDevice, props, desc.instanceApiVersion, &req, &core13);
  if (!why.empty()) return Status::error(Result::UnsupportedDevice, "adoptDevice: this physical device cannot run Canopy: " + why);

  // What the host enabled, read from its create info.
  const VkDeviceCreateInfo& ci = *desc.deviceCreateInfo;
  std::vector<std::string> enabled;
  for (uint32_t i = 0; i < ci.enabledExtensionCount; ++i) enabled.push_back(ci.ppEnabledExtensionNames[i]);
  std::string absent;
  for (const std::string& e : req.deviceExtensions)
    if (!contains(enabled, e)) absent += (absent.empty() ? "" : ", ") + ("extension " + e);
  const FeatureView on = readChain(ci.pNext, ci.pEnabledFeatures);
  if (!on.scalarBlockLayout) absent += std::string(absent.empty() ? "" : ", ") + "feature scalarBlockLayout";
  if (!on.synchronization2) absent += std::string(absent.empty() ? "" : ", ") + "feature synchronization2";
  if (!on.dynamicRendering) absent += std::string(absent.empty() ? "" : ", ") + "feature dynamicRendering";
  if (!on.shaderOutputLayer && !on.core.shaderClipDistance)
    absent += std::string(absent.empty() ? "" : ", ") + "feature shaderOutputLayer or shaderClipDistance";
  if (!absent.empty())
    return Status::error(Result::UnsupportedDevice, "adoptDevice: the device was created without what Canopy needs: " + absent +
                                                        " (queryDeviceRequirements / enableDeviceFeatures list them)");

  d.instance = desc.instance;
  d.physical = desc.physicalDevice;
  d.device = desc.device;
  d.queue = desc.queue;
  d.queueFamily = desc.queueFamily;
  d.allocationCallbacks = desc.allocationCallbacks;
  d.pipelineCache = desc.pipelineCache;
  if (desc.memoryAllocator) d.hostAllocator = *desc.memoryAllocator;
  d.framesInFlight = desc.framesInFlight;
  missing = loadVulkanFunctions(desc.getInstanceProcAddr, desc.instance, desc.device, core13, &d.vk);
  if (!missing.empty()) return Status::error(Result::UnsupportedDevice, "adoptDevice: " + missing + " is unavailable");
  d.cmdPipelineBarrier2 = d.vk.CmdPipelineBarrier2;
  d.cmdPushDescriptorSet = d.vk.CmdPushDescriptorSetKHR;
  d.cmdBeginRendering = d.vk.CmdBeginRendering;
  d.cmdEndRendering = d.vk.CmdEndRendering;
  // Used only where debug utils is known to be enabled (createDevice with validation sets
  // validationEnabled); the public desc does not list the host's instance extensions.
  d.setObjectName = d.vk.SetDebugUtilsObjectNameEXT;
  d.vk.GetPhysicalDeviceProperties(d.physical, &d.properties);
  d.vk.GetPhysicalDeviceMemoryProperties(d.physical, &d.memoryProperties);
  {
    VkPhysicalDeviceSubgroupProperties sg{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
    VkPhysicalDeviceProperties2 p2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2, &sg};
    d.vk.GetPhysicalDeviceProperties2(d.physical, &p2);
    const VkSubgroupFeatureFlags need =
        VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_SHUFFLE_BIT | VK_SUBGROUP_FEATURE_ARITHMETIC_BIT;
    d.subgroupSize = sg.subgroupSize;
    d.computeSubgroupShuffle = (sg.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) && (sg.supportedOperations & need) == need;
  }
  {
    uint32_t qn = 0;
    d.vk.GetPhysicalDeviceQueueFamilyProperties(d.physical, &qn, nullptr);
    std::vector<VkQueueFamilyProperties> fams(qn);
    d.vk.GetPhysicalDeviceQueueFamilyProperties(d.physical, &qn, fams.data());
    if (d.queueFamily >= qn) return Status::error("AdoptDeviceDesc.queueFamily = " + std::to_string(d.queueFamily) + " does not exist");
    const VkQueueFlags need = VK_QUEUE_GRAPHICS_BIT | VK_QUEUE_COMPUTE_BIT;
    if ((fams[d.queueFamily].queueFlags & need) != need)
      return Status::error(Result::UnsupportedDevice, "AdoptDeviceDesc.queueFamily " + std::to_string(d.queueFamily) +
                                                          " lacks graphics + compute");
    d.timestampValidBits = d.properties.limits.timestampComputeAndGraphics ? fams[d.queueFamily].timestampValidBits : 0;
  }
  d.shaderOutputLayer = on.shaderOutputLayer;
  d.shaderClipDistance = on.core.shaderClipDistance;
  d.fragmentPrimitiveId = on.core.geometryShader;
  d.independentBlend = on.core.independentBlend;
  d.pipelineStatistics = on.core.pipelineStatisticsQuery;  // the host's own choice (engine/pass_counters.h)

  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_TRANSIENT_BIT | VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = d.queueFamily;
  CANOPY_VK(d.vk.CreateCommandPool(d.device, &pci, d.allocationCallbacks, &d.oneShotPool));
  d.allocator = new Allocator();
  CANOPY_TRY(initAllocator(d, d.allocator));
  return Status();
}

void releaseAdoptedDevice(Device& d) {
  if (!d.device || !d.vk.DestroyCommandPool) return;  // adoption stopped before the table was loaded
  releaseAllPending(d);
  if (d.allocator) {
    destroyAllocator(d, *d.allocator);
    delete d.allocator;
    d.allocator = nullptr;
  }
  if (d.oneShotPool) d.vk.DestroyCommandPool(d.device, d.oneShotPool, d.allocationCallbacks);
  d.oneShotPool = VK_NULL_HANDLE;
}

Status adoptDevice(const AdoptDeviceDesc& desc, Device** out) {
  return guardApi("adoptDevice", [&]() -> Status {
    if (!out) return Status::error("adoptDevice: out is null");
    *out = nullptr;
    auto* d = new (std::nothrow) Device();
    if (!d) return Status::error(Result::OutOfHostMemory, "adoptDevice: out of host memory");
    Status s = adoptDeviceInto(desc, d);
    if (!s.ok()) {
      releaseAdoptedDevice(*d);
      delete d;
      return s;
    }
    d->deferUploads = true;  // a host's device: Canopy submits nothing behind its back
    *out = d;
    return Status();
  });
}

void releaseDevice(Device* d) {
  if (!d) return;
  releaseAdoptedDevice(*d);
  delete d;
}

void deferRelease(Device& d, std::function<void()> release) {
  if (!d.anyFrame) {
    release();  // nothing was ever recorded: no frame can be using it
    return;
  }
  d.pendingReleases.push_back({d.frameNumber, std::move(release)});
}

Status beginDeviceFrame(Device& d, uint64_t frameNumber) {
  if (d.anyFrame && frameNumber < d.frameNumber)
    return Status::error("CanopyFrame.frameNumber = " + std::to_string(frameNumber) + " is older than frame " +
                         std::to_string(d.frameNumber) + " already recorded (frame numbers never decrease)");
  d.frameNumber = frameNumber;
  d.anyFrame = true;
  // A frame tagged T was last used by host frame T; recording F promises F - framesInFlight done.
  std::vector<Device::PendingRelease> keep;
  std::vector<Device::PendingRelease> now;
  for (auto& p : d.pendingReleases) (p.frame + d.framesInFlight <= frameNumber ? now : keep).push_back(std::move(p));
  d.pendingReleases = std::move(keep);
  for (auto& p : now) p.release();
  return Status();
}

void releaseAllPending(Device& d) {
  // Releases can queue further releases (a context freeing its parts): drain until empty.
  while (!d.pendingReleases.empty()) {
    std::vector<Device::PendingRelease> now = std::move(d.pendingReleases);
    d.pendingReleases.clear();
    for (auto& p : now) p.release();
  }
}

Status submitAndWait(Device& d, const std::function<Status(VkCommandBuffer)>& record) {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = d.oneShotPool;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = 1;
  VkCommandBuffer cmd;
  CANOPY_VK(d.vk.AllocateCommandBuffers(d.device, &ai, &cmd));
  VkFence fence = VK_NULL_HANDLE;
  bool submitted = false;
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  Status s = [&]() -> Status {
    CANOPY_VK(d.vk.BeginCommandBuffer(cmd, &bi));
    CANOPY_TRY(record(cmd));
    CANOPY_VK(d.vk.EndCommandBuffer(cmd));
    VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    CANOPY_VK(d.vk.CreateFence(d.device, &fci, d.allocationCallbacks, &fence));
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd;
    CANOPY_VK(d.vk.QueueSubmit(d.queue, 1, &si, fence));
    submitted = true;
    CANOPY_VK(d.vk.WaitForFences(d.device, 1, &fence, VK_TRUE, UINT64_MAX));
    return Status();
  }();
  // A submitted buffer whose wait failed (device lost) cannot be proven idle; it is leaked with its
  // fence rather than freed under the GPU.
  const bool safe = !submitted || s.ok();
  if (safe) {
    if (fence) d.vk.DestroyFence(d.device, fence, d.allocationCallbacks);
    d.vk.FreeCommandBuffers(d.device, d.oneShotPool, 1, &cmd);
  }
  return s;
}

void setDebugName(const Device& d, VkObjectType type, uint64_t handle, const char* name) {
  if (!d.setObjectName || !name || !d.validationEnabled) return;
  VkDebugUtilsObjectNameInfoEXT info{VK_STRUCTURE_TYPE_DEBUG_UTILS_OBJECT_NAME_INFO_EXT};
  info.objectType = type;
  info.objectHandle = handle;
  info.pObjectName = name;
  d.setObjectName(d.device, &info);
}

}  // namespace canopy
