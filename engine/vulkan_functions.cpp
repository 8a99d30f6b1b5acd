#include "engine/vulkan_functions.h"

namespace canopy {

std::string loadInstanceFunctions(PFN_vkGetInstanceProcAddr gipa, VkInstance instance, VulkanFunctions* f) {
  if (!gipa) return "vkGetInstanceProcAddr";
#define CANOPY_VK_LOAD(name)                                                  \
  f->name = reinterpret_cast<PFN_vk##name>(gipa(instance, "vk" #name));       \
  if (!f->name) return "vk" #name;
  CANOPY_VK_INSTANCE_FUNCTIONS(CANOPY_VK_LOAD)
#undef CANOPY_VK_LOAD
  return "";
}

std::string loadVulkanFunctions(PFN_vkGetInstanceProcAddr gipa, VkInstance instance, VkDevice device, bool core13,
                                VulkanFunctions* f) {
  std::string missing = loadInstanceFunctions(gipa, instance, f);
  if (!missing.empty()) return missing;
  PFN_vkGetDeviceProcAddr gdpa = f->GetDeviceProcAddr;
#define CANOPY_VK_LOAD(name)                                                  \
  f->name = reinterpret_cast<PFN_vk##name>(gdpa(device, "vk" #name));         \
  if (!f->name) return "vk" #name;
  CANOPY_VK_DEVICE_FUNCTIONS(CANOPY_VK_LOAD)
#undef CANOPY_VK_LOAD
  auto either = [&](const char* core, const char* khr) {
    PFN_vkVoidFunction p = core13 ? gdpa(device, core) : nullptr;
    return p ? p : gdpa(device, khr);
  };
  f->CmdPipelineBarrier2 = reinterpret_cast<PFN_vkCmdPipelineBarrier2>(either("vkCmdPipelineBarrier2", "vkCmdPipelineBarrier2KHR"));
  if (!f->CmdPipelineBarrier2) return "vkCmdPipelineBarrier2 (or vkCmdPipelineBarrier2KHR)";
  f->CmdBeginRendering = reinterpret_cast<PFN_vkCmdBeginRendering>(either("vkCmdBeginRendering", "vkCmdBeginRenderingKHR"));
  f->CmdEndRendering = reinterpret_cast<PFN_vkCmdEndRendering>(either("vkCmdEndRendering", "vkCmdEndRenderingKHR"));
  if (!f->CmdBeginRendering || !f->CmdEndRendering) return "vkCmdBeginRendering (or vkCmdBeginRenderingKHR)";
  f->CmdPushDescriptorSetKHR = reinterpret_cast<PFN_vkCmdPushDescriptorSetKHR>(gdpa(device, "vkCmdPushDescriptorSetKHR"));
  if (!f->CmdPushDescriptorSetKHR) return "vkCmdPushDescriptorSetKHR";
  // Debug names are optional: present only when the host enabled VK_EXT_debug_utils.
  f->SetDebugUtilsObjectNameEXT =
      reinterpret_cast<PFN_vkSetDebugUtilsObjectNameEXT>(gipa(instance, "vkSetDebugUtilsObjectNameEXT"));
  return "";
}

}  // namespace canopy
