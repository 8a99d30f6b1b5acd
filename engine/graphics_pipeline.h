#pragma once
// Graphics pipelines for dynamic rendering (no render-pass objects): vertex + fragment shader from
// the embedded SPIR-V, push descriptors (one set, read from the SPIR-V) and push constants visible to both stages,
// dynamic viewport and scissor.
#include <initializer_list>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/pipeline.h"
#include "engine/status.h"

namespace canopy {
struct Device;

struct VertexAttribute {
  uint32_t location = 0;
  VkFormat format = VK_FORMAT_UNDEFINED;
  uint32_t offset = 0;  // bytes into its (interleaved) stream
};

// ConstantMix: result = source + destination * (1 - blend-constant alpha), the constant set per
// draw (vkCmdSetBlendConstants, a dynamic state of these pipelines): a cross-fade whose shader
// writes the new value already weighted.
enum class BlendMode { None, PremultipliedOver, ConstantMix };

struct GraphicsPipelineDesc {
  const char* vertexShader = nullptr;    // embedded shader names, e.g. "layers.vert"
  const char* fragmentShader = nullptr;
  ShaderLookup shaderLookup = nullptr;   // where the names are looked up; null: Canopy's shaders
  uint32_t pushConstantSize = 0;
  uint32_t vertexStride = 0;
  std::vector<VertexAttribute> attributes;
  // A second stream, binding 1, advanced per draw instance (VK_VERTEX_INPUT_RATE_INSTANCE); 0: none.
  // Per-instance data goes here rather than in a storage buffer indexed by gl_InstanceIndex, which
  // lavapipe gathers lane by lane (docs/lab/performance-notebook.md "Instances as a vertex stream").
  uint32_t instanceStride = 0;
  std::vector<VertexAttribute> instanceAttributes;
  std::vector<VkFormat> colorFormats;    // one per colour attachment
  VkFormat depthFormat = VK_FORMAT_UNDEFINED;
  BlendMode blend = BlendMode::None;
  uint32_t blendedAttachments = 1;       // blend applies to colour attachments [0, this)
  bool depthTest = true, depthWrite = true;
  bool colorWrite = true;                // false: colour write mask 0 on every attachment (a depth-only pass)
  VkCompareOp depthCompare = VK_COMPARE_OP_LESS;
  VkCullModeFlags cullMode = VK_CULL_MODE_NONE;
  // The fragment stage's specialization constants: value i for constant_id i (32-bit); empty: the
  // shader's defaults.
  std::vector<uint32_t> fragmentSpecialization;
};

struct GraphicsPipeline {
  const Device* device = nullptr;  // whose entry points record it
  VkPipeline pipeline = VK_NULL_HANDLE;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkDescriptorSetLayout setLayout = VK_NULL_HANDLE;
  std::vector<VkDescriptorType> bindings;  // binding i of set 0: the two stages' SPIR-V merged
  uint32_t pushConstantSize = 0;
  std::string name;
};

// The set layout is the union of the two shaders' declared bindings (engine/spirv_reflect.h),
// visible to both stages; a binding typed differently in the two, or a gap, is refused.
Status createGraphicsPipeline(Device& device, const GraphicsPipelineDesc& desc, GraphicsPipeline* out);
void destroyGraphicsPipeline(Device& device, GraphicsPipeline& pipeline);

// Binds the pipeline and pushes its descriptors and constants (refusing a size or count mismatch).
Status bindGraphics(Device& device, VkCommandBuffer cmd, const GraphicsPipeline& pipeline,
                    std::initializer_list<Binding> bindings, const void* push, uint32_t pushSize);
Status bindGraphics(Device& device, VkCommandBuffer cmd, const GraphicsPipeline& pipeline,
                    const std::vector<Binding>& bindings, const void* push, uint32_t pushSize);
template <class Push>
Status bindGraphics(Device& device, VkCommandBuffer cmd, const GraphicsPipeline& pipeline,
                    std::initializer_list<Binding> bindings, const Push& push) {
  return bindGraphics(device, cmd, pipeline, bindings, &push, uint32_t(sizeof(Push)));
}
// Pushes constants only (same pipeline, next draw); refuses a size mismatch.
Status pushGraphicsConstants(VkCommandBuffer cmd, const GraphicsPipeline& pipeline, const void* push, uint32_t pushSize);

// Sets a full-target viewport (y down, depth 0..1) and scissor.
void setViewportScissor(const Device& device, VkCommandBuffer cmd, uint32_t width, uint32_t height);

}  // namespace canopy
