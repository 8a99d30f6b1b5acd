#include "engine/pipeline.h"

#include "engine/device.h"
#include "engine/shader_registry.h"
#include "engine/spirv_reflect.h"

namespace canopy {

bool spirvLocalSize(const uint32_t* code, size_t words, uint32_t out[3]) {
  if (words < 5 || code[0] != 0x07230203u) return false;
  for (size_t i = 5; i < words;) {
    const uint32_t op = code[i] & 0xffffu, len = code[i] >> 16;
    if (len == 0 || i + len > words) return false;
    // OpExecutionMode (16) %entry LocalSize (17) x y z
    if (op == 16 && len >= 6 && code[i + 2] == 17) {
      out[0] = code[i + 3];
      out[1] = code[i + 4];
      out[2] = code[i + 5];
      return true;
    }
    i += len;
  }
  return false;
}

Status createPushDescriptorLayouts(Device& d, const std::vector<VkDescriptorType>& bindings, VkShaderStageFlags stages,
                                   uint32_t pushConstantSize, VkDescriptorSetLayout* setLayout, VkPipelineLayout* layout) {
  std::vector<VkDescriptorSetLayoutBinding> b(bindings.size());
  for (size_t i = 0; i < b.size(); ++i) b[i] = {uint32_t(i), bindings[i], 1, stages, nullptr};
  VkDescriptorSetLayoutCreateInfo sl{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  sl.flags = VK_DESCRIPTOR_SET_LAYOUT_CREATE_PUSH_DESCRIPTOR_BIT_KHR;
  sl.bindingCount = uint32_t(b.size());
  sl.pBindings = b.data();
  CANOPY_VK(d.vk.CreateDescriptorSetLayout(d.device, &sl, d.allocationCallbacks, setLayout));
  VkPushConstantRange pr{stages, 0, pushConstantSize};
  VkPipelineLayoutCreateInfo pl{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  pl.setLayoutCount = 1;
  pl.pSetLayouts = setLayout;
  pl.pushConstantRangeCount = pushConstantSize ? 1 : 0;
  pl.pPushConstantRanges = &pr;
  CANOPY_VK(d.vk.CreatePipelineLayout(d.device, &pl, d.allocationCallbacks, layout));
  return Status();
}

const VkSpecializationInfo* specializationOf(const std::vector<uint32_t>& values, std::vector<VkSpecializationMapEntry>* entries,
                                             VkSpecializationInfo* info) {
  if (values.empty()) return nullptr;
  entries->resize(values.size());
  for (size_t i = 0; i < values.size(); ++i) (*entries)[i] = {uint32_t(i), uint32_t(i * 4), 4};
  *info = {uint32_t(entries->size()), entries->data(), values.size() * 4, values.data()};
  return info;
}

Status createComputePipeline(Device& d, const ComputePipelineDesc& desc, ComputePipeline* out) {
  *out = ComputePipeline{};
  const EmbeddedShader* sh = desc.shader ? (desc.shaderLookup ? desc.shaderLookup : &findEmbeddedShader)(desc.shader) : nullptr;
  if (!sh) return Status::error(std::string("no embedded shader named '") + (desc.shader ? desc.shader : "") + "'");
  const std::string what = std::string("compute pipeline '") + desc.shader + "'";
  if (!spirvLocalSize(sh->code, sh->sizeBytes / 4, out->localSize))
    return Status::error(what + ": no LocalSize execution mode in the SPIR-V");
  if (desc.pushConstantSize > d.properties.limits.maxPushConstantsSize)
    return Status::error(what + ": push constants of " + std::to_string(desc.pushConstantSize) +
                         " bytes exceed the device limit " + std::to_string(d.properties.limits.maxPushConstantsSize));
  if (desc.workgroupXFromSpec) {
    if (desc.specialization.empty() || desc.specialization[0] < 1 ||
        desc.specialization[0] > d.properties.limits.maxComputeWorkGroupSize[0] ||
        desc.specialization[0] > d.properties.limits.maxComputeWorkGroupInvocations)
      return Status::error(what + ": workgroup width " +
                           (desc.specialization.empty() ? std::string("missing") : std::to_string(desc.specialization[0])) +
                           " is outside 1.." + std::to_string(d.properties.limits.maxComputeWorkGroupInvocations));
    out->localSize[0] = desc.specialization[0];
  }
  out->name = desc.shader;
  CANOPY_TRY(reflectDescriptors(sh->code, sh->sizeBytes / 4, &out->bindings).context(what));
  CANOPY_TRY(requireContiguous(out->bindings, what));
  out->pushConstantSize = desc.pushConstantSize;

  Status s = [&]() -> Status {
    CANOPY_TRY(createPushDescriptorLayouts(d, out->bindings, VK_SHADER_STAGE_COMPUTE_BIT, desc.pushConstantSize,
                                           &out->setLayout, &out->layout));
    VkShaderModuleCreateInfo mi{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
    mi.codeSize = sh->sizeBytes;
    mi.pCode = sh->code;
    VkShaderModule module;
    CANOPY_VK(d.vk.CreateShaderModule(d.device, &mi, d.allocationCallbacks, &module));
    VkComputePipelineCreateInfo ci{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
    ci.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO};
    ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
    ci.stage.module = module;
    ci.stage.pName = "main";
    std::vector<VkSpecializationMapEntry> entries;
    VkSpecializationInfo spec{};
    ci.stage.pSpecializationInfo = specializationOf(desc.specialization, &entries, &spec);
    ci.layout = out->layout;
    VkResult r = d.vk.CreateComputePipelines(d.device, d.pipelineCache, 1, &ci, d.allocationCallbacks, &out->pipeline);
    d.vk.DestroyShaderModule(d.device, module, d.allocationCallbacks);
    if (r != VK_SUCCESS) return vkError("vkCreateComputePipelines", r);
    setDebugName(d, VK_OBJECT_TYPE_PIPELINE, uint64_t(out->pipeline), desc.shader);
    return Status();
  }();
  if (!s.ok()) {
    destroyComputePipeline(d, *out);
    return s.context(what);
  }
  return Status();
}

void destroyComputePipeline(Device& d, ComputePipeline& p) {
  if (p.pipeline) d.vk.DestroyPipeline(d.device, p.pipeline, d.allocationCallbacks);
  if (p.layout) d.vk.DestroyPipelineLayout(d.device, p.layout, d.allocationCallbacks);
  if (p.setLayout) d.vk.DestroyDescriptorSetLayout(d.device, p.setLayout, d.allocationCallbacks);
  p = ComputePipeline{};
}

Status pushDescriptors(Device& d, VkCommandBuffer cmd, VkPipelineBindPoint bindPoint, VkPipelineLayout layout,
                       const std::vector<VkDescriptorType>& types, const Binding* bindings, size_t count,
                       const std::string& what) {
  if (count != types.size())
    return Status::error(what + ": " + std::to_string(count) + " bindings given, " + std::to_string(types.size()) +
                         " declared");
  std::vector<VkWriteDescriptorSet> writes(count);
  std::vector<VkDescriptorBufferInfo> bufs(count);
  std::vector<VkDescriptorImageInfo> imgs(count);
  for (size_t i = 0; i < count; ++i) {
    const Binding& b = bindings[i];
    VkWriteDescriptorSet& w = writes[i];
    w = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    w.dstBinding = uint32_t(i);
    w.descriptorCount = 1;
    w.descriptorType = types[i];
    switch (types[i]) {
      case VK_DESCRIPTOR_TYPE_STORAGE_BUFFER:
      case VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER:
        if (!b.buffer) return Status::error(what + ": binding " + std::to_string(i) + " needs a buffer");
        bufs[i] = {b.buffer, b.offset, b.range};
        w.pBufferInfo = &bufs[i];
        break;
      default:
        if (!b.view) return Status::error(what + ": binding " + std::to_string(i) + " needs an image view");
        if (types[i] == VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER && !b.sampler)
          return Status::error(what + ": binding " + std::to_string(i) + " needs a sampler");
        imgs[i] = {b.sampler, b.view, b.layout};
        w.pImageInfo = &imgs[i];
        break;
    }
  }
  if (!writes.empty()) d.cmdPushDescriptorSet(cmd, bindPoint, layout, 0, uint32_t(writes.size()), writes.data());
  return Status();
}

namespace {
Status bindCompute(Device& d, VkCommandBuffer cmd, const ComputePipeline& p, const Binding* bindings, size_t count,
                   const void* push, uint32_t pushSize) {
  if (pushSize != p.pushConstantSize)
    return Status::error("dispatch '" + p.name + "': push constants are " + std::to_string(pushSize) +
                         " bytes, the pipeline declares " + std::to_string(p.pushConstantSize));
  if (count != p.bindings.size())
    return Status::error("dispatch '" + p.name + "': " + std::to_string(count) + " bindings given, " +
                         std::to_string(p.bindings.size()) + " declared");
  d.vk.CmdBindPipeline(cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.pipeline);
  CANOPY_TRY(pushDescriptors(d, cmd, VK_PIPELINE_BIND_POINT_COMPUTE, p.layout, p.bindings, bindings, count,
                             "dispatch '" + p.name + "'"));
  if (pushSize) d.vk.CmdPushConstants(cmd, p.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, pushSize, push);
  return Status();
}

Status dispatchList(Device& d, VkCommandBuffer cmd, const ComputePipeline& p, uint32_t tx, uint32_t ty, uint32_t tz,
                    const Binding* bindings, size_t count, const void* push, uint32_t pushSize) {
  CANOPY_TRY(bindCompute(d, cmd, p, bindings, count, push, pushSize));
  auto groups = [](uint32_t n, uint32_t l) { return (n + l - 1) / l; };
  d.vk.CmdDispatch(cmd, groups(tx, p.localSize[0]), groups(ty, p.localSize[1]), groups(tz, p.localSize[2]));
  return Status();
}

Status dispatchIndirectList(Device& d, VkCommandBuffer cmd, const ComputePipeline& p, VkBuffer args, VkDeviceSize offset,
                            const Binding* bindings, size_t count, const void* push, uint32_t pushSize) {
  CANOPY_TRY(bindCompute(d, cmd, p, bindings, count, push, pushSize));
  d.vk.CmdDispatchIndirect(cmd, args, offset);
  return Status();
}
}  // namespace

Status dispatch(Device& d, VkCommandBuffer cmd, const ComputePipeline& p, uint32_t tx, uint32_t ty, uint32_t tz,
                std::initializer_list<Binding> bindings, const void* push, uint32_t pushSize) {
  return dispatchList(d, cmd, p, tx, ty, tz, bindings.begin(), bindings.size(), push, pushSize);
}
Status dispatch(Device& d, VkCommandBuffer cmd, const ComputePipeline& p, uint32_t tx, uint32_t ty, uint32_t tz,
                const std::vector<Binding>& bindings, const void* push, uint32_t pushSize) {
  return dispatchList(d, cmd, p, tx, ty, tz, bindings.data(), bindings.size(), push, pushSize);
}

Status dispatchIndirect(Device& d, VkCommandBuffer cmd, const ComputePipeline& p, VkBuffer args, VkDeviceSize offset,
                        std::initializer_list<Binding> bindings, const void* push, uint32_t pushSize) {
  return dispatchIndirectList(d, cmd, p, args, offset, bindings.begin(), bindings.size(), push, pushSize);
}
Status dispatchIndirect(Device& d, VkCommandBuffer cmd, const ComputePipeline& p, VkBuffer args, VkDeviceSize offset,
                        const std::vector<Binding>& bindings, const void* push, uint32_t pushSize) {
  return dispatchIndirectList(d, cmd, p, args, offset, bindings.data(), bindings.size(), push, pushSize);
}

}  // namespace canopy
