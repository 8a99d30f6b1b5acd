#include "engine/graphics_pipeline.h"

#include "engine/device.h"
#include "engine/shader_registry.h"
#include "engine/spirv_reflect.h"

namespace canopy {
namespace {
constexpr VkShaderStageFlags kStages = VK_SHADER_STAGE_VERTEX_BIT | VK_SHADER_STAGE_FRAGMENT_BIT;

Status makeModule(Device& d, ShaderLookup lookup, const char* name, VkShaderModule* out, DescriptorTypes* bindings) {
  const EmbeddedShader* sh = name ? (lookup ? lookup : &findEmbeddedShader)(name) : nullptr;
  if (!sh) return Status::error(std::string("no embedded shader named '") + (name ? name : "") + "'");
  CANOPY_TRY(reflectDescriptors(sh->code, sh->sizeBytes / 4, bindings).context(name));
  VkShaderModuleCreateInfo mi{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  mi.codeSize = sh->sizeBytes;
  mi.pCode = sh->code;
  CANOPY_VK(d.vk.CreateShaderModule(d.device, &mi, d.allocationCallbacks, out));
  return Status();
}
}  // namespace

Status createGraphicsPipeline(Device& d, const GraphicsPipelineDesc& desc, GraphicsPipeline* out) {
  *out = GraphicsPipeline{};
  out->device = &d;
  const std::string what = std::string("graphics pipeline '") + (desc.vertexShader ? desc.vertexShader : "?") + "+" +
                           (desc.fragmentShader ? desc.fragmentShader : "?") + "'";
  if (desc.pushConstantSize > d.properties.limits.maxPushConstantsSize)
    return Status::error(what + ": push constants of " + std::to_string(desc.pushConstantSize) +
                         " bytes exceed the device limit " + std::to_string(d.properties.limits.maxPushConstantsSize));
  out->name = what;
  out->pushConstantSize = desc.pushConstantSize;
  VkShaderModule vs = VK_NULL_HANDLE, fs = VK_NULL_HANDLE;
  Status s = [&]() -> Status {
    DescriptorTypes vsBindings, fsBindings;
    CANOPY_TRY(makeModule(d, desc.shaderLookup, desc.vertexShader, &vs, &vsBindings));
    CANOPY_TRY(makeModule(d, desc.shaderLookup, desc.fragmentShader, &fs, &fsBindings));
    CANOPY_TRY(mergeDescriptors(vsBindings, fsBindings, what, &out->bindings));
    CANOPY_TRY(requireContiguous(out->bindings, what));
    CANOPY_TRY(createPushDescriptorLayouts(d, out->bindings, kStages, desc.pushConstantSize, &out->setLayout,
                                           &out->layout));

    VkPipelineShaderStageCreateInfo stages[2] = {{VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO},
                                                 {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO}};
    stages[0].stage = VK_SHADER_STAGE_VERTEX_BIT;
    stages[0].module = vs;
    stages[0].pName = "main";
    stages[1].stage = VK_SHADER_STAGE_FRAGMENT_BIT;
    stages[1].module = fs;
    stages[1].pName = "main";
    std::vector<VkSpecializationMapEntry> entries;
    VkSpecializationInfo spec{};
    stages[1].pSpecializationInfo = specializationOf(desc.fragmentSpecialization, &entries, &spec);

    std::vector<VkVertexInputBindingDescription> vb;
    if (desc.vertexStride) vb.push_back({0, desc.vertexStride, VK_VERTEX_INPUT_RATE_VERTEX});
    if (desc.instanceStride) vb.push_back({1, desc.instanceStride, VK_VERTEX_INPUT_RATE_INSTANCE});
    std::vector<VkVertexInputAttributeDescription> va;
    for (const VertexAttribute& a : desc.attributes) va.push_back({a.location, 0, a.format, a.offset});
    for (const VertexAttribute& a : desc.instanceAttributes) va.push_back({a.location, 1, a.format, a.offset});
    VkPipelineVertexInputStateCreateInfo vi{VK_STRUCTURE_TYPE_PIPELINE_VERTEX_INPUT_STATE_CREATE_INFO};
    vi.vertexBindingDescriptionCount = uint32_t(vb.size());
    vi.pVertexBindingDescriptions = vb.data();
    vi.vertexAttributeDescriptionCount = uint32_t(va.size());
    vi.pVertexAttributeDescriptions = va.data();
    VkPipelineInputAssemblyStateCreateInfo ia{VK_STRUCTURE_TYPE_PIPELINE_INPUT_ASSEMBLY_STATE_CREATE_INFO};
    ia.topology = VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST;
    VkPipelineViewportStateCreateInfo vp{VK_STRUCTURE_TYPE_PIPELINE_VIEWPORT_STATE_CREATE_INFO};
    vp.viewportCount = 1;
    vp.scissorCount = 1;
    VkPipelineRasterizationStateCreateInfo rs{VK_STRUCTURE_TYPE_PIPELINE_RASTERIZATION_STATE_CREATE_INFO};
    rs.polygonMode = VK_POLYGON_MODE_FILL;
    rs.cullMode = desc.cullMode;
    rs.frontFace = VK_FRONT_FACE_COUNTER_CLOCKWISE;
    rs.lineWidth = 1.0f;
    VkPipelineMultisampleStateCreateInfo ms{VK_STRUCTURE_TYPE_PIPELINE_MULTISAMPLE_STATE_CREATE_INFO};
    ms.rasterizationSamples = VK_SAMPLE_COUNT_1_BIT;
    VkPipelineDepthStencilStateCreateInfo ds{VK_STRUCTURE_TYPE_PIPELINE_DEPTH_STENCIL_STATE_CREATE_INFO};
    ds.depthTestEnable = desc.depthTest;
    ds.depthWriteEnable = desc.depthWrite;
    ds.depthCompareOp = desc.depthCompare;
    std::vector<VkPipelineColorBlendAttachmentState> att(desc.colorFormats.size());
    for (size_t i = 0; i < att.size(); ++i) {
      att[i] = {};
      att[i].colorWriteMask = desc.colorWrite ? VK_COLOR_COMPONENT_R_BIT | VK_COLOR_COMPONENT_G_BIT |
                                                    VK_COLOR_COMPONENT_B_BIT | VK_COLOR_COMPONENT_A_BIT
                                              : 0;
      if (i < desc.blendedAttachments && desc.blend == BlendMode::PremultipliedOver) {
        att[i].blendEnable = VK_TRUE;
        att[i].srcColorBlendFactor = VK_BLEND_FACTOR_ONE;
        att[i].dstColorBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
        att[i].colorBlendOp = VK_BLEND_OP_ADD;
        att[i].srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
        att[i].dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA;
        att[i].alphaBlendOp = VK_BLEND_OP_ADD;
      } else if (i < desc.blendedAttachments && desc.blend == BlendMode::ConstantMix) {
        att[i].blendEnable = VK_TRUE;
        att[i].srcColorBlendFactor = att[i].srcAlphaBlendFactor = VK_BLEND_FACTOR_ONE;
        att[i].dstColorBlendFactor = att[i].dstAlphaBlendFactor = VK_BLEND_FACTOR_ONE_MINUS_CONSTANT_ALPHA;
        att[i].colorBlendOp = att[i].alphaBlendOp = VK_BLEND_OP_ADD;
      }
    }
    VkPipelineColorBlendStateCreateInfo cb{VK_STRUCTURE_TYPE_PIPELINE_COLOR_BLEND_STATE_CREATE_INFO};
    cb.attachmentCount = uint32_t(att.size());
    cb.pAttachments = att.data();
    const VkDynamicState dyn[] = {VK_DYNAMIC_STATE_VIEWPORT, VK_DYNAMIC_STATE_SCISSOR, VK_DYNAMIC_STATE_BLEND_CONSTANTS};
    VkPipelineDynamicStateCreateInfo dy{VK_STRUCTURE_TYPE_PIPELINE_DYNAMIC_STATE_CREATE_INFO};
    dy.dynamicStateCount = desc.blend == BlendMode::ConstantMix ? 3 : 2;
    dy.pDynamicStates = dyn;
    VkPipelineRenderingCreateInfo ri{VK_STRUCTURE_TYPE_PIPELINE_RENDERING_CREATE_INFO};
    ri.colorAttachmentCount = uint32_t(desc.colorFormats.size());
    ri.pColorAttachmentFormats = desc.colorFormats.data();
    ri.depthAttachmentFormat = desc.depthFormat;

    VkGraphicsPipelineCreateInfo ci{VK_STRUCTURE_TYPE_GRAPHICS_PIPELINE_CREATE_INFO, &ri};
    ci.stageCount = 2;
    ci.pStages = stages;
    ci.pVertexInputState = &vi;
    ci.pInputAssemblyState = &ia;
    ci.pViewportState = &vp;
    ci.pRasterizationState = &rs;
    ci.pMultisampleState = &ms;
    ci.pDepthStencilState = &ds;
    ci.pColorBlendState = &cb;
    ci.pDynamicState = &dy;
    ci.layout = out->layout;
    CANOPY_VK(d.vk.CreateGraphicsPipelines(d.device, d.pipelineCache, 1, &ci, d.allocationCallbacks, &out->pipeline));
    setDebugName(d, VK_OBJECT_TYPE_PIPELINE, uint64_t(out->pipeline), what.c_str());
    return Status();
  }();
  if (vs) d.vk.DestroyShaderModule(d.device, vs, d.allocationCallbacks);
  if (fs) d.vk.DestroyShaderModule(d.device, fs, d.allocationCallbacks);
  if (!s.ok()) {
    destroyGraphicsPipeline(d, *out);
    return s.context(what);
  }
  return Status();
}

void destroyGraphicsPipeline(Device& d, GraphicsPipeline& p) {
  if (p.pipeline) d.vk.DestroyPipeline(d.device, p.pipeline, d.allocationCallbacks);
  if (p.layout) d.vk.DestroyPipelineLayout(d.device, p.layout, d.allocationCallbacks);
  if (p.setLayout) d.vk.DestroyDescriptorSetLayout(d.device, p.setLayout, d.allocationCallbacks);
  p = GraphicsPipeline{};
}

Status pushGraphicsConstants(VkCommandBuffer cmd, const GraphicsPipeline& p, const void* push, uint32_t pushSize) {
  if (pushSize != p.pushConstantSize)
    return Status::error(p.name + ": push constants are " + std::to_string(pushSize) + " bytes, the pipeline declares " +
                         std::to_string(p.pushConstantSize));
  if (pushSize) p.device->vk.CmdPushConstants(cmd, p.layout, kStages, 0, pushSize, push);
  return Status();
}

namespace {
Status bindGraphicsList(Device& d, VkCommandBuffer cmd, const GraphicsPipeline& p, const Binding* bindings, size_t count,
                        const void* push, uint32_t pushSize) {
  if (pushSize != p.pushConstantSize) return pushGraphicsConstants(cmd, p, push, pushSize);
  d.vk.CmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.pipeline);
  CANOPY_TRY(pushDescriptors(d, cmd, VK_PIPELINE_BIND_POINT_GRAPHICS, p.layout, p.bindings, bindings, count, p.name));
  return pushGraphicsConstants(cmd, p, push, pushSize);
}
}  // namespace

Status bindGraphics(Device& d, VkCommandBuffer cmd, const GraphicsPipeline& p, std::initializer_list<Binding> bindings,
                    const void* push, uint32_t pushSize) {
  return bindGraphicsList(d, cmd, p, bindings.begin(), bindings.size(), push, pushSize);
}
Status bindGraphics(Device& d, VkCommandBuffer cmd, const GraphicsPipeline& p, const std::vector<Binding>& bindings,
                    const void* push, uint32_t pushSize) {
  return bindGraphicsList(d, cmd, p, bindings.data(), bindings.size(), push, pushSize);
}

void setViewportScissor(const Device& d, VkCommandBuffer cmd, uint32_t width, uint32_t height) {
  VkViewport v{0.0f, 0.0f, float(width), float(height), 0.0f, 1.0f};
  VkRect2D r{{0, 0}, {width, height}};
  d.vk.CmdSetViewport(cmd, 0, 1, &v);
  d.vk.CmdSetScissor(cmd, 0, 1, &r);
}

}  // namespace canopy
