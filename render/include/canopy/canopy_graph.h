#pragma once
// Canopy as one pass of a host engine's render graph (docs/embedding.md "In a host's render graph";
// how Canopy keeps it: docs/design.md "Embedding contract").
//
// recordCanopy() (<canopy/canopy.h>) places every barrier itself, from the states the host says its
// images arrive in and must leave in. A host whose own render graph places barriers declares
// Canopy's pass group as one pass instead:
//   1. when it builds its graph, canopyPassGroupUses() gives, per host image, the state the group
//      uses it in (every stage and access of the group's passes, and the layout it enters and
//      leaves in); the host's graph declares that use for its Canopy pass;
//   2. when the host's graph executes that pass, recordCanopyPassGroup() records the group into
//      the pass's command buffer. The host's graph has put the images in their declared states;
//      Canopy records barriers only for its own resources and for layout changes inside the group,
//      and leaves each image in its declared state with no closing barrier: the host's next barrier
//      starts from the declared stages and accesses.
// Everything else (frames in flight, deferred uploads, several contexts, the host's conventions)
// is as for recordCanopy.
#include <vector>

#include <canopy/canopy.h>

namespace canopy {

enum class CanopyTarget : uint32_t { Color = 0, Depth = 1, Motion = 2 };

struct CanopyTargetUse {
  CanopyTarget target = CanopyTarget::Color;
  // stage/access: the union over the group's passes; layout: the image's layout on entry and exit.
  ResourceState state;
  bool writes = true;  // the group writes the image (orders the host's passes around it)
};

// The host images the pass group touches (colour, depth, and motion when CanopyDesc.motionFormat
// is set) and how. Fixed for the context's life: a host may cache the list. CPU only.
// Errors: a null context or output.
CanopyStatus canopyPassGroupUses(const CanopyContext* context, std::vector<CanopyTargetUse>* uses);

// Records one whole frame as recordCanopy() does, for a host graph that has placed `inputs`'
// images in the states of canopyPassGroupUses() (their `current` and `final` fields are ignored).
// Records into `cmd` only; nothing is submitted and nothing waits. Same thread rules as
// recordCanopy (<canopy/canopy.h>): no two calls on one Device or its contexts run concurrently,
// whichever contexts they name (docs/embedding.md "Threads").
CanopyStatus recordCanopyPassGroup(CanopyContext* context, VkCommandBuffer cmd, const CanopyFrameInputs& inputs);

}  // namespace canopy
