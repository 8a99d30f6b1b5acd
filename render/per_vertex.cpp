#include "render/per_vertex.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/camera.h"
#include "engine/device.h"
#include "engine/pass_slots.h"
#include "engine/transfer.h"

namespace canopy {
namespace {

// How the frame blocks and the branch table rest between frames: read by the motion kernel (bend
// frame, branch levels), the vertex stage (matrices, bend frame, branch chains) and the fragment
// stage (light). Resting in all three makes the next frame's update wait for every reader.
const rg::State kFrameRead{VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT |
                               VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                           VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_IMAGE_LAYOUT_UNDEFINED};

}  // namespace

Status validatePerVertexParams(const PerVertexParams& p) { return checkParams(p, "PerVertexParams."); }

Status validateBendHierarchy(const std::vector<gpu::BendVertex>& bend, const std::vector<gpu::BendBranch>& branches,
                             size_t vertexCount, const std::string& what) {
  if (bend.empty() && branches.empty()) return Status();
  if (bend.size() != vertexCount)
    return Status::error(Result::InvalidModel, what + ": the branch hierarchy has " + std::to_string(bend.size()) +
                                                   " vertices for " + std::to_string(vertexCount));
  for (size_t i = 0; i < branches.size(); ++i) {
    const gpu::BendBranch& b = branches[i];
    const std::string name = what + ": branch " + std::to_string(i);
    if (b.parent == BEND_NO_PARENT ? b.level != 0 : (b.parent >= i || b.level != branches[b.parent].level + 1))
      return Status::error(Result::InvalidModel, name + " has parent " + std::to_string(int64_t(int32_t(b.parent))) +
                                                     " and level " + std::to_string(b.level) +
                                                     " (parents come first; a level is its parent's + 1)");
    if (b.level >= BEND_LEVELS)
      return Status::error(Result::InvalidModel, name + " is at level " + std::to_string(b.level) + ", past the " +
                                                     std::to_string(BEND_LEVELS) + " levels a vertex carries");
    const float len = glm::length(b.axis);
    if (!std::isfinite(b.origin.x + b.origin.y + b.origin.z) || !(std::abs(len - 1.0f) < 1e-3f))
      return Status::error(Result::InvalidModel, name + " needs a finite origin and a unit axis");
  }
  for (size_t v = 0; v < bend.size(); ++v)
    if (bend[v].branch < BEND_LEAF_ONLY && bend[v].branch >= branches.size())
      return Status::error(Result::InvalidModel, what + ": vertex " + std::to_string(v) + " names branch " +
                                                     std::to_string(bend[v].branch) + " of " + std::to_string(branches.size()));
  return Status();
}

gpu::BendChain bendChainOf(const std::vector<gpu::BendBranch>& branches, uint32_t branch) {
  gpu::BendChain c{};
  if (branch >= BEND_LEAF_ONLY) return c;
  uint32_t ids[BEND_LEVELS];
  uint32_t n = 0;
  for (uint32_t b = branch; b != BEND_NO_PARENT && n < BEND_LEVELS; b = branches[b].parent) ids[n++] = b;
  for (uint32_t i = 0; i < n; ++i) {
    c.id[i] = ids[n - 1 - i];
    c.b[i] = branches[c.id[i]];
  }
  c.count = n;
  return c;
}

gpu::BendTrunk bendTrunkOf(const glm::vec3& boundsMin, const glm::vec3& boundsMax) {
  const glm::vec3 centre = 0.5f * (boundsMin + boundsMax);
  const glm::vec2 halfXZ(0.5f * (boundsMax.x - boundsMin.x), 0.5f * (boundsMax.z - boundsMin.z));
  // glTF's up is the trunk's axis.
  return gpu::BendTrunk{glm::vec4(centre.x, boundsMin.y, centre.z, std::max(glm::length(halfXZ), 1e-6f)),
                        glm::vec4(0.0f, 1.0f, 0.0f, std::max(boundsMax.y - boundsMin.y, 1e-6f))};
}

gpu::BendFrame makeBendFrame(const PerVertexParams& p, const WindParams& wind, const SimulationPlane& plane,
                             const glm::vec3& boundsMin, const glm::vec3& boundsMax, float time, float previousTime) {
  gpu::BendFrame f{};
  // The wind's direction on the simulation plane as the 2D method's sources blow it (a source on
  // the left blows towards +x, on the top towards -y), in world space.
  glm::vec2 d(0.0f);
  if (wind.sides & kWindFromLeft) d.x += 1.0f;
  if (wind.sides & kWindFromRight) d.x -= 1.0f;
  if (wind.sides & kWindFromBottom) d.y += 1.0f;
  if (wind.sides & kWindFromTop) d.y -= 1.0f;
  glm::vec3 dir = d.x * toGlm(plane.right) + d.y * toGlm(plane.up);
  const float dl = glm::length(dir);
  const bool blows = dl > 1e-6f;
  dir = blows ? dir / dl : glm::vec3(1, 0, 0);
  const glm::vec3 up(0.0f, 1.0f, 0.0f);  // glTF's up: the fallback trunk's axis
  glm::vec3 lateral = glm::cross(up, dir);
  lateral = glm::length(lateral) > 1e-4f ? glm::normalize(lateral) : toGlm(plane.right);
  f.wind = glm::vec4(dir, wind.strength * wind.baseline);
  f.lateral = glm::vec4(lateral, p.lateral);
  const gpu::BendTrunk trunk = bendTrunkOf(boundsMin, boundsMax);
  f.up = trunk.up;
  f.root = trunk.root;
  f.trunkCount = 1;
  f.flexibility = glm::vec4(p.flexibility[0], p.flexibility[1], p.flexibility[2], p.flexibility[3]);
  f.frequency = glm::vec4(p.frequency[0], p.frequency[1], p.frequency[2], p.frequency[3]);
  f.leafFlexibility = p.leafFlexibility;
  f.leafFrequency = p.leafFrequency;
  f.referenceSpeed = p.referenceSpeed;
  f.maxAngle = p.maxAngle;
  // No source side (or opposite sides cancelling): no wind.
  f.strength = blows ? wind.strength : 0.0f;
  f.baseline = wind.baseline;
  f.modulation = wind.modulation;
  f.windFrequency = wind.frequency;
  f.gust = wind.gust;
  f.taper = p.taper;
  f.time = time;
  f.previousTime = previousTime;
  f.seed = p.seed;
  f.windModel = p.wind == PerVertexWind::KaimalField ? BEND_WIND_FIELD : BEND_WIND_UNIFORM;
  f.damping = glm::vec4(p.damping[0], p.damping[1], p.damping[2], p.damping[3]);
  f.leafDamping = p.leafDamping;
  f.integralScale = p.integralScale;
  // The field's coordinates: from the fallback trunk's root, in the simulation's domain units (one
  // tile of the plane), like the 2D method's wind.
  f.fieldOrigin = glm::vec4(glm::vec3(f.root), std::max(plane.tileSize, 1e-6f));
  return f;
}

Status createPerVertex(Device& d, const LayeredVegetation& lv, const std::vector<gpu::BendBranch>& branches,
                       const PerVertexDesc& desc, PerVertexAnimation* out, PreparedList* deferred) {
  *out = PerVertexAnimation{};
  PerVertexAnimation& pv = *out;
  pv.device = &d;
  pv.desc = desc;
  pv.hierarchy = lv.mesh.bendVertices.buffer != VK_NULL_HANDLE;
  const bool motion = desc.motionFormat != VK_FORMAT_UNDEFINED;
  // shaders/layers_common.glsl's six bindings, then shaders/per_vertex_common.glsl's five.
  GraphicsPipelineDesc p = layerMeshPipelineDesc(desc.colorFormat, desc.depthFormat);
  if (motion) p.colorFormats.push_back(desc.motionFormat);
  p.blendedAttachments = 1;
  p.depthCompare = desc.reverseZ ? VK_COMPARE_OP_GREATER : VK_COMPARE_OP_LESS;
  p.vertexShader = motion ? "per_vertex_motion.vert" : "per_vertex.vert";
  p.fragmentShader = motion ? "per_vertex_motion.frag" : "layers.frag";
  // Specialised for the model's materials as the layers' draws are (the same shading, at the same
  // cost per fragment); the settings' parts stay open: this pipeline outlives settings changes.
  p.fragmentSpecialization = {layerShadingFeatures(lv, lv.settings) | LAYER_FEATURE_HABEL | LAYER_FEATURE_DIFFUSE_BTDF |
                              LAYER_FEATURE_LEVEL_COLORS};
  CANOPY_TRY(createGraphicsPipeline(d, p, &pv.pipeline));
  const VkBufferUsageFlags usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createBuffer(d, sizeof(gpu::LayerFrame), usage, MemoryUsage::DeviceLocal, &pv.frame, "per-vertex: frame"));
  CANOPY_TRY(createBuffer(d, sizeof(gpu::BendFrame), usage, MemoryUsage::DeviceLocal, &pv.bendFrame, "per-vertex: bend frame"));
  pv.branchCount = uint32_t(branches.size());
  pv.leafCount = lv.mesh.leafCount;
  CANOPY_TRY(createComputePipeline(d, {"per_vertex_tips.comp", 0}, &pv.tipsPipeline));
  pv.copies = 0;
  CANOPY_TRY(resizePerVertexCopies(pv, uint32_t(lv.instances.models.size())));
  const VkDeviceSize branchBytes = std::max<VkDeviceSize>(branches.size() * sizeof(gpu::BendBranch), sizeof(gpu::BendBranch));
  CANOPY_TRY(createBuffer(d, branchBytes, usage, MemoryUsage::DeviceLocal, &pv.branches, "per-vertex: branches"));
  std::vector<gpu::BendBranch> table = branches;
  if (table.empty()) table.push_back(gpu::BendBranch{glm::vec3(0), BEND_NO_PARENT, glm::vec3(0, 1, 0), 0});  // never read
  CANOPY_TRY(uploadBuffer(d, deferred, pv.branches, table.data(), branchBytes, kFrameRead));
  // Each leaf's root, where the motion kernel samples the wind field for it (16 bytes a leaf).
  std::vector<glm::vec4> leafPositions = lv.mesh.leafRootPositions;
  leafPositions.resize(std::max<size_t>(pv.leafCount, 1), glm::vec4(0.0f));
  const VkDeviceSize leafBytes = leafPositions.size() * sizeof(glm::vec4);
  CANOPY_TRY(createBuffer(d, leafBytes, usage, MemoryUsage::DeviceLocal, &pv.leafPositions, "per-vertex: leaf roots"));
  CANOPY_TRY(uploadBuffer(d, deferred, pv.leafPositions, leafPositions.data(), leafBytes, kFrameRead));
  // Each species' fallback trunk (entry 0 the vegetation's for one species: BendFrame's own).
  std::vector<gpu::BendTrunk> trunks;
  if (lv.mesh.species.size() > 1)
    for (const MeshSpecies& s : lv.mesh.species) trunks.push_back(bendTrunkOf(s.boundsMin, s.boundsMax));
  else
    trunks.push_back(bendTrunkOf(lv.mesh.boundsMin, lv.mesh.boundsMax));
  pv.trunkCount = uint32_t(trunks.size());
  const VkDeviceSize trunkBytes = trunks.size() * sizeof(gpu::BendTrunk);
  CANOPY_TRY(createBuffer(d, trunkBytes, usage, MemoryUsage::DeviceLocal, &pv.trunks, "per-vertex: trunks"));
  CANOPY_TRY(uploadBuffer(d, deferred, pv.trunks, trunks.data(), trunkBytes, rg::stateOf(rg::Use::VertexStorageRead)));
  if (!pv.hierarchy) {
    CANOPY_TRY(createBuffer(d, 16, usage, MemoryUsage::DeviceLocal, &pv.dummy, "per-vertex: no hierarchy"));
    const uint32_t zero[4] = {};
    CANOPY_TRY(uploadBuffer(d, deferred, pv.dummy, zero, sizeof zero, rg::stateOf(rg::Use::VertexStorageRead)));
  }
  return Status();
}

