#pragma once
// The per-vertex wind baseline (seed 004, Habel IV-VI; docs/design.md "Per-vertex wind baseline"):
// the "3D" way the 2D method is measured against. Every frame the whole compact mesh is drawn into
// the host's colour and depth with the layers' shading, each vertex bent in the vertex shader
// through its branch hierarchy (shaders/shared/bend.h) by spectral noise that follows the wind.
#include <vector>

#include "engine/graphics_pipeline.h"
#include "engine/memory.h"
#include "engine/pipeline.h"
#include "engine/render_graph.h"
#include "render/composite.h"
#include <canopy/canopy_params.h>
#include "render/layers.h"
#include "shared/bend.h"

namespace canopy {

// The host's targets as the compositor sees them (size, formats, depth convention; motionFormat
// UNDEFINED: no motion vectors): the baseline draws into the same targets.
using PerVertexDesc = CompositorDesc;

struct PerVertexAnimation {
  Device* device = nullptr;
  PerVertexDesc desc;
  GraphicsPipeline pipeline;
  ComputePipeline tipsPipeline;              // shaders/per_vertex_tips.comp: the motion table
  Buffer frame, bendFrame, branches, dummy;  // dummy: BendVertexBuf when the model has no hierarchy
  Buffer tips;                               // the motion table: per copy, a vec3 per branch and leaf (twice with motion)
  Buffer leafPositions;                      // a vec4 per leaf: its root (the wind field's sample point)
  Buffer trunks;                             // gpu::BendTrunk per species (a model without a hierarchy bends about it)
  uint32_t branchCount = 0, leafCount = 0, trunkCount = 1;
  uint32_t copies = 1;                       // the placed copies the motion table holds (CanopyDesc.instances)
  std::vector<InstanceRun> runs;             // the copies this frame's camera sees
  bool hierarchy = false;
  gpu::LayerFrame layerFrame{};
  gpu::BendFrame current{};
  double time = 0.0;   // the baseline's own clock, s (advanced by CanopyFrame.dt)
  uint64_t frames = 0;
  glm::mat4 lastViewProj{1.0f};  // the camera of the frame before (motion vectors)
};

// Checks PerVertexParams' ranges; the message names the field and its range.
Status validatePerVertexParams(const PerVertexParams& params);
// Checks a branch table and per-vertex hierarchy (parents before children, levels = parent's + 1
// below BEND_LEVELS, unit finite axes, branch indices in range); `what` names the model.
Status validateBendHierarchy(const std::vector<gpu::BendVertex>& bend, const std::vector<gpu::BendBranch>& branches,
                             size_t vertexCount, const std::string& what);

// Creates the pipeline and uploads the branch table (`branches` may be empty: the fallback).
// The branch table's upload goes to `deferred` on a device that defers its work (engine/transfer.h,
// submitOrDefer); null: submitted at once.
Status createPerVertex(Device& device, const LayeredVegetation& lv, const std::vector<gpu::BendBranch>& branches,
                       const PerVertexDesc& desc, PerVertexAnimation* out, PreparedList* deferred = nullptr);
void destroyPerVertex(PerVertexAnimation& pv);
// Sizes the motion table for `copies` placed copies (the old one released after the frames in
// flight; a graph holding it must be rebuilt).
Status resizePerVertexCopies(PerVertexAnimation& pv, uint32_t copies);

// The fallback trunk of a model without a hierarchy: the vertical through its bounds' centre from
// their bottom, crown radius the bounds' horizontal half-diagonal.
gpu::BendTrunk bendTrunkOf(const glm::vec3& boundsMin, const glm::vec3& boundsMax);
// The bend frame for the wind and parameters at time t (the model's bounds give the fallback
// trunk: the vertical through the bounds' centre, from their bottom).
gpu::BendFrame makeBendFrame(const PerVertexParams& params, const WindParams& wind, const SimulationPlane& plane,
                             const glm::vec3& boundsMin, const glm::vec3& boundsMax, float time, float previousTime);
// Advances the clock by dt and fills this frame's constants (camera, light, bend frame); `cut`: the
// camera jumped (CanopyFrame.cameraCut), so the motion vectors carry no camera motion this frame.
Status preparePerVertex(PerVertexAnimation& pv, const LayeredVegetation& lv, const CanopyParams& params,
                        const SimulationPlane& plane, const CanopyCamera& camera, const glm::mat4& jitter, float dt, bool cut);
// "per-vertex: constants", "per-vertex: branch motion" (the motion table) and "per-vertex: draw"
// (into the host's colour and depth, and motion).
Status addPerVertexPasses(PerVertexAnimation& pv, LayeredVegetation& lv, rg::RenderGraph& graph,
                          const CompositeTargets& targets);

// The CPU twin of shaders/per_vertex_common.glsl's fetchChain.
gpu::BendChain bendChainOf(const std::vector<gpu::BendBranch>& branches, uint32_t branch);

}  // namespace canopy
