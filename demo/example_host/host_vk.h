#pragma once
// The example hosts' own small Vulkan helpers (demo/example_host.cpp, demo/game_host.cpp): what an
// engine has in its renderer already — its instance with validation, a memory-type search, a 2D
// image with its memory and view, an image barrier, the box pipeline from host_box.vert/frag. Nothing of Canopy's: the hosts embed
// Canopy through <canopy/canopy.h> only.
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>
#include <vulkan/vulkan.h>

#include <glm/glm.hpp>

#include "host_box.frag.h"  // SPIR-V words, built by glslangValidator
#include "host_box.vert.h"

namespace host {

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

// The box pipeline layout (BoxPush as push constants).
inline VkResult createBoxLayout(VkDevice device, VkPipelineLayout* out) {
  VkPushConstantRange range{VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT, 0, sizeof(BoxPush)};
  VkPipelineLayoutCreateInfo li{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  li.pushConstantRangeCount = 1;
  li.pPushConstantRanges = &range;
  return vkCreatePipelineLayout(device, &li, nullptr, out);
}

// A box pipeline for dynamic rendering into `color` and `depth` (`stencil`: the depth format again,
// or UNDEFINED), with depth-stencil state `ds`; viewport, scissor and (with `stencilReference`)
// the stencil reference are dynamic.
inline VkResult createBoxPipeline(VkDevice device, VkPipelineLayout layout, VkFormat color, VkFormat depth, VkFormat stencil,
                                  const VkPipelineDepthStencilStateCreateInfo& ds, bool stencilReference, VkPipeline* out) {
  VkShaderModule modules[2] = {};
  const uint32_t* code[2] = {host_box_vert, host_box_frag};
  const size_t size[2] = {sizeof(host_box_vert), sizeof(host_box_frag)};
  VkResult r = VK_SUCCESS;
  for (int i = 0; i < 2 && r == VK_SUCCESS; ++i) {
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
  cb.attachmentCount = 1;
  cb.pAttachments = &blend;
  const VkDynamicState dyn[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR, VK_DYNAMIC_STATE_STENCIL_REFERENCE};
  VkPipelineDynamicStateCreateInfo dy{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
  dy.dynamicStateCount = stencilReference ? 3 : 2;
  dy.pDynamicStates = dyn;
  VkPipelineRenderingCreateInfo rci{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
  rci.colorAttachmentCount = 1;
  rci.pColorAttachmentFormats = &color;
  rci.depthAttachmentFormat = depth;
  rci.stencilAttachmentFormat = stencil;
  VkGraphicsPipelineCreateInfo pci{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO, &rci};
  pci.stageCount = 2;
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

}  // namespace host