Status resizePerVertexCopies(PerVertexAnimation& pv, uint32_t copies) {
  if (copies == pv.copies && pv.tips.buffer) return Status();
  Device& d = *pv.device;
  const bool motion = pv.desc.motionFormat != VK_FORMAT_UNDEFINED;
  const VkDeviceSize tipBytes = (uint64_t(pv.branchCount) + pv.leafCount) * sizeof(glm::vec3) * (motion ? 2 : 1) * copies;
  Buffer next;
  CANOPY_TRY(createBuffer(d, std::max<VkDeviceSize>(tipBytes, 16), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUsage::DeviceLocal, &next,
                          "per-vertex: motion table"));
  destroyBufferLater(d, pv.tips);  // frames in flight read the old table
  pv.tips = next;
  pv.copies = copies;
  return Status();
}

void destroyPerVertex(PerVertexAnimation& pv) {
  if (!pv.device) return;
  Device& d = *pv.device;
  destroyGraphicsPipeline(d, pv.pipeline);
  destroyComputePipeline(d, pv.tipsPipeline);
  for (Buffer* b : {&pv.frame, &pv.bendFrame, &pv.branches, &pv.dummy, &pv.tips, &pv.leafPositions, &pv.trunks}) destroyBuffer(d, *b);
  pv = PerVertexAnimation{};
}

