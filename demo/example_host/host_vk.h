#pragma once
// The example hosts' own small Vulkan helpers (demo/example_host.cpp, demo/game_host.cpp): what an
// engine has in its renderer already — its instance with validation, its device made with what
// Canopy asks for and adopted, a memory-type search, a 2D image with its memory and view, an image
// barrier, the box pipeline from host_box.vert/frag. Canopy through <canopy/canopy.h> only, as a
// host embeds it (docs/embedding.md).
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include <canopy/canopy.h>

#include <glm/glm.hpp>

#include "host_box.frag.h"  // SPIR-V words, built by glslangValidator
#include "host_box.vert.h"

namespace host {

// The program's name in messages (each host defines it).
extern const char* const kProgram;

// A Vulkan call in a function returning bool: on failure, says which call and its VkResult.
#define HOST_CHECK(call)                                                                        \
  do {                                                                                          \
    VkResult r_ = (call);                                                                       \
    if (r_ != VK_SUCCESS) {                                                                     \
      std::fprintf(stderr, "%s: %s failed: VkResult %d\n", host::kProgram, #call, int(r_));     \
      return false;                                                                             \
    }                                                                                           \
  } while (0)

// The hosts' colour target and the usage both create their targets with, declared to Canopy with
// them (CanopyImage); the depth is SAMPLED because Canopy reads it.
constexpr VkFormat kColorFormat = VK_FORMAT_R8G8B8A8_UNORM;
constexpr VkImageUsageFlags kColorUsage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
constexpr VkImageUsageFlags kDepthUsage =
    VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;

// Counts (and prints) every validation message into the int the messenger was created with.
inline VKAPI_ATTR VkBool32 VKAPI_CALL onValidation(VkDebugUtilsMessageSeverityFlagBitsEXT, VkDebugUtilsMessageTypeFlagsEXT,
                                                   const VkDebugUtilsMessengerCallbackDataEXT* data, void* counter) {
  ++*static_cast<int*>(counter);
  std::fprintf(stderr, "validation: %s: %s\n", data->pMessageIdName ? data->pMessageIdName : "", data->pMessage);
  return VK_FALSE;
}

// The host's instance at the newest version Canopy knows the loader has (1.3, else 1.2; *apiVersion),
// with `extensions`; with `validate`, the validation layer and synchronization validation on and
// every message counted into *messages (a messenger in *messenger). A missing layer is an error.
inline VkResult createInstance(const char* name, std::vector<const char*> extensions, bool validate, int* messages,
                               uint32_t* apiVersion, VkInstance* instance, VkDebugUtilsMessengerEXT* messenger) {
  uint32_t loader = VK_API_VERSION_1_0;
  vkEnumerateInstanceVersion(&loader);
  *apiVersion = loader >= VK_API_VERSION_1_3 ? VK_API_VERSION_1_3 : VK_API_VERSION_1_2;
  const char* layer = "VK_LAYER_KHRONOS_validation";
  if (validate) {
    uint32_t n = 0;
    vkEnumerateInstanceLayerProperties(&n, nullptr);
    std::vector<VkLayerProperties> layers(n);
    vkEnumerateInstanceLayerProperties(&n, layers.data());
    bool found = false;
    for (const VkLayerProperties& l : layers) found = found || std::strcmp(l.layerName, layer) == 0;
    if (!found) {
      std::fprintf(stderr, "%s: %s is not installed (apt-get install vulkan-validationlayers)\n", name, layer);
      return VK_ERROR_LAYER_NOT_PRESENT;
    }
    extensions.push_back(VK_EXT_DEBUG_UTILS_EXTENSION_NAME);
  }
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = name;
  app.apiVersion = *apiVersion;
  const VkValidationFeatureEnableEXT sync = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT;
  VkValidationFeaturesEXT vf{VK_STRUCTURE_TYPE_VALIDATION_FEATURES_EXT};
  vf.enabledValidationFeatureCount = 1;
  vf.pEnabledValidationFeatures = &sync;
  VkInstanceCreateInfo ici{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO, validate ? &vf : nullptr};
  ici.pApplicationInfo = &app;
  ici.enabledLayerCount = validate ? 1 : 0;
  ici.ppEnabledLayerNames = &layer;
  ici.enabledExtensionCount = uint32_t(extensions.size());
  ici.ppEnabledExtensionNames = extensions.data();
  VkResult r = vkCreateInstance(&ici, nullptr, instance);
  if (r != VK_SUCCESS || !validate) return r;
  VkDebugUtilsMessengerCreateInfoEXT mci{VK_STRUCTURE_TYPE_DEBUG_UTILS_MESSENGER_CREATE_INFO_EXT};
  mci.messageSeverity = VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT;
  mci.messageType = VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT | VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT;
  mci.pfnUserCallback = onValidation;
  mci.pUserData = messages;
  auto create = (PFN_vkCreateDebugUtilsMessengerEXT)vkGetInstanceProcAddr(*instance, "vkCreateDebugUtilsMessengerEXT");
  return create ? create(*instance, &mci, nullptr, messenger) : VK_ERROR_EXTENSION_NOT_PRESENT;
}

inline void destroyInstance(VkInstance instance, VkDebugUtilsMessengerEXT messenger) {
  if (!instance) return;
  if (messenger) {
    auto destroy = (PFN_vkDestroyDebugUtilsMessengerEXT)vkGetInstanceProcAddr(instance, "vkDestroyDebugUtilsMessengerEXT");
    if (destroy) destroy(instance, messenger, nullptr);
  }
  vkDestroyInstance(instance, nullptr);
}

// host_box.vert's push constants: a unit cube placed by mvp, shaded in `color`.
struct BoxPush {
  glm::mat4 mvp;
  glm::vec4 color;
};

// A memory type with `need` among `bits`, preferring one that also has `want`; -1: none.
inline int32_t memoryType(const VkPhysicalDeviceMemoryProperties& props, uint32_t bits, VkMemoryPropertyFlags need,
                          VkMemoryPropertyFlags want = 0) {
  for (int pass = 0; pass < 2; ++pass)
    for (uint32_t i = 0; i < props.memoryTypeCount; ++i) {
      const VkMemoryPropertyFlags f = props.memoryTypes[i].propertyFlags;
      if ((bits & (1u << i)) && (f & need) == need && (pass == 1 || (f & want) == want)) return int32_t(i);
    }
  return -1;
}

struct Image {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;       // every aspect of the format
  VkImageView depthOnly = VK_NULL_HANDLE;  // a depth-stencil format's depth aspect (Canopy's view)
  VkDeviceMemory memory = VK_NULL_HANDLE;
};

// A single-sampled 2D image in device-local memory with its views.
inline VkResult createImage(VkDevice device, const VkPhysicalDeviceMemoryProperties& props, uint32_t width, uint32_t height,
                            VkFormat format, VkImageUsageFlags usage, VkImageAspectFlags aspect, Image* out) {
  VkImageCreateInfo ci{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ci.imageType = VK_IMAGE_TYPE_2D;
  ci.format = format;
  ci.extent = {width, height, 1};
  ci.mipLevels = ci.arrayLayers = 1;
  ci.samples = VK_SAMPLE_COUNT_1_BIT;
  ci.tiling = VK_IMAGE_TILING_OPTIMAL;
  ci.usage = usage;
  VkResult r = vkCreateImage(device, &ci, nullptr, &out->image);
  if (r != VK_SUCCESS) return r;
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(device, out->image, &req);
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = req.size;
  const int32_t type = memoryType(props, req.memoryTypeBits, 0, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  if (type < 0) return VK_ERROR_OUT_OF_DEVICE_MEMORY;
  ai.memoryTypeIndex = uint32_t(type);
  if ((r = vkAllocateMemory(device, &ai, nullptr, &out->memory)) != VK_SUCCESS) return r;
  if ((r = vkBindImageMemory(device, out->image, out->memory, 0)) != VK_SUCCESS) return r;
  VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vi.image = out->image;
  vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
  vi.format = format;
  vi.subresourceRange = {aspect, 0, 1, 0, 1};
  if ((r = vkCreateImageView(device, &vi, nullptr, &out->view)) != VK_SUCCESS) return r;
  if (aspect == (VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT)) {
    vi.subresourceRange.aspectMask = VK_IMAGE_ASPECT_DEPTH_BIT;
    r = vkCreateImageView(device, &vi, nullptr, &out->depthOnly);
  }
  return r;
}

inline void destroyImage(VkDevice device, Image& image) {
  vkDestroyImageView(device, image.view, nullptr);
  vkDestroyImageView(device, image.depthOnly, nullptr);
  vkDestroyImage(device, image.image, nullptr);
  vkFreeMemory(device, image.memory, nullptr);
  image = Image{};
}

inline void barrier(VkCommandBuffer cmd, VkImage image, VkImageAspectFlags aspect, VkImageLayout from, VkImageLayout to,
                    VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess, VkPipelineStageFlags2 dstStage,
                    VkAccessFlags2 dstAccess) {
  VkImageMemoryBarrier2 b{VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER_2};
  b.srcStageMask = srcStage;
  b.srcAccessMask = srcAccess;
  b.dstStageMask = dstStage;
  b.dstAccessMask = dstAccess;
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {aspect, 0, 1, 0, 1};
  VkDependencyInfo di{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  di.imageMemoryBarrierCount = 1;
  di.pImageMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &di);
}

// A whole-buffer barrier: `buffer`'s accesses before (src) ordered before those after (dst).
inline void bufferBarrier(VkCommandBuffer cmd, VkBuffer buffer, VkPipelineStageFlags2 srcStage, VkAccessFlags2 srcAccess,
                          VkPipelineStageFlags2 dstStage, VkAccessFlags2 dstAccess) {
  VkBufferMemoryBarrier2 b{VK_STRUCTURE_TYPE_BUFFER_MEMORY_BARRIER_2};
  b.srcStageMask = srcStage;
  b.srcAccessMask = srcAccess;
  b.dstStageMask = dstStage;
  b.dstAccessMask = dstAccess;
  b.srcQueueFamilyIndex = b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.buffer = buffer;
  b.size = VK_WHOLE_SIZE;
  VkDependencyInfo di{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
  di.bufferMemoryBarrierCount = 1;
  di.pBufferMemoryBarriers = &b;
  vkCmdPipelineBarrier2(cmd, &di);
}

// A pool whose command buffers are reset one by one (a frame slot re-records its own).
inline VkResult createCommandPool(VkDevice device, uint32_t family, VkCommandPool* out) {
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = family;
  return vkCreateCommandPool(device, &pci, nullptr, out);
}

// A frame slot's command buffer and the fence its submission signals.
inline VkResult createFrameSlot(VkDevice device, VkCommandPool pool, VkCommandBuffer* cmd, VkFence* fence) {
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = pool;
  ai.commandBufferCount = 1;
  VkResult r = vkAllocateCommandBuffers(device, &ai, cmd);
  if (r != VK_SUCCESS) return r;
  VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  return vkCreateFence(device, &fci, nullptr, fence);
}

// The hosts' box pass: dynamic rendering into `color` and `depth` (and its stencil with
// `stencil`), cleared to `clearColor` / `clearDepth` or loaded, both stored (Canopy reads the host's
// depth), viewport and scissor over `width` x `height`, `pipeline` bound. vkCmdEndRendering ends it.
inline void beginBoxPass(VkCommandBuffer cmd, VkImageView color, VkImageView depth, bool stencil, bool clear,
                         VkClearColorValue clearColor, float clearDepth, uint32_t width, uint32_t height, VkPipeline pipeline) {
  VkRenderingAttachmentInfo c{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO}, z{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  c.imageView = color;
  c.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  c.loadOp = clear ? VK_ATTACHMENT_LOAD_OP_CLEAR : VK_ATTACHMENT_LOAD_OP_LOAD;
  c.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  c.clearValue.color = clearColor;
  z.imageView = depth;
  z.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
  z.loadOp = c.loadOp;
  z.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  z.clearValue.depthStencil = {clearDepth, 0};
  VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
  ri.renderArea = {{0, 0}, {width, height}};
  ri.layerCount = 1;
  ri.colorAttachmentCount = 1;
  ri.pColorAttachments = &c;
  ri.pDepthAttachment = &z;
  ri.pStencilAttachment = stencil ? &z : nullptr;
  vkCmdBeginRendering(cmd, &ri);
  const VkViewport v{0, 0, float(width), float(height), 0, 1};
  const VkRect2D sc{{0, 0}, {width, height}};
  vkCmdSetViewport(cmd, 0, 1, &v);
  vkCmdSetScissor(cmd, 0, 1, &sc);
  vkCmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, pipeline);
}

// Depth tested with `compare` and written, no stencil (a box pipeline's depth state to start from).
inline VkPipelineDepthStencilStateCreateInfo depthTested(VkCompareOp compare) {
  VkPipelineDepthStencilStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
  ds.depthTestEnable = ds.depthWriteEnable = VK_TRUE;
  ds.depthCompareOp = compare;
  return ds;
}

// The box pipeline layout (BoxPush as push constants).
inline VkResult createBoxLayout(VkDevice device, VkPipelineLayout* out) {
  VkPushConstantRange range{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(BoxPush)};
  VkPipelineLayoutCreateInfo li{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  li.pushConstantRangeCount = 1;
  li.pPushConstantRanges = &range;
  return vkCreatePipelineLayout(device, &li, nullptr, out);
}

// A host's SPIR-V: a vertex shader and a fragment shader (none: a depth-only pass).
struct ShaderPair {
  const uint32_t* vert = nullptr;
  size_t vertBytes = 0;
  const uint32_t* frag = nullptr;
  size_t fragBytes = 0;
};

// A pipeline for dynamic rendering of `shaders` (no vertex input: the shaders make their corners)
// into `color` (UNDEFINED: none, a depth-only pass) and `depth` (`stencil`: the depth format again,
// or UNDEFINED), with depth-stencil state `ds`; viewport, scissor and (with `stencilReference`) the
// stencil reference are dynamic.
inline VkResult createHostPipeline(VkDevice device, VkPipelineLayout layout, const ShaderPair& shaders, VkFormat color, VkFormat depth,
                                   VkFormat stencil, const VkPipelineDepthStencilStateCreateInfo& ds, bool stencilReference,
                                   VkPipeline* out) {
  VkShaderModule modules[2] = {};
  const uint32_t* code[2] = {shaders.vert, shaders.frag};
  const size_t size[2] = {shaders.vertBytes, shaders.fragBytes};
  const uint32_t stageCount = shaders.frag ? 2 : 1;
  VkResult r = VK_SUCCESS;
  for (uint32_t i = 0; i < stageCount && r == VK_SUCCESS; ++i) {
    VkShaderModuleCreateInfo mi{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    mi.codeSize = size[i];
    mi.pCode = code[i];
    r = vkCreateShaderModule(device, &mi, nullptr, &modules[i]);
  }
  VkPipelineShaderStageCreateInfo stages[2] = {{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO},
                                               {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO}};
  stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
  stages[0].module = modules[0];
  stages[0].pName = "main";
  stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
  stages[1].module = modules[1];
  stages[1].pName = "main";
  VkPipelineVertexInputStateCreateInfo vin{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
  VkPipelineInputAssemblyStateCreateInfo ia{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
  ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
  VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
  vp.viewportCount = vp.scissorCount = 1;
  VkPipelineRasterizationStateCreateInfo rs{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
  rs.polygonMode = VK_POLYGON_MODE_FILL;
  rs.cullMode = VK_CULL_MODE_NONE;
  rs.lineWidth = 1.0f;
  VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
  ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
  VkPipelineColorBlendAttachmentState blend{};
  blend.colorWriteMask = 0xf;
  VkPipelineColorBlendStateCreateInfo cb{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
  cb.attachmentCount = color != VK_FORMAT_UNDEFINED ? 1 : 0;
  cb.pAttachments = &blend;
  const VkDynamicState dyn[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR, VK_DYNAMIC_STATE_STENCIL_REFERENCE};
  VkPipelineDynamicStateCreateInfo dy{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
  dy.dynamicStateCount = stencilReference ? 3 : 2;
  dy.pDynamicStates = dyn;
  VkPipelineRenderingCreateInfo rci{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
  rci.colorAttachmentCount = color != VK_FORMAT_UNDEFINED ? 1 : 0;
  rci.pColorAttachmentFormats = &color;
  rci.depthAttachmentFormat = depth;
  rci.stencilAttachmentFormat = stencil;
  VkGraphicsPipelineCreateInfo pci{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO, &rci};
  pci.stageCount = stageCount;
  pci.pStages = stages;
  pci.pVertexInputState = &vin;
  pci.pInputAssemblyState = &ia;
  pci.pViewportState = &vp;
  pci.pRasterizationState = &rs;
  pci.pMultisampleState = &ms;
  pci.pDepthStencilState = &ds;
  pci.pColorBlendState = &cb;
  pci.pDynamicState = &dy;
  pci.layout = layout;
  if (r == VK_SUCCESS) r = vkCreateGraphicsPipelines(device, VK_NULL_HANDLE, 1, &pci, nullptr, out);
  for (VkShaderModule m : modules)
    if (m) vkDestroyShaderModule(device, m, nullptr);
  return r;
}

// The box pipeline (host_box.vert/frag) into `color` and `depth`, as createHostPipeline.
inline VkResult createBoxPipeline(VkDevice device, VkPipelineLayout layout, VkFormat color, VkFormat depth, VkFormat stencil,
                                  const VkPipelineDepthStencilStateCreateInfo& ds, bool stencilReference, VkPipeline* out) {
  return createHostPipeline(device, layout, {host_box_vert, sizeof(host_box_vert), host_box_frag, sizeof(host_box_frag)}, color, depth,
                            stencil, ds, stencilReference, out);
}

// The host's device, made as docs/embedding.md says: a physical device Canopy can run on
// (queryDeviceRequirements says why one is skipped), a discrete GPU first, with a graphics +
// compute family (that presents to `surface` when one is given), Canopy's extensions and features
// switched on in the host's own chain for the device's API version.
struct HostDevice {
  VkPhysicalDevice physical = VK_NULL_HANDLE;
  uint32_t family = 0;
  uint32_t apiVersion = 0;  // the device's: the lower of the instance's and the physical device's
  std::string name;
  VkPhysicalDeviceMemoryProperties memory{};
  VkDevice device = VK_NULL_HANDLE;
  VkQueue queue = VK_NULL_HANDLE;
  // What the device was created with, for adoptDevice (which reads it during the call).
  struct Created {
    VkPhysicalDeviceDynamicRenderingFeatures dynamicRendering{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_DYNAMIC_RENDERING_FEATURES};
    VkPhysicalDeviceSynchronization2Features sync2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SYNCHRONIZATION_2_FEATURES};
    VkPhysicalDeviceVulkan13Features f13{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_3_FEATURES};
    VkPhysicalDeviceVulkan12Features f12{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_VULKAN_1_2_FEATURES};
    VkPhysicalDeviceFeatures2 features{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    std::vector<std::string> extensionNames;
    std::vector<const char*> extensions;
    float priority = 1.0f;
    VkDeviceQueueCreateInfo queueInfo{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    VkDeviceCreateInfo info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  };
  std::unique_ptr<Created> created;
};

inline bool createHostDevice(VkInstance instance, uint32_t instanceApi, VkSurfaceKHR surface,
                             const std::vector<const char*>& extraExtensions, HostDevice* out) {
  uint32_t n = 0;
  vkEnumeratePhysicalDevices(instance, &n, nullptr);
  std::vector<VkPhysicalDevice> pds(n);
  vkEnumeratePhysicalDevices(instance, &n, pds.data());
  canopy::DeviceRequirements req;
  for (VkPhysicalDevice pd : pds) {
    VkPhysicalDeviceProperties p;
    vkGetPhysicalDeviceProperties(pd, &p);
    canopy::DeviceRequirements r;
    const canopy::Status s = canopy::queryDeviceRequirements(vkGetInstanceProcAddr, instance, instanceApi, pd, &r);
    if (!s.ok()) {
      std::fprintf(stderr, "%s: skipping %s: %s\n", kProgram, p.deviceName, s.message().c_str());
      continue;
    }
    if (out->physical && p.deviceType != VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU) continue;
    uint32_t qn = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &qn, nullptr);
    std::vector<VkQueueFamilyProperties> fams(qn);
    vkGetPhysicalDeviceQueueFamilyProperties(pd, &qn, fams.data());
    for (uint32_t i = 0; i < qn; ++i) {
      VkBool32 present = VK_TRUE;
      if (surface) vkGetPhysicalDeviceSurfaceSupportKHR(pd, i, surface, &present);
      if (present && (fams[i].queueFlags & r.queueFlags) == r.queueFlags) {
        out->physical = pd;
        out->family = i;
        out->name = p.deviceName;
        out->apiVersion = std::min(instanceApi, p.apiVersion);
        req = r;
        break;
      }
    }
  }
  if (!out->physical) {
    std::fprintf(stderr, "%s: no device runs Canopy%s\n", kProgram, surface ? " and presents to the window" : "");
    return false;
  }
  vkGetPhysicalDeviceMemoryProperties(out->physical, &out->memory);
  // The chain for the device's version (DeviceRequirements::featureStructs); Canopy switches its
  // features on in it.
  out->created = std::make_unique<HostDevice::Created>();
  HostDevice::Created& c = *out->created;
  const bool core13 = out->apiVersion >= VK_API_VERSION_1_3;
  c.sync2.pNext = &c.dynamicRendering;
  c.f12.pNext = core13 ? static_cast<void*>(&c.f13) : static_cast<void*>(&c.sync2);
  c.features.pNext = &c.f12;
  const canopy::Status s = canopy::enableDeviceFeatures(vkGetInstanceProcAddr, instance, out->physical, out->apiVersion, &c.features);
  if (!s.ok()) {
    std::fprintf(stderr, "%s: %s\n", kProgram, s.message().c_str());
    return false;
  }
  c.extensionNames = req.deviceExtensions;
  c.extensions = extraExtensions;
  for (const std::string& e : c.extensionNames) c.extensions.push_back(e.c_str());
  c.queueInfo.queueFamilyIndex = out->family;
  c.queueInfo.queueCount = 1;
  c.queueInfo.pQueuePriorities = &c.priority;
  c.info.pNext = &c.features;
  c.info.queueCreateInfoCount = 1;
  c.info.pQueueCreateInfos = &c.queueInfo;
  c.info.enabledExtensionCount = uint32_t(c.extensions.size());
  c.info.ppEnabledExtensionNames = c.extensions.data();
  HOST_CHECK(vkCreateDevice(out->physical, &c.info, nullptr, &out->device));
  vkGetDeviceQueue(out->device, out->family, 0, &out->queue);
  return true;
}

// Canopy on the host's device, through the host's loader (and its allocator, when given).
inline bool adoptHostDevice(const HostDevice& d, VkInstance instance, uint32_t instanceApi, uint32_t framesInFlight,
                            const canopy::DeviceMemoryAllocator* allocator, canopy::Device** adopted) {
  canopy::AdoptDeviceDesc ad;
  ad.getInstanceProcAddr = vkGetInstanceProcAddr;
  ad.instance = instance;
  ad.instanceApiVersion = instanceApi;
  ad.physicalDevice = d.physical;
  ad.device = d.device;
  ad.deviceCreateInfo = &d.created->info;
  ad.queue = d.queue;
  ad.queueFamily = d.family;
  ad.memoryAllocator = allocator;
  ad.framesInFlight = framesInFlight;
  const canopy::Status s = canopy::adoptDevice(ad, adopted);
  if (!s.ok()) std::fprintf(stderr, "%s: %s\n", kProgram, s.message().c_str());
  return s.ok();
}

}  // namespace host
