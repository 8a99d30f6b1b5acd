#pragma once
// Rigid parts in wind (docs/design.md "Rigid parts in wind"; beyond the paper): with
// LayerSettings.rigidMotion = FollowFoliage the trunks and branches are not a still background
// drawn per re-slice but the rigid chunks drawn every frame into the host's colour and depth (and
// motion) before the composite, each vertex displaced by its share (render/rigid_flex.h) of the
// displacement of the foliage layer its depth falls in (shaders/rigid_follow_draw.glsl), so the
// leaves stay on the branches that carry them and the trunk's base stands. The composite then finds
// them in the host's depth as it finds the host's own geometry.
#include <vector>

#include "engine/graphics_pipeline.h"
#include "engine/memory.h"
#include "engine/render_graph.h"
#include "render/composite.h"
#include "render/layers.h"
#include "shared/rigid.h"

namespace canopy {

struct RigidFollow {
  Device* device = nullptr;
  CompositorDesc desc;       // the host's targets (size, formats, depth convention, motion)
  GraphicsPipeline pipeline;
  uint32_t features = 0;     // the pipeline's LAYER_FEATURE_* specialization
  Buffer frame;              // gpu::LayerFrame, then gpu::RigidFrame at rigidOffset
  VkDeviceSize rigidOffset = 0;
  gpu::LayerFrame layerFrame{};
  gpu::RigidFrame rigidFrame{};
  std::vector<InstanceRun> runs;  // the copies this frame's camera sees
  glm::mat4 lastViewProj{1.0f};
  uint64_t frames = 0;
};

Status createRigidFollow(Device& device, const LayeredVegetation& lv, const CompositorDesc& desc, RigidFollow* out);
void destroyRigidFollow(RigidFollow& rf);
// This frame's constants: the visible placement's frame block with `exposure` in its light, the
// host's camera (its own projection) and last frame's; `motionValid`: the previous displacement and
// camera are last frame's (else no motion is written for the rigid parts).
Status prepareRigidFollow(RigidFollow& rf, const LayeredVegetation& lv, const CanopyCamera& camera, const glm::mat4& jitter, float exposure,
                          bool motionValid);
// What the rigid draw reads of the other passes' resources: the mesh as the layer passes imported
// it, the dynamics' frame block and displacements (addDynamicsPasses).
struct RigidFollowSources {
  const LayerResources* layers = nullptr;
  rg::ResourceId animFrame = rg::kInvalidResource, displacement = rg::kInvalidResource, previous = rg::kInvalidResource;
  const LayerDynamics* dynamics = nullptr;
};
// "rigid: constants" and "rigid: draw" (after the dynamics, before the composite reads the host's depth).
Status addRigidFollowPasses(RigidFollow& rf, LayeredVegetation& lv, rg::RenderGraph& graph, const CompositeTargets& targets,
                            const RigidFollowSources& sources);

}  // namespace canopy