Status preparePerVertex(PerVertexAnimation& pv, const LayeredVegetation& lv, const CanopyParams& params,
                        const SimulationPlane& plane, const CanopyCamera& camera, const glm::mat4& jitter, float dt, bool cut) {
  if (!pv.device) return Status::error("per-vertex baseline: not created (CanopyDesc.allowPerVertex)");
  const double before = pv.time;
  pv.time += dt;
  // The host's own projection (its depth convention: the pipeline compares accordingly).
  LayerView view;
  view.view = toGlm(camera.view);
  view.proj = jitter * toGlm(camera.proj);  // drawn at the jittered position
  pv.layerFrame = cameraFrame(params.layers, view);
  // The 2D method multiplies the composited colour by the exposure; here the light does.
  const float e = params.composite.exposure;
  pv.layerFrame.lightColor *= glm::vec4(e, e, e, 1.0f);
  pv.layerFrame.lightDirection.w *= e;
  pv.current = makeBendFrame(params.perVertex, params.simulation.wind, plane, lv.mesh.boundsMin, lv.mesh.boundsMax, float(pv.time),
                             float(pv.frames > 0 ? before : pv.time));
  pv.current.targetSize = glm::vec2(float(pv.desc.width), float(pv.desc.height));
  pv.current.flags = (pv.hierarchy ? BEND_FLAG_HIERARCHY : 0u) |
                     (pv.desc.motionFormat != VK_FORMAT_UNDEFINED ? BEND_FLAG_PREVIOUS : 0u);
  const glm::mat4 viewProj = toGlm(camera.proj) * view.view;  // unjittered
  // The previous camera jittered as this frame's: the motion vectors carry no jitter.
  pv.current.previousViewProj = jitter * (pv.frames > 0 && !cut ? pv.lastViewProj : viewProj);
  pv.lastViewProj = viewProj;
  pv.current.branchCount = pv.branchCount;
  pv.current.tipCount = pv.branchCount + pv.leafCount;
  pv.current.copyCount = pv.copies;
  pv.current.trunkCount = pv.trunkCount;
  // The copies in view (drawn every frame: culled every frame).
  pv.runs = visibleInstanceRuns(lv.instances, lv.mesh.species, viewProj);
  pv.frames++;
  return Status();
}

