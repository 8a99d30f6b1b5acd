#include "render/rigid_follow.h"

#include <algorithm>

#include "compute/dynamics.h"
#include "engine/device.h"

namespace canopy {
namespace {

// The frame block rests readable by the vertex stage (the slice camera, the layers' boundaries) and
// the fragment stage (the light): the next frame's update waits for both.
const rg::State kFrameRead{VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                           VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_IMAGE_LAYOUT_UNDEFINED};

}  // namespace

Status createRigidFollow(Device& d, const LayeredVegetation& lv, const CompositorDesc& desc, RigidFollow* out) {
  *out = RigidFollow{};
  RigidFollow& rf = *out;
  rf.device = &d;
  rf.desc = desc;
  const bool motion = desc.motionFormat != VK_FORMAT_UNDEFINED;
  GraphicsPipelineDesc p = layerMeshPipelineDesc(desc.colorFormat, desc.depthFormat);
  if (motion) p.colorFormats.push_back(desc.motionFormat);
  p.blendedAttachments = 1;
  p.depthCompare = desc.reverseZ ? VK_COMPARE_OP_GREATER : VK_COMPARE_OP_LESS;
  p.vertexShader = motion ? "rigid_follow_motion.vert" : "rigid_follow.vert";
  p.fragmentShader = motion ? "per_vertex_motion.frag" : "layers.frag";
  // The model's textures as the layers' draws have them; both translucency models and the level
  // colours stay open (the pipeline outlives settings changes; rigid parts transmit nothing anyway).
  rf.features = layerShadingFeatures(lv, lv.settings) | LAYER_FEATURE_HABEL | LAYER_FEATURE_DIFFUSE_BTDF | LAYER_FEATURE_LEVEL_COLORS;
  p.fragmentSpecialization = {rf.features};
  Status s = createGraphicsPipeline(d, p, &rf.pipeline);
  const VkDeviceSize align = std::max<VkDeviceSize>(d.properties.limits.minStorageBufferOffsetAlignment, 16);
  rf.rigidOffset = (sizeof(gpu::LayerFrame) + align - 1) / align * align;
  if (s.ok())
    s = createBuffer(d, rf.rigidOffset + sizeof(gpu::RigidFrame), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                     MemoryUsage::DeviceLocal, &rf.frame, "rigid: frame");
  if (!s.ok()) destroyRigidFollow(rf);
  return s;
}

void destroyRigidFollow(RigidFollow& rf) {
  if (!rf.device) return;
  destroyGraphicsPipeline(*rf.device, rf.pipeline);
  destroyBuffer(*rf.device, rf.frame);
  rf = RigidFollow{};
}

Status prepareRigidFollow(RigidFollow& rf, const LayeredVegetation& lv, const CanopyCamera& camera, const glm::mat4& jitter, float exposure,
                          bool motionValid) {
  if (!rf.device) return Status::error("rigid parts: not created");
  // The slice camera's frame block: the layers' boundaries and the camera the warp grid is in.
  rf.layerFrame = lv.visible.frame;
  // The composite multiplies the vegetation's colour by the exposure; drawn directly, the light does.
  rf.layerFrame.lightColor *= glm::vec4(exposure, exposure, exposure, 1.0f);
  rf.layerFrame.lightDirection.w *= exposure;
  const glm::mat4 viewProj = toGlm(camera.proj) * toGlm(camera.view);  // the host's own depth convention
  rf.rigidFrame = gpu::RigidFrame{};
  // Drawn at the jittered position; the previous camera jittered alike, so the motion vectors
  // (current minus previous pixel) carry no jitter.
  rf.rigidFrame.currentViewProj = jitter * viewProj;
  const bool valid = motionValid && rf.frames > 0;
  rf.rigidFrame.previousViewProj = jitter * (valid ? rf.lastViewProj : viewProj);
  rf.rigidFrame.targetSize = glm::vec2(float(rf.desc.width), float(rf.desc.height));
  rf.rigidFrame.flags = (lv.visible.frame.layerCount > 0 ? RIGID_FLAG_DISPLACE : 0u) | (valid ? RIGID_FLAG_MOTION_VALID : 0u);
  rf.lastViewProj = viewProj;
  rf.runs = visibleInstanceRuns(lv.instances, lv.mesh.species, viewProj);
  rf.frames++;
  return Status();
}

Status addRigidFollowPasses(RigidFollow& rf, LayeredVegetation& lv, rg::RenderGraph& g, const CompositeTargets& t,
                            const RigidFollowSources& src) {
  if (!rf.device || !src.layers || !src.dynamics) return Status::error("rigid parts: not created");
  const auto frame = g.importBuffer("rigid: frame", rf.frame.size, kFrameRead, kFrameRead);
  MeshResources mesh;
  mesh.vertices = src.layers->meshVertices;
  mesh.indices = src.layers->meshIndices;
  mesh.roots = src.layers->meshRoots;
  const LayerDynamics& dyn = *src.dynamics;
  RigidFollow* r = &rf;
  g.addPass("rigid: constants", [r](rg::PassContext& c) {
     c.device->vk.CmdUpdateBuffer(c.cmd, r->frame.buffer, 0, sizeof(gpu::LayerFrame), &r->layerFrame);
     c.device->vk.CmdUpdateBuffer(c.cmd, r->frame.buffer, r->rigidOffset, sizeof(gpu::RigidFrame), &r->rigidFrame);
     return Status();
   }).write(frame, rg::Use::TransferDst);
  const bool motion = rf.desc.motionFormat != VK_FORMAT_UNDEFINED;
  const LayerDynamics* d = &dyn;
  LayeredVegetation* l = &lv;
  auto draw = g.addPass("rigid: draw", [r, l, d, t, motion](rg::PassContext& x) {
    if (r->runs.empty()) return Status();
    // Nothing to draw when every rigid chunk is carried into the layers.
    const bool carry = carriesWood(l->mesh, l->settings, l->visible.impostors.cut.active);
    if (std::none_of(l->mesh.chunks.begin(), l->mesh.chunks.end(), [&](const MeshChunk& c) { return !drawnWithFoliage(c, carry); }))
      return Status();
    beginHostRendering(x, t, r->desc.width, r->desc.height, motion);
    MeshDrawOptions o;
    o.frame = r->frame.buffer;
    o.keepViewport = true;
    o.runs = &r->runs;
    // The wood carried into the layers is warped with them; this pass draws the rest.
    o.carryWood = carry;
    o.extra = {bindBuffer(r->frame.buffer, r->rigidOffset, sizeof(gpu::RigidFrame)), bindBuffer(d->frame.buffer, 0, sizeof(gpu::AnimFrame)),
               bindBuffer(d->displacement.buffer)};
    if (motion) o.extra.push_back(bindBuffer(d->previous.buffer));
    const Status s = drawMaterials(meshDraw(*l), x.cmd, r->pipeline, false, LAYER_PASS_BACKGROUND, 0, nullptr, nullptr, &o);
    x.device->cmdEndRendering(x.cmd);
    return s;
  });
  draw.access(frame, kFrameRead)
      .read(src.animFrame, rg::Use::VertexStorageRead)
      .read(src.displacement, rg::Use::VertexStorageRead)
      .write(t.color, rg::Use::ColorAttachmentReadWrite)
      .write(t.depth, rg::Use::DepthAttachmentWrite);
  if (motion) draw.read(src.previous, rg::Use::VertexStorageRead).write(t.motion, rg::Use::ColorAttachmentReadWrite);
  readsMesh(draw, mesh);
  return g.bindBuffer(frame, rf.frame.buffer);
}

}  // namespace canopy
