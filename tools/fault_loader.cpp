#include "tools/fault_loader.h"

#include <atomic>
#include <cstring>

namespace canopy::fault {
namespace {

std::atomic<int> g_mode{int(Mode::Off)};
std::atomic<int64_t> g_left{0}, g_calls{0}, g_live{0};
std::atomic<bool> g_triggered{false};
PFN_vkGetInstanceProcAddr g_real = nullptr;
PFN_vkGetDeviceProcAddr g_realDevice = nullptr;
PFN_vkQueueSubmit g_realSubmit = nullptr;

// One creation or allocation: VK_SUCCESS to go ahead, else the injected error.
VkResult gate() {
  g_calls++;
  const Mode m = Mode(g_mode.load());
  if (m == Mode::Off) return VK_SUCCESS;
  if (g_left.fetch_sub(1) > 0) return VK_SUCCESS;
  g_triggered = true;
  return m == Mode::OutOfMemory ? VK_ERROR_OUT_OF_DEVICE_MEMORY : VK_ERROR_DEVICE_LOST;
}
// After a device loss every submission and wait fails too.
VkResult lost() { return Mode(g_mode.load()) == Mode::DeviceLost && g_triggered ? VK_ERROR_DEVICE_LOST : VK_SUCCESS; }

#define REAL(name) reinterpret_cast<PFN_vk##name>(g_realDevice(device, "vk" #name))

// Creation functions: gated, counted when they succeed.
#define CREATE(name, Info, Handle)                                                                      \
  VKAPI_ATTR VkResult VKAPI_CALL name(VkDevice device, const Info* info, const VkAllocationCallbacks* cb, \
                                      Handle* out) {                                                    \
    if (VkResult r = gate(); r != VK_SUCCESS) return r;                                                 \
    const VkResult r = REAL(name)(device, info, cb, out);                                               \
    if (r == VK_SUCCESS) g_live++;                                                                      \
    return r;                                                                                           \
  }
#define DESTROY(name, Handle)                                                                           \
  VKAPI_ATTR void VKAPI_CALL name(VkDevice device, Handle h, const VkAllocationCallbacks* cb) {          \
    if (h) g_live--;                                                                                    \
    REAL(name)(device, h, cb);                                                                          \
  }
CREATE(AllocateMemory, VkMemoryAllocateInfo, VkDeviceMemory)
DESTROY(FreeMemory, VkDeviceMemory)
CREATE(CreateBuffer, VkBufferCreateInfo, VkBuffer)
DESTROY(DestroyBuffer, VkBuffer)
CREATE(CreateImage, VkImageCreateInfo, VkImage)
DESTROY(DestroyImage, VkImage)
CREATE(CreateImageView, VkImageViewCreateInfo, VkImageView)
DESTROY(DestroyImageView, VkImageView)
CREATE(CreateSampler, VkSamplerCreateInfo, VkSampler)
DESTROY(DestroySampler, VkSampler)
CREATE(CreateShaderModule, VkShaderModuleCreateInfo, VkShaderModule)
DESTROY(DestroyShaderModule, VkShaderModule)
CREATE(CreateDescriptorSetLayout, VkDescriptorSetLayoutCreateInfo, VkDescriptorSetLayout)
DESTROY(DestroyDescriptorSetLayout, VkDescriptorSetLayout)
CREATE(CreatePipelineLayout, VkPipelineLayoutCreateInfo, VkPipelineLayout)
DESTROY(DestroyPipelineLayout, VkPipelineLayout)
CREATE(CreateCommandPool, VkCommandPoolCreateInfo, VkCommandPool)
DESTROY(DestroyCommandPool, VkCommandPool)
CREATE(CreateFence, VkFenceCreateInfo, VkFence)
DESTROY(DestroyFence, VkFence)
CREATE(CreateQueryPool, VkQueryPoolCreateInfo, VkQueryPool)
DESTROY(DestroyQueryPool, VkQueryPool)
DESTROY(DestroyPipeline, VkPipeline)

VKAPI_ATTR VkResult VKAPI_CALL CreateComputePipelines(VkDevice device, VkPipelineCache cache, uint32_t n,
                                                      const VkComputePipelineCreateInfo* info,
                                                      const VkAllocationCallbacks* cb, VkPipeline* out) {
  if (VkResult r = gate(); r != VK_SUCCESS) return r;
  const VkResult r = REAL(CreateComputePipelines)(device, cache, n, info, cb, out);
  if (r == VK_SUCCESS) g_live += n;
  return r;
}
VKAPI_ATTR VkResult VKAPI_CALL CreateGraphicsPipelines(VkDevice device, VkPipelineCache cache, uint32_t n,
                                                       const VkGraphicsPipelineCreateInfo* info,
                                                       const VkAllocationCallbacks* cb, VkPipeline* out) {
  if (VkResult r = gate(); r != VK_SUCCESS) return r;
  const VkResult r = REAL(CreateGraphicsPipelines)(device, cache, n, info, cb, out);
  if (r == VK_SUCCESS) g_live += n;
  return r;
}
VKAPI_ATTR VkResult VKAPI_CALL QueueSubmit(VkQueue queue, uint32_t n, const VkSubmitInfo* s, VkFence fence) {
  if (VkResult r = lost(); r != VK_SUCCESS) return r;
  return g_realSubmit(queue, n, s, fence);
}
VKAPI_ATTR VkResult VKAPI_CALL WaitForFences(VkDevice device, uint32_t n, const VkFence* f, VkBool32 all, uint64_t t) {
  if (VkResult r = lost(); r != VK_SUCCESS) return r;
  return REAL(WaitForFences)(device, n, f, all, t);
}

PFN_vkVoidFunction wrapped(const char* name) {
#define W(fn) \
  if (std::strcmp(name, "vk" #fn) == 0) return reinterpret_cast<PFN_vkVoidFunction>(&fn);
  W(AllocateMemory) W(FreeMemory) W(CreateBuffer) W(DestroyBuffer) W(CreateImage) W(DestroyImage)
  W(CreateImageView) W(DestroyImageView) W(CreateSampler) W(DestroySampler) W(CreateShaderModule)
  W(DestroyShaderModule) W(CreateDescriptorSetLayout) W(DestroyDescriptorSetLayout) W(CreatePipelineLayout)
  W(DestroyPipelineLayout) W(CreateCommandPool) W(DestroyCommandPool) W(CreateFence) W(DestroyFence)
  W(CreateQueryPool) W(DestroyQueryPool) W(DestroyPipeline) W(CreateComputePipelines) W(CreateGraphicsPipelines)
  W(QueueSubmit) W(WaitForFences)
#undef W
  return nullptr;
}

VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL GetDeviceProcAddr(VkDevice device, const char* name) {
  if (std::strcmp(name, "vkQueueSubmit") == 0) g_realSubmit = reinterpret_cast<PFN_vkQueueSubmit>(g_realDevice(device, name));
  if (PFN_vkVoidFunction w = wrapped(name)) return g_realDevice(device, name) ? w : nullptr;
  return g_realDevice(device, name);
}
VKAPI_ATTR PFN_vkVoidFunction VKAPI_CALL GetInstanceProcAddr(VkInstance instance, const char* name) {
  if (std::strcmp(name, "vkGetDeviceProcAddr") == 0) {
    g_realDevice = reinterpret_cast<PFN_vkGetDeviceProcAddr>(g_real(instance, name));
    return reinterpret_cast<PFN_vkVoidFunction>(&GetDeviceProcAddr);
  }
  return g_real(instance, name);
}

}  // namespace

void arm(Mode mode, int64_t successes) {
  g_left = successes;
  g_calls = 0;
  g_triggered = false;
  g_mode = int(mode);
}
int64_t calls() { return g_calls; }
int64_t liveObjects() { return g_live; }
bool triggered() { return g_triggered; }

PFN_vkGetInstanceProcAddr loader(PFN_vkGetInstanceProcAddr real) {
  g_real = real;
  return &GetInstanceProcAddr;
}

bool parse(const std::string& spec, Mode* mode, int64_t* successes) {
  const size_t colon = spec.find(':');
  if (colon == std::string::npos) return false;
  const std::string kind = spec.substr(0, colon), n = spec.substr(colon + 1);
  if (n.empty() || n.find_first_not_of("0123456789") != std::string::npos || n.size() > 12) return false;
  if (kind == "oom") *mode = Mode::OutOfMemory;
  else if (kind == "lost") *mode = Mode::DeviceLost;
  else return false;
  *successes = std::stoll(n);
  return true;
}

}  // namespace canopy::fault