Status addPerVertexPasses(PerVertexAnimation& pv, LayeredVegetation& lv, rg::RenderGraph& g, const CompositeTargets& t) {
  if (!pv.device) return Status::error("per-vertex baseline: not created (CanopyDesc.allowPerVertex)");
  const auto frame = g.importBuffer("per-vertex: frame", pv.frame.size, kFrameRead, kFrameRead);
  const auto bendFrame = g.importBuffer("per-vertex: bend frame", pv.bendFrame.size, kFrameRead, kFrameRead);
  const rg::State tipRest = rg::stateOf(rg::Use::VertexStorageRead);
  const auto tips = g.importBuffer("per-vertex: motion table", pv.tips.size, tipRest, tipRest);
  MeshResources mesh;
  CANOPY_TRY(importMesh(lv.mesh, g, &mesh));
  PerVertexAnimation* p = &pv;
  g.addPass("per-vertex: constants", [p](rg::PassContext& c) {
     c.device->vk.CmdUpdateBuffer(c.cmd, p->frame.buffer, 0, sizeof(gpu::LayerFrame), &p->layerFrame);
     c.device->vk.CmdUpdateBuffer(c.cmd, p->bendFrame.buffer, 0, sizeof(gpu::BendFrame), &p->current);
     return Status();
   })
      .write(frame, rg::Use::TransferDst)
      .write(bendFrame, rg::Use::TransferDst);
  // The branch table and the leaf roots are uploaded at creation and never written again: bound
  // outside the graph.
  rg::addSlotPass(g, "per-vertex: branch motion",
                  {rg::slot(bendFrame, rg::Use::ComputeStorageRead), rg::outsideGraph(bindBuffer(pv.branches.buffer)),
                   rg::slot(tips, rg::Use::ComputeStorageWrite), rg::outsideGraph(bindBuffer(lv.instances.buffer.buffer)),
                   rg::outsideGraph(bindBuffer(pv.leafPositions.buffer))},
                  [p](rg::PassContext& c, const rg::Slots& s) {
                    // The shader strides over the rest.
                    const uint32_t n = uint32_t(std::min<uint64_t>(uint64_t(p->current.tipCount) * p->copies, 64u * 4096u));
                    if (n == 0) return Status();
                    return rg::dispatchSlots(c, p->tipsPipeline, s, n, 1, 1, nullptr, 0);
                  });
  const bool motion = pv.desc.motionFormat != VK_FORMAT_UNDEFINED;
  LayeredVegetation* l = &lv;
  auto draw = g.addPass("per-vertex: draw", [p, l, t, motion](rg::PassContext& x) {
    beginHostRendering(x, t, p->desc.width, p->desc.height, motion);
    PerVertexBindings b;
    b.frame = p->frame.buffer;
    b.bendFrame = p->bendFrame.buffer;
    b.branches = p->branches.buffer;
    b.bendVertices = p->hierarchy ? l->mesh.bendVertices.buffer : p->dummy.buffer;
    b.tips = p->tips.buffer;
    b.trunks = p->trunks.buffer;
    Status s = drawWholeMesh(meshDraw(*l), x.cmd, p->pipeline, b, p->runs);
    x.device->cmdEndRendering(x.cmd);
    return s;
  });
  draw.access(frame, kFrameRead)
      .read(bendFrame, rg::Use::VertexStorageRead)
      .read(tips, rg::Use::VertexStorageRead)
      .write(t.color, rg::Use::ColorAttachmentReadWrite)
      .write(t.depth, rg::Use::DepthAttachmentWrite);
  readsMesh(draw, mesh);
  if (motion) draw.write(t.motion, rg::Use::ColorAttachmentReadWrite);
  CANOPY_TRY(g.bindBuffer(frame, pv.frame.buffer));
  CANOPY_TRY(g.bindBuffer(bendFrame, pv.bendFrame.buffer));
  CANOPY_TRY(g.bindBuffer(tips, pv.tips.buffer));
  return Status();
}

}  // namespace canopy
