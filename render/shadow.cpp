// The vegetation's shadow caster (render/shadow.h; docs/design.md "Shadows").
#include "render/shadow.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/camera.h"
#include "engine/device.h"
#include "render/host_images.h"
#include "render/layer_common.h"

namespace canopy {
namespace {

constexpr size_t kMaxShadowGraphs = 8;  // a cascade array's layers, each its own view

// The dynamics' buffers as the canopy graph leaves them (compute/dynamics.cpp imports: compute
// reads), declared here as their writers left them, so that the barrier into this graph's vertex
// reads makes the writes visible to the vertex stage too (the canopy graph made them visible to
// compute only).
const rg::State kComputeRest{VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT, VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_IMAGE_LAYOUT_UNDEFINED};

bool depthFormat(VkFormat f) {
  return f == VK_FORMAT_D16_UNORM || f == VK_FORMAT_D32_SFLOAT || f == VK_FORMAT_D24_UNORM_S8_UINT || f == VK_FORMAT_D32_SFLOAT_S8_UINT ||
         f == VK_FORMAT_X8_D24_UNORM_PACK32 || f == VK_FORMAT_D16_UNORM_S8_UINT;
}

bool sameInputs(const CanopyShadowInputs& a, const CanopyShadowInputs& b) {
  return sameHostImage(a.depth, b.depth) && a.width == b.width && a.height == b.height && a.reverseZ == b.reverseZ &&
         a.clear == b.clear;
}

Status pipelineFor(ShadowCaster& sc, VkFormat format, bool reverseZ, const GraphicsPipeline** out) {
  for (const ShadowCaster::Pipeline& p : sc.pipelines)
    if (p.format == format && p.reverseZ == reverseZ) {
      *out = &p.pipeline;
      return Status();
    }
  GraphicsPipelineDesc p = layerMeshPipelineDesc(VK_FORMAT_UNDEFINED, format);
  p.colorFormats.clear();
  p.blend = BlendMode::None;
  p.vertexShader = "shadow.vert";
  p.fragmentShader = "shadow.frag";
  // The host's convention: nearer is smaller (LESS) or, reverse-Z, larger (GREATER); equal passes so
  // the host's own casters drawn before at the same depth do not hide the leaves.
  p.depthCompare = reverseZ ? VK_COMPARE_OP_GREATER_OR_EQUAL : VK_COMPARE_OP_LESS_OR_EQUAL;
  ShadowCaster::Pipeline made;
  made.format = format;
  made.reverseZ = reverseZ;
  CANOPY_TRY(createGraphicsPipeline(*sc.device, p, &made.pipeline));
  sc.pipelines.push_back(made);
  *out = &sc.pipelines.back().pipeline;
  return Status();
}

Status buildShadowGraph(ShadowCaster& sc, const ShadowSources& src, const CanopyShadowInputs& in, ShadowGraph** out) {
  Device& d = *sc.device;
  LayeredVegetation& lv = *src.layers;
  // Graphs of replaced resources, and the least recently used beyond the cache, may still execute.
  std::vector<ShadowGraph> keep, drop;
  for (ShadowGraph& g : sc.graphs) (g.generation == src.generation ? keep : drop).push_back(std::move(g));
  if (keep.size() >= kMaxShadowGraphs) {
    auto lru = std::min_element(keep.begin(), keep.end(), [](const ShadowGraph& a, const ShadowGraph& b) { return a.lastUse < b.lastUse; });
    drop.push_back(std::move(*lru));
    keep.erase(lru);
  }
  sc.graphs = std::move(keep);
  if (!drop.empty()) {
    auto old = std::make_shared<std::vector<ShadowGraph>>(std::move(drop));
    Device* dp = &d;
    deferRelease(d, [dp, old] {
      for (ShadowGraph& g : *old) g.graph->release(*dp);
    });
  }
  const GraphicsPipeline* pipe = nullptr;
  CANOPY_TRY(pipelineFor(sc, in.depth.format, in.reverseZ, &pipe));
  auto graph = std::make_shared<rg::RenderGraph>();
  rg::RenderGraph& g = *graph;
  ImageDesc id;
  id.format = in.depth.format;
  id.width = in.width;
  id.height = in.height;
  const auto depth = g.importImage("host: shadow map", id, in.depth.current, in.depth.final);
  const auto frame = g.importBuffer("shadow: frame", sc.frame.size, kFrameRead, kFrameRead);
  const auto anim = g.importBuffer("dynamics: frame", src.dynamics->frame.size, rg::stateOf(rg::Use::TransferDst), kComputeRest);
  const auto disp = g.importBuffer("dynamics: displacement", src.dynamics->displacement.size, rg::stateOf(rg::Use::ComputeStorageWrite),
                                   kComputeRest);
  MeshResources mesh;
  CANOPY_TRY(importMesh(lv.mesh, g, &mesh));
  ShadowCaster* s = &sc;
  g.addPass("shadow: constants", [s](rg::PassContext& c) {
     c.device->vk.CmdUpdateBuffer(c.cmd, s->frame.buffer, 0, sizeof(gpu::LayerFrame), &s->layerFrame);
     c.device->vk.CmdUpdateBuffer(c.cmd, s->frame.buffer, s->shadowOffset, sizeof(gpu::ShadowFrame), &s->shadowFrame);
     return Status();
   })
      .write(frame, rg::Use::TransferDst)
      .when([s] { return s->drawNow; });
  const LayeredVegetation* l = &lv;
  const LayerDynamics* dyn = src.dynamics;
  const CanopyShadowInputs ci = in;
  auto draw = g.addPass("shadow: draw", [s, l, dyn, pipe, ci, depth](rg::PassContext& x) {
    VkRenderingAttachmentInfo da{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
    da.imageView = x.graph->image(depth).view;
    da.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    da.loadOp = ci.clear ? VK_ATTACHMENT_LOAD_OP_CLEAR : VK_ATTACHMENT_LOAD_OP_LOAD;
    da.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    da.clearValue.depthStencil = {ci.reverseZ ? 0.0f : 1.0f, 0};
    VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
    ri.renderArea = {{0, 0}, {ci.width, ci.height}};
    ri.layerCount = 1;
    ri.pDepthAttachment = &da;
    x.device->cmdBeginRendering(x.cmd, &ri);
    setViewportScissor(*x.device, x.cmd, ci.width, ci.height);
    MeshDrawOptions o;
    o.frame = s->frame.buffer;
    o.keepViewport = true;
    o.runs = &s->runs;
    o.extra = {bindBuffer(s->frame.buffer, s->shadowOffset, sizeof(gpu::ShadowFrame)), bindBuffer(dyn->frame.buffer, 0, sizeof(gpu::AnimFrame)),
               bindBuffer(dyn->displacement.buffer)};
    MeshDraw md = meshDraw(*l);
    Status st = s->runs.empty() ? Status() : drawMaterials(md, x.cmd, *pipe, true, LAYER_PASS_BACKGROUND, 0, nullptr, nullptr, &o);
    if (st.ok() && !s->runs.empty() && l->mesh.hasRigid)
      st = drawMaterials(md, x.cmd, *pipe, false, LAYER_PASS_BACKGROUND, 0, nullptr, nullptr, &o);
    x.device->cmdEndRendering(x.cmd);
    return st;
  });
  draw.access(frame, kFrameRead)
      .read(anim, rg::Use::VertexStorageRead)
      .read(disp, rg::Use::VertexStorageRead)
      .write(depth, rg::Use::DepthAttachmentWrite)  // its test reads the host's casters (loaded) too
      .when([s] { return s->drawNow; });
  readsMesh(draw, mesh);
  CANOPY_TRY(g.bindImage(depth, hostImage(in.depth, in.depth.format, in.width, in.height)));
  CANOPY_TRY(g.bindBuffer(frame, sc.frame.buffer));
  CANOPY_TRY(g.bindBuffer(anim, src.dynamics->frame.buffer));
  CANOPY_TRY(g.bindBuffer(disp, src.dynamics->displacement.buffer));
  CANOPY_TRY(g.compile());
  CANOPY_TRY(g.realize(d));
  ShadowGraph made;
  made.graph = std::move(graph);
  made.inputs = in;
  made.generation = src.generation;
  sc.graphs.push_back(std::move(made));
  *out = &sc.graphs.back();
  return Status();
}

}  // namespace

Status checkShadowInputs(const CanopyShadowInputs& in) {
  const std::string name = "CanopyShadowInputs";
  if (!in.depth.image || !in.depth.view) return Status::error(Result::InvalidArgument, name + ".depth: the image and its view are required");
  if (!depthFormat(in.depth.format))
    return Status::error(Result::InvalidArgument, name + ".depth.format " + std::to_string(int(in.depth.format)) +
                                                      " is not a depth format (D16_UNORM, D32_SFLOAT, D24_UNORM_S8_UINT, D32_SFLOAT_S8_UINT, ...)");
  if (in.depth.usage == 0)
    return Status::error(Result::InvalidArgument, name + ".depth.usage is not declared; set it to the VkImageCreateInfo.usage the image was "
                                                         "created with (Canopy needs VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT)");
  if (!(in.depth.usage & VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT))
    return Status::error(Result::InvalidArgument, name + ".depth.usage lacks VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT; create the "
                                                         "image with it (Canopy draws the vegetation's depth into it)");
  if (in.depth.samples != VK_SAMPLE_COUNT_1_BIT)
    return Status::error(Result::InvalidArgument, name + ".depth: " + std::to_string(int(in.depth.samples)) +
                                                      " samples; the shadow map must be single-sampled");
  if (in.depth.viewAspects != 0 && in.depth.viewAspects != VK_IMAGE_ASPECT_DEPTH_BIT)
    return Status::error(Result::InvalidArgument, name + ".depth: the view's aspects must be the depth aspect only");
  if (in.width < 1 || in.width > 16384 || in.height < 1 || in.height > 16384)
    return Status::error(Result::InvalidArgument, name + ".width x height = " + std::to_string(in.width) + " x " +
                                                      std::to_string(in.height) + " is outside [1, 16384] each");
  for (float v : in.lightViewProj.m)
    if (!std::isfinite(v)) return Status::error(Result::InvalidArgument, name + ".lightViewProj has a non-finite element");
  if (in.cascade >= kMaxShadowCascades)
    return Status::error(Result::InvalidArgument, name + ".cascade = " + std::to_string(in.cascade) + " is outside [0, " +
                                                      std::to_string(kMaxShadowCascades - 1) + "]");
  if (in.updateInterval < 1 || in.updateInterval > kMaxShadowInterval)
    return Status::error(Result::InvalidArgument, name + ".updateInterval = " + std::to_string(in.updateInterval) + " is outside [1, " +
                                                      std::to_string(kMaxShadowInterval) + "]");
  return Status();
}

Status recordShadow(ShadowCaster& sc, const ShadowSources& src, VkCommandBuffer cmd, const CanopyShadowInputs& in, bool* updated) {
  if (updated) *updated = false;
  LayeredVegetation& lv = *src.layers;
  Device& d = *lv.device;
  if (lv.mesh.streamed)
    return Status::error("recordCanopyShadow: the shadow draws the resident mesh; the mesh (" + std::to_string(lv.stats.meshBytes >> 20) +
                         " MiB) is streamed under CanopyDesc.deviceMemoryBudget; raise it (or 0: no limit)");
  if (!sc.device) {
    sc.device = &d;
    const VkDeviceSize align = std::max<VkDeviceSize>(d.properties.limits.minStorageBufferOffsetAlignment, 16);
    sc.shadowOffset = (sizeof(gpu::LayerFrame) + align - 1) / align * align;
    CANOPY_TRY(createBuffer(d, sc.shadowOffset + sizeof(gpu::ShadowFrame), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                            MemoryUsage::DeviceLocal, &sc.frame, "shadow: frame"));
  }
  // Per cascade, every updateInterval-th call draws; the others only move the image's state.
  const uint64_t call = sc.calls[in.cascade]++;
  sc.drawNow = call % in.updateInterval == 0;
  const glm::mat4 light = toGlm(in.lightViewProj);
  sc.layerFrame = lv.visible.frame;
  sc.shadowFrame = gpu::ShadowFrame{};
  sc.shadowFrame.lightViewProj = light;
  sc.shadowFrame.displace = src.displaced && src.dynamics->current.layerCount > 0 ? 1u : 0u;
  sc.shadowFrame.displaceRigid = rigidFollows(lv) ? 1u : 0u;
  sc.runs = sc.drawNow ? visibleInstanceRuns(lv.instances, lv.mesh.species, light) : std::vector<InstanceRun>{};
  ShadowGraph* graph = nullptr;
  for (ShadowGraph& g : sc.graphs)
    if (g.generation == src.generation && sameInputs(g.inputs, in)) graph = &g;
  if (!graph) CANOPY_TRY(buildShadowGraph(sc, src, in, &graph));
  graph->lastUse = ++sc.uses;
  CANOPY_TRY(graph->graph->record(cmd));
  (sc.drawNow ? sc.updates : sc.skips)++;
  if (updated) *updated = sc.drawNow;
  return Status();
}

void destroyShadowCaster(ShadowCaster& sc) {
  if (!sc.device) return;
  Device& d = *sc.device;
  for (ShadowGraph& g : sc.graphs) g.graph->release(d);
  for (ShadowCaster::Pipeline& p : sc.pipelines) destroyGraphicsPipeline(d, p.pipeline);
  destroyBuffer(d, sc.frame);
  sc = ShadowCaster{};
}

}  // namespace canopy
