#pragma once
// Compute pipelines from the embedded SPIR-V (graphics pipelines: engine/graphics_pipeline.h).
// Descriptors are push descriptors (VK_KHR_push_descriptor): one set, no pools to manage. The set
// layout is read from the shader's SPIR-V (engine/spirv_reflect.h), never typed in C++.
#include <cstring>
#include <initializer_list>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/status.h"

namespace canopy {
struct Device;
struct EmbeddedShader;
// A registry of embedded SPIR-V (engine/shader_registry.h): Canopy's own (findEmbeddedShader) or
// another library's, such as the tests' shaders (tools/test_shaders.h).
using ShaderLookup = const EmbeddedShader* (*)(const char* name);

struct ComputePipeline {
  VkPipeline pipeline = VK_NULL_HANDLE;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkDescriptorSetLayout setLayout = VK_NULL_HANDLE;
  std::vector<VkDescriptorType> bindings;  // binding i of set 0, as the SPIR-V declares it
  uint32_t pushConstantSize = 0;
  uint32_t localSize[3] = {1, 1, 1};  // read from the SPIR-V
  std::string name;
};

struct ComputePipelineDesc {
  const char* shader = nullptr;               // embedded shader name, e.g. "sim_tile.comp"
  uint32_t pushConstantSize = 0;              // sizeof the shared push-constant struct
  // Specialization constants: value i for constant_id i (32-bit). A shader declaring
  // local_size_x_id = 0 takes its workgroup width from specialization[0]: set workgroupXFromSpec.
  std::vector<uint32_t> specialization;
  bool workgroupXFromSpec = false;
  ShaderLookup shaderLookup = nullptr;        // where `shader` is looked up; null: Canopy's shaders
};

// One descriptor for a push: a buffer range, a storage/sampled image view, or both with a sampler.
struct Binding {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceSize offset = 0;
  VkDeviceSize range = VK_WHOLE_SIZE;
  VkImageView view = VK_NULL_HANDLE;
  VkImageLayout layout = VK_IMAGE_LAYOUT_GENERAL;
  VkSampler sampler = VK_NULL_HANDLE;
};
inline Binding bindBuffer(VkBuffer b, VkDeviceSize offset = 0, VkDeviceSize range = VK_WHOLE_SIZE) {
  Binding x;
  x.buffer = b;
  x.offset = offset;
  x.range = range;
  return x;
}
inline Binding bindImage(VkImageView v, VkImageLayout layout = VK_IMAGE_LAYOUT_GENERAL, VkSampler s = VK_NULL_HANDLE) {
  Binding x;
  x.view = v;
  x.layout = layout;
  x.sampler = s;
  return x;
}

// The set layout (push descriptors, binding i typed by bindings[i]) and pipeline layout (one push
// constant range of pushConstantSize bytes) shared by compute and graphics pipelines. On failure
// whatever was created is left in the outputs for the caller's destroy function.
Status createPushDescriptorLayouts(Device& device, const std::vector<VkDescriptorType>& bindings,
                                   VkShaderStageFlags stages, uint32_t pushConstantSize,
                                   VkDescriptorSetLayout* setLayout, VkPipelineLayout* layout);

// Reads the workgroup size (OpExecutionMode LocalSize) from SPIR-V; false if absent/malformed.
// A stage's specialization constants, value i for constant_id i (32-bit), as the create info's
// pointer: null for none; `entries` and `info` hold what it points to.
const VkSpecializationInfo* specializationOf(const std::vector<uint32_t>& values, std::vector<VkSpecializationMapEntry>* entries,
                                             VkSpecializationInfo* info);

bool spirvLocalSize(const uint32_t* code, size_t words, uint32_t out[3]);

Status createComputePipeline(Device& device, const ComputePipelineDesc& desc, ComputePipeline* out);
void destroyComputePipeline(Device& device, ComputePipeline& pipeline);

// Writes `bindings` (binding i of set 0, typed by `types`) as push descriptors; refuses a count
// mismatch or a binding without the buffer/view/sampler its type needs. `what` prefixes errors.
Status pushDescriptors(Device& device, VkCommandBuffer cmd, VkPipelineBindPoint bindPoint, VkPipelineLayout layout,
                       const std::vector<VkDescriptorType>& types, const Binding* bindings, size_t count,
                       const std::string& what);

// Binds, pushes descriptors and constants, and dispatches enough workgroups to cover `threads`
// invocations per axis. Refuses (records nothing) when the push-constant size or the binding
// count differs from the pipeline's declaration.
Status dispatch(Device& device, VkCommandBuffer cmd, const ComputePipeline& pipeline, uint32_t threadsX,
                uint32_t threadsY, uint32_t threadsZ, std::initializer_list<Binding> bindings, const void* push,
                uint32_t pushSize);
// The same with a built list (a pass's slots, engine/pass_slots.h).
Status dispatch(Device& device, VkCommandBuffer cmd, const ComputePipeline& pipeline, uint32_t threadsX,
                uint32_t threadsY, uint32_t threadsZ, const std::vector<Binding>& bindings, const void* push,
                uint32_t pushSize);

template <class Push>
Status dispatch(Device& device, VkCommandBuffer cmd, const ComputePipeline& pipeline, uint32_t tx, uint32_t ty,
                uint32_t tz, std::initializer_list<Binding> bindings, const Push& push) {
  return dispatch(device, cmd, pipeline, tx, ty, tz, bindings, &push, uint32_t(sizeof(Push)));
}

// As dispatch(), with the workgroup counts read by the GPU from `args` at `offset`
// (VkDispatchIndirectCommand, written by an earlier pass).
Status dispatchIndirect(Device& device, VkCommandBuffer cmd, const ComputePipeline& pipeline, VkBuffer args,
                        VkDeviceSize offset, std::initializer_list<Binding> bindings, const void* push, uint32_t pushSize);
Status dispatchIndirect(Device& device, VkCommandBuffer cmd, const ComputePipeline& pipeline, VkBuffer args,
                        VkDeviceSize offset, const std::vector<Binding>& bindings, const void* push, uint32_t pushSize);
template <class Push>
Status dispatchIndirect(Device& device, VkCommandBuffer cmd, const ComputePipeline& pipeline, VkBuffer args,
                        VkDeviceSize offset, std::initializer_list<Binding> bindings, const Push& push) {
  return dispatchIndirect(device, cmd, pipeline, args, offset, bindings, &push, uint32_t(sizeof(Push)));
}

}  // namespace canopy
