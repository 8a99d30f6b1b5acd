#pragma once
// Every Vulkan entry point the runtime library calls, loaded per device through the host's
// vkGetInstanceProcAddr (docs/design.md, "Embedding contract"): the library is compiled with
// VK_NO_PROTOTYPES, so it never binds to the loader's exported symbols, and a host that uses its
// own loader (volk, a static loader, layers of its own) gets Canopy's calls through the same
// dispatch it uses. One table per canopy::Device, no global pointers.
#include <string>
#include <vulkan/vulkan.h>

namespace canopy {

// Instance-level functions (vkGetInstanceProcAddr with the host's instance).
#define CANOPY_VK_INSTANCE_FUNCTIONS(X)     \
  X(GetDeviceProcAddr)                      \
  X(GetPhysicalDeviceProperties)            \
  X(GetPhysicalDeviceProperties2)           \
  X(GetPhysicalDeviceFeatures2)             \
  X(GetPhysicalDeviceQueueFamilyProperties) \
  X(GetPhysicalDeviceMemoryProperties)      \
  X(GetPhysicalDeviceFormatProperties)      \
  X(EnumerateDeviceExtensionProperties)

// Core device-level functions (vkGetDeviceProcAddr with the host's device).
#define CANOPY_VK_DEVICE_FUNCTIONS(X)                                                            \
  X(GetDeviceQueue) X(QueueSubmit) X(QueueWaitIdle)                                              \
  X(AllocateMemory) X(FreeMemory) X(MapMemory) X(UnmapMemory)                                    \
  X(CreateBuffer) X(DestroyBuffer) X(GetBufferMemoryRequirements) X(BindBufferMemory)            \
  X(CreateImage) X(DestroyImage) X(GetImageMemoryRequirements) X(BindImageMemory)                \
  X(CreateImageView) X(DestroyImageView) X(CreateSampler) X(DestroySampler)                      \
  X(CreateShaderModule) X(DestroyShaderModule) X(CreateDescriptorSetLayout)                      \
  X(DestroyDescriptorSetLayout) X(CreatePipelineLayout) X(DestroyPipelineLayout)                 \
  X(CreateComputePipelines) X(CreateGraphicsPipelines) X(DestroyPipeline)                        \
  X(CreateQueryPool) X(DestroyQueryPool) X(GetQueryPoolResults)                                  \
  X(CreateCommandPool) X(DestroyCommandPool) X(ResetCommandPool) X(AllocateCommandBuffers)       \
  X(FreeCommandBuffers) X(BeginCommandBuffer) X(EndCommandBuffer)                                \
  X(CreateFence) X(DestroyFence) X(WaitForFences) X(ResetFences) X(GetFenceStatus)               \
  X(CmdBindPipeline) X(CmdPushConstants) X(CmdDispatch) X(CmdDispatchIndirect) X(CmdDraw) X(CmdDrawIndirect) X(CmdDrawIndexed)             \
  X(CmdBindVertexBuffers) X(CmdBindIndexBuffer) X(CmdSetViewport) X(CmdSetScissor) X(CmdSetBlendConstants) \
  X(CmdCopyBuffer) X(CmdCopyImage) X(CmdCopyBufferToImage) X(CmdCopyImageToBuffer) X(CmdUpdateBuffer)            \
  X(CmdFillBuffer) X(CmdClearColorImage) X(CmdClearDepthStencilImage)                            \
  X(CmdResetQueryPool) X(CmdWriteTimestamp) X(CmdBeginQuery) X(CmdEndQuery)

struct VulkanFunctions {
#define CANOPY_VK_MEMBER(name) PFN_vk##name name = nullptr;
  CANOPY_VK_INSTANCE_FUNCTIONS(CANOPY_VK_MEMBER)
  CANOPY_VK_DEVICE_FUNCTIONS(CANOPY_VK_MEMBER)
#undef CANOPY_VK_MEMBER
  // Core in 1.3, an extension on 1.2 (resolved under either name).
  PFN_vkCmdPipelineBarrier2 CmdPipelineBarrier2 = nullptr;
  PFN_vkCmdBeginRendering CmdBeginRendering = nullptr;
  PFN_vkCmdEndRendering CmdEndRendering = nullptr;
  PFN_vkCmdPushDescriptorSetKHR CmdPushDescriptorSetKHR = nullptr;
  PFN_vkSetDebugUtilsObjectNameEXT SetDebugUtilsObjectNameEXT = nullptr;  // optional
};

// Resolves the table. `core13`: the device runs Vulkan 1.3 (core names) rather than 1.2 + KHR.
// Returns "" or the name of the first entry point that could not be resolved.
std::string loadVulkanFunctions(PFN_vkGetInstanceProcAddr getInstanceProcAddr, VkInstance instance, VkDevice device,
                                bool core13, VulkanFunctions* out);
// The instance-level part only (to inspect a physical device before a VkDevice exists).
std::string loadInstanceFunctions(PFN_vkGetInstanceProcAddr getInstanceProcAddr, VkInstance instance,
                                  VulkanFunctions* out);

}  // namespace canopy
