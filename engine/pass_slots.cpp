#include "engine/pass_slots.h"

#include <utility>

#include "engine/device.h"
#include "engine/spirv_reflect.h"

namespace canopy::rg {
namespace {

const char* useName(Use u) {
  switch (u) {
    case Use::ComputeStorageRead: return "ComputeStorageRead";
    case Use::ComputeStorageWrite: return "ComputeStorageWrite";
    case Use::ComputeStorageReadWrite: return "ComputeStorageReadWrite";
    case Use::ComputeSampled: return "ComputeSampled";
    case Use::ComputeUniform: return "ComputeUniform";
    case Use::FragmentSampled: return "FragmentSampled";
    case Use::FragmentStorageRead: return "FragmentStorageRead";
    case Use::FragmentUniform: return "FragmentUniform";
    case Use::VertexStorageRead: return "VertexStorageRead";
    default: return "a use no descriptor has";
  }
}

// Whether a shader binding of type `t` can be what the slot declares: a storage buffer is read or
// written as storage, a sampled image sampled, a storage image read or written as storage.
bool fits(VkDescriptorType t, Use u) {
  switch (t) {
    case VK_DESCRIPTOR_TYPE_STORAGE_BUFFER:
      return u == Use::ComputeStorageRead || u == Use::ComputeStorageWrite || u == Use::ComputeStorageReadWrite ||
             u == Use::VertexStorageRead || u == Use::FragmentStorageRead;
    case VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER: return u == Use::ComputeUniform || u == Use::FragmentUniform;
    case VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER:
    case VK_DESCRIPTOR_TYPE_SAMPLED_IMAGE: return u == Use::ComputeSampled || u == Use::FragmentSampled;
    case VK_DESCRIPTOR_TYPE_STORAGE_IMAGE:
      return u == Use::ComputeStorageRead || u == Use::ComputeStorageWrite || u == Use::ComputeStorageReadWrite;
    default: return false;
  }
}

bool isBufferType(VkDescriptorType t) {
  return t == VK_DESCRIPTOR_TYPE_STORAGE_BUFFER || t == VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
}

}  // namespace

Slot slot(ResourceId id, Use use, VkSampler sampler) {
  Slot s;
  s.id = id;
  s.use = use;
  s.sampler = sampler;
  return s;
}

Slot untouched(ResourceId id) {
  Slot s = slot(id, Use::ComputeStorageRead);
  s.touched = false;
  return s;
}

Slot outsideGraph(const Binding& binding) {
  Slot s;
  s.outside = binding;
  return s;
}

RenderGraph::PassBuilder addSlotPass(RenderGraph& g, std::string name, Slots slots, SlotRecordFn record) {
  const Slots declared = slots;
  auto pass = g.addPass(std::move(name), [slots = std::move(slots), record = std::move(record)](PassContext& c) {
    return record(c, slots);
  });
  for (const Slot& s : declared) {
    if (s.id == kInvalidResource || !s.touched) continue;
    if (isWriteAccess(stateOf(s.use).access)) pass.write(s.id, s.use);
    else pass.read(s.id, s.use);
  }
  return pass;
}

Status slotBindings(const PassContext& c, const Slots& slots, const std::vector<VkDescriptorType>& types,
                    const std::string& what, std::vector<Binding>* out) {
  if (slots.size() != types.size())
    return Status::error(what + ": " + std::to_string(slots.size()) + " slots declared, the SPIR-V has " +
                         std::to_string(types.size()) + " bindings");
  out->clear();
  for (size_t i = 0; i < slots.size(); ++i) {
    const Slot& s = slots[i];
    if (s.id == kInvalidResource) {
      out->push_back(s.outside);
      continue;
    }
    // The resource's name only for a message: nothing is built on the per-dispatch path.
    auto name = [&] { return "'" + c.graph->resourceName(s.id) + "'"; };
    if (!fits(types[i], s.use))
      return Status::error(what + ": binding " + std::to_string(i) + " is a " + descriptorTypeName(types[i]) +
                           " in the SPIR-V; its slot declares " + name() + " as " + useName(s.use));
    if (isBufferType(types[i])) {
      out->push_back(bindBuffer(c.buffer(s.id)));
    } else {
      if (types[i] == VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER && !s.sampler)
        return Status::error(what + ": binding " + std::to_string(i) + " (" + name() + ") is sampled and its slot has no sampler");
      out->push_back(bindImage(c.image(s.id).view, stateOf(s.use).layout, s.sampler));
    }
  }
  return Status();
}

Status dispatchSlots(PassContext& c, const ComputePipeline& p, const Slots& s, uint32_t tx, uint32_t ty, uint32_t tz,
                     const void* push, uint32_t pushSize) {
  std::vector<Binding> b;
  CANOPY_TRY(slotBindings(c, s, p.bindings, p.name, &b));  // the pipeline's name: no string built per dispatch
  return dispatch(*c.device, c.cmd, p, tx, ty, tz, b, push, pushSize);
}

Status dispatchIndirectSlots(PassContext& c, const ComputePipeline& p, const Slots& s, VkBuffer args, VkDeviceSize offset,
                             const void* push, uint32_t pushSize) {
  std::vector<Binding> b;
  CANOPY_TRY(slotBindings(c, s, p.bindings, p.name, &b));  // the pipeline's name: no string built per dispatch
  return dispatchIndirect(*c.device, c.cmd, p, args, offset, b, push, pushSize);
}

Status bindGraphicsSlots(PassContext& c, const GraphicsPipeline& p, const Slots& s, const void* push, uint32_t pushSize) {
  std::vector<Binding> b;
  CANOPY_TRY(slotBindings(c, s, p.bindings, p.name, &b));
  return bindGraphics(*c.device, c.cmd, p, b, push, pushSize);
}

}  // namespace canopy::rg
