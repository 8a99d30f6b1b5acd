#pragma once
// A pass's descriptors declared once (docs/design.md "Descriptors from the SPIR-V"): binding i of
// the pass's pipeline is slots[i], naming the graph resource it binds and how the shader uses it.
// The one list declares the pass's graph uses (so its barriers and layouts) and, when the pass is
// recorded, gives its bind list, each slot checked against the descriptor type the pipeline's
// SPIR-V declares for that binding. A slot outside the graph (an object no frame writes, such as a
// texture uploaded at creation) says so.
#include <functional>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/graphics_pipeline.h"
#include "engine/pipeline.h"
#include "engine/render_graph.h"
#include "engine/status.h"

namespace canopy::rg {

struct Slot {
  ResourceId id = kInvalidResource;  // the graph resource bound; kInvalidResource: `outside`
  Use use = Use::ComputeStorageRead; // how the shader uses it: the pass's declared access
  bool touched = true;               // false: bound for a shared include's declaration, not accessed
  VkSampler sampler = VK_NULL_HANDLE;
  Binding outside;                   // bound as is (id == kInvalidResource): no graph use
};
using Slots = std::vector<Slot>;

// A graph resource used by the shader as `use` (a buffer: all of it; an image with a sampler: a
// combined image sampler).
Slot slot(ResourceId id, Use use, VkSampler sampler = VK_NULL_HANDLE);
// A graph resource bound because the shaders' shared include declares it, which this kernel does
// not access: bound, no access declared (so no barrier for it).
Slot untouched(ResourceId id);
// An object outside the graph, written by no frame (created and uploaded before the first).
Slot outsideGraph(const Binding& binding);

// Adds a pass whose descriptors are `slots`: each touched slot's use is declared on the pass (a
// read or a write by the use's access), and `record` gets the same list to bind from.
using SlotRecordFn = std::function<Status(PassContext&, const Slots&)>;
RenderGraph::PassBuilder addSlotPass(RenderGraph& graph, std::string name, Slots slots, SlotRecordFn record);

// The bind list of `slots` for this record (each graph slot's buffer, or image view in its use's
// layout), each checked against binding i of `types`: a count or a kind that differs is refused,
// naming `what`, the binding, the resource and both kinds.
Status slotBindings(const PassContext& c, const Slots& slots, const std::vector<VkDescriptorType>& types,
                    const std::string& what, std::vector<Binding>* out);

// dispatch(), dispatchIndirect() and bindGraphics() over the slots' bind list.
Status dispatchSlots(PassContext& c, const ComputePipeline& pipeline, const Slots& slots, uint32_t threadsX,
                     uint32_t threadsY, uint32_t threadsZ, const void* push, uint32_t pushSize);
Status dispatchIndirectSlots(PassContext& c, const ComputePipeline& pipeline, const Slots& slots, VkBuffer args,
                             VkDeviceSize offset, const void* push, uint32_t pushSize);
Status bindGraphicsSlots(PassContext& c, const GraphicsPipeline& pipeline, const Slots& slots, const void* push,
                         uint32_t pushSize);
template <class Push>
Status dispatchSlots(PassContext& c, const ComputePipeline& p, const Slots& s, uint32_t tx, uint32_t ty, uint32_t tz,
                     const Push& push) {
  return dispatchSlots(c, p, s, tx, ty, tz, &push, uint32_t(sizeof(Push)));
}
template <class Push>
Status dispatchIndirectSlots(PassContext& c, const ComputePipeline& p, const Slots& s, VkBuffer args, VkDeviceSize offset,
                             const Push& push) {
  return dispatchIndirectSlots(c, p, s, args, offset, &push, uint32_t(sizeof(Push)));
}
template <class Push>
Status bindGraphicsSlots(PassContext& c, const GraphicsPipeline& p, const Slots& s, const Push& push) {
  return bindGraphicsSlots(c, p, s, &push, uint32_t(sizeof(Push)));
}

}  // namespace canopy::rg
