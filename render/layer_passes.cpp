#include "render/layer_passes.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "engine/device.h"
#include "engine/transfer.h"
#include "render/layer_common.h"
#include "render/layers.h"
#include "render/impostor_gpu.h"

namespace canopy {

namespace {
VkRenderingAttachmentInfo attachment(VkImageView view, bool depth, bool clear) {
  VkRenderingAttachmentInfo a{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  a.imageView = view;
  a.imageLayout = depth ? VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  a.loadOp = clear ? VK_ATTACHMENT_LOAD_OP_CLEAR : VK_ATTACHMENT_LOAD_OP_LOAD;
  a.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  if (depth) a.clearValue.depthStencil = {1.0f, 0};
  return a;
}

// Begins dynamic rendering into the attachments, records `draw`, ends rendering.
Status renderInto(Device& d, VkCommandBuffer cmd, const LayeredVegetation& lv, uint32_t layerCount,
                  const VkRenderingAttachmentInfo* colors, uint32_t colorCount, const VkRenderingAttachmentInfo& depth,
                  const std::function<Status()>& draw) {
  VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
  ri.renderArea = {{0, 0}, {lv.desc.width, lv.desc.height}};
  ri.layerCount = layerCount;
  ri.colorAttachmentCount = colorCount;
  ri.pColorAttachments = colors;
  ri.pDepthAttachment = &depth;
  d.cmdBeginRendering(cmd, &ri);
  Status s = draw();
  d.cmdEndRendering(cmd);
  return s;
}

// Where foliage and rigid parts are drawn: the visible set (a re-slice at once) or the next set (a
// spread slice).
struct DrawTargets {
  VkImageView color, depth, ids;  // array views
  const std::vector<VkImageView>*colorLayers, *depthLayers, *idsLayers;
  VkImageView backgroundColor, backgroundDepth;
  const std::vector<InstanceRun>* runs;  // the copies that set's camera sees
};
DrawTargets visibleTargets(const LayeredVegetation& lv) {
  return {lv.targets.color.view, lv.targets.depth.view, lv.targets.ids.view, &lv.targets.colorLayerViews, &lv.targets.depthLayerViews, &lv.targets.idsLayerViews,
          lv.targets.backgroundColor.view, lv.targets.backgroundDepth.view, &lv.visible.runs};
}
DrawTargets nextTargets(const LayeredVegetation& lv) {
  return {lv.targets.next.color.view, lv.targets.next.depth.view, VK_NULL_HANDLE, &lv.targets.next.colorLayerViews, &lv.targets.next.depthLayerViews,
          nullptr, lv.targets.next.backgroundColor.view, lv.targets.next.backgroundDepth.view,
          // A re-slice that ended in this frame (its last slice, then the copy) made its copies the visible ones.
          lv.reslice.spread.phase != SpreadPhase::Idle ? &lv.reslice.spread.job.runs : &lv.visible.runs};
}

// A layer or background draw, shaded once where the path has the pipelines and the settings ask
// for it (docs/design.md "Layers: shading once"): the depth pre-pass, Habel's shading on the depth
// it left, then what a pre-pass cannot hold (blended materials, parts fading towards their
// impostors) the plain way, depth-tested against it.
Status drawShaded(LayeredVegetation& lv, VkCommandBuffer cmd, const GraphicsPipeline& plain, const LayerShadingPipelines::ShadeOnce& once,
                  bool foliage, uint32_t passKind, uint32_t target, const std::vector<ChunkPart>* parts, MeshDrawOptions o) {
  const MeshDraw md = meshDraw(lv);
  if (!lv.settings.shadeOnce || !once.depth.pipeline) return drawMaterials(md, cmd, plain, foliage, passKind, target, parts, nullptr, &o);
  o.subset = MeshDrawOptions::Subset::DepthPrepassed;
  CANOPY_TRY(drawMaterials(md, cmd, once.depth, foliage, passKind, target, parts, nullptr, &o));
  CANOPY_TRY(drawMaterials(md, cmd, once.shade, foliage, passKind, target, parts, nullptr, &o));
  o.subset = MeshDrawOptions::Subset::Rest;
  return drawMaterials(md, cmd, plain, foliage, passKind, target, parts, nullptr, &o);
}

Status recordFoliage(LayeredVegetation& lv, VkCommandBuffer cmd, const DrawTargets& t, bool clear,
                     const std::vector<ChunkPart>* parts) {
  const uint32_t n = lv.settings.layout.count();
  const uint32_t passes = lv.pipelines.singlePass ? 1 : n;
  const bool ids = t.ids != VK_NULL_HANDLE;
  for (uint32_t i = 0; i < passes; ++i) {
    const VkRenderingAttachmentInfo colors[2] = {
        attachment(lv.pipelines.singlePass ? t.color : (*t.colorLayers)[i], false, clear),
        attachment(ids ? (lv.pipelines.singlePass ? t.ids : (*t.idsLayers)[i]) : VK_NULL_HANDLE, false, clear)};
    const VkRenderingAttachmentInfo depth = attachment(lv.pipelines.singlePass ? t.depth : (*t.depthLayers)[i], true, clear);
    // With an impostor cut: the opaque impostors, the foliage left, then the impostors fading in
    // over their fading leaves (docs/design.md "Impostors"); a spread re-slice's slices draw its
    // cut's parts, the opaque impostors with the first slice and the fading ones with the last.
    const ImpostorDraws* imp = parts ? &lv.reslice.spread.impostors : &lv.visible.impostors;
    const bool cut = imp->cut.active;
    const bool opaque = cut && (!parts || lv.reslice.spread.sliceClears), fading = cut && (!parts || lv.reslice.spread.sliceLast);
    // The single pass with layers at half resolution uses its clip-distance variant.
    const bool half = lv.settings.halfResolutionLayers > 0;
    const GraphicsPipeline& layered = half ? lv.pipelines.shaded.layeredHalf : lv.pipelines.shaded.layered;
    const LayerShadingPipelines::ShadeOnce& layeredOnce = half ? lv.pipelines.shaded.layeredHalfOnce : lv.pipelines.shaded.layeredOnce;
    MeshDrawOptions o;
    o.debugLevels = cut && lv.settings.impostors.debugView;
    // The wood that follows the leaves fully is drawn with them (render/layer_mesh.h carriesWood).
    o.carryWood = carriesWood(lv.mesh, lv.settings, cut);
    // With copies the cut's parts for every copy draw its whole copies (the rest are per copy).
    o.runs = cut && imp->cut.perCopy ? &imp->wholeRuns : t.runs;
    CANOPY_TRY(renderInto(*lv.device, cmd, lv, lv.pipelines.singlePass ? n : 1, colors, ids ? 2 : 1, depth, [&]() -> Status {
      if (opaque) CANOPY_TRY(recordImpostors(meshDraw(lv), lv.impostors, lv.settings, lv.pipelines.singlePass, cmd, *imp, false, i));
      const std::vector<ChunkPart>* drawn = parts ? parts : cut ? &imp->parts : nullptr;
      if (!drawn || !drawn->empty())
        CANOPY_TRY(lv.pipelines.singlePass
                       ? drawShaded(lv, cmd, layered, layeredOnce, true, LAYER_PASS_LAYERED, 0, drawn, o)
                       : drawShaded(lv, cmd, lv.pipelines.shaded.perLayer, lv.pipelines.shaded.perLayerOnce, true, LAYER_PASS_ONE_LAYER, i, drawn, o));
      return fading ? recordImpostors(meshDraw(lv), lv.impostors, lv.settings, lv.pipelines.singlePass, cmd, *imp, true, i) : Status();
    }));
  }
  return Status();
}

Status recordBackground(LayeredVegetation& lv, VkCommandBuffer cmd, const DrawTargets& t, bool clear,
                        const std::vector<ChunkPart>* parts) {
  const VkRenderingAttachmentInfo color = attachment(t.backgroundColor, false, clear);
  const VkRenderingAttachmentInfo depth = attachment(t.backgroundDepth, true, clear);
  MeshDrawOptions o;
  o.runs = t.runs;
  return renderInto(*lv.device, cmd, lv, 1, &color, 1, depth, [&] {
    return drawShaded(lv, cmd, lv.pipelines.shaded.background, lv.pipelines.shaded.backgroundOnce, false, LAYER_PASS_BACKGROUND, 0, parts, o);
  });
}

// Whether a spread slice holds parts of foliage (rigid) chunks.
bool sliceHas(const LayeredVegetation& lv, bool foliage) {
  for (const ChunkPart& p : lv.reslice.spread.slice)
    if (drawnWithFoliage(lv.mesh.chunks[p.chunk], carriesWood(lv.mesh, lv.settings, lv.reslice.spread.impostors.cut.active)) == foliage)
      return true;
  return false;
}


// A cross-fade step before the last (shared/layers.h LayerFadePush): the visible layers' colours
// (and the background's) with a weight this frame blended towards the next set inside
// layerFootprint — laid over the visible image in an image's first half of blends, mixed towards
// the new one in its second (render/reslice_scheduler.cpp, the weights). A layer's depth becomes
// the nearer of the two sets' at its first blend (one depth pass per layer and fade, not per
// step): the composite tests each layer's depth against the
// scene, so a leaf the new settings put in another layer, whose texels were empty in the old set,
// would otherwise stay hidden until the last step while the old copy fades out (see-through
// leaves; canopy-bench camera's cross-fade column). The background keeps its depth: rigid parts
// are drawn the same by both sets at one camera.
Status recordFadeBlend(LayeredVegetation& lv, VkCommandBuffer cmd) {
  Device& d = *lv.device;
  const VkRect2D rect = layerFootprint(lv);
  if (rect.extent.width == 0 || rect.extent.height == 0) return Status();
  // `over`: the premultiplied "over" pipeline (no blend constant), else the constant mix.
  auto step = [&](bool over, const GraphicsPipeline& mixPipe, const GraphicsPipeline& overPipe, VkImageView color,
                  const Image& newColor, uint32_t layer, float w) -> Status {
    const GraphicsPipeline& pipe = over ? overPipe : mixPipe;
    if (w <= 0.0f) return Status();
    const float constants[4] = {0.0f, 0.0f, 0.0f, w};
    VkRenderingAttachmentInfo c = attachment(color, false, false);
    VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
    ri.renderArea = rect;
    ri.layerCount = 1;
    ri.colorAttachmentCount = 1;
    ri.pColorAttachments = &c;
    d.cmdBeginRendering(cmd, &ri);
    gpu::LayerFadePush push{};
    push.layer = layer;
    push.weight = w;
    Status s = bindGraphics(d, cmd, pipe, {bindImage(newColor.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, lv.pipelines.nearestSampler)},
                            push);
    if (s.ok()) {
      setViewportScissor(d, cmd, lv.desc.width, lv.desc.height);
      d.vk.CmdSetScissor(cmd, 0, 1, &rect);
      if (!over) d.vk.CmdSetBlendConstants(cmd, constants);
      d.vk.CmdDraw(cmd, 3, 1, 0, 0);
    }
    d.cmdEndRendering(cmd);
    return s;
  };
  auto mergeDepth = [&](uint32_t layer) -> Status {
    VkRenderingAttachmentInfo z = attachment(lv.targets.depthLayerViews[layer], true, false);
    VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
    ri.renderArea = rect;
    ri.layerCount = 1;
    ri.pDepthAttachment = &z;
    d.cmdBeginRendering(cmd, &ri);
    gpu::LayerFadePush push{};
    push.layer = layer;
    push.weight = 1.0f;
    Status s = bindGraphics(d, cmd, lv.pipelines.fadeDepth,
                            {bindImage(lv.targets.next.depth.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, lv.pipelines.nearestSampler)}, push);
    if (s.ok()) {
      setViewportScissor(d, cmd, lv.desc.width, lv.desc.height);
      d.vk.CmdSetScissor(cmd, 0, 1, &rect);
      d.vk.CmdDraw(cmd, 3, 1, 0, 0);
    }
    d.cmdEndRendering(cmd);
    return s;
  };
  const std::vector<float>& w = lv.reslice.spread.fadeWeights;
  const std::vector<uint8_t>& merge = lv.reslice.spread.fadeMergeDepth;
  const std::vector<uint8_t>& over = lv.reslice.spread.fadeOver;
  const uint32_t n = lv.settings.layout.count();
  auto laidOver = [&](uint32_t image) { return image < over.size() && over[image] != 0; };
  for (uint32_t i = 0; i < n; ++i) {
    CANOPY_TRY(step(laidOver(i), lv.pipelines.fade, lv.pipelines.fadeOver, lv.targets.colorLayerViews[i], lv.targets.next.color, i, w[i]));
    if (i < merge.size() && merge[i]) CANOPY_TRY(mergeDepth(i));
  }
  if (!drawsBackground(lv)) return Status();  // both backgrounds stay cleared
  return step(laidOver(n), lv.pipelines.fadeBackground, lv.pipelines.fadeOverBackground, lv.targets.backgroundColor.view,
              lv.targets.next.backgroundColor, 0, w[n]);
}

// The last cross-fade step: the next set copied whole into the visible one, colour and depth.
Status recordFadeCopy(LayeredVegetation& lv, VkCommandBuffer cmd) {
  Device& d = *lv.device;
  auto copy = [&](const Image& from, const Image& to) {
    VkImageCopy r{};
    r.srcSubresource = {from.aspect, 0, 0, from.layers};
    r.dstSubresource = {to.aspect, 0, 0, to.layers};
    r.extent = {lv.desc.width, lv.desc.height, 1};
    d.vk.CmdCopyImage(cmd, from.image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, to.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &r);
  };
  copy(lv.targets.next.color, lv.targets.color);
  copy(lv.targets.next.depth, lv.targets.depth);
  copy(lv.targets.next.backgroundColor, lv.targets.backgroundColor);
  copy(lv.targets.next.backgroundDepth, lv.targets.backgroundDepth);
  return Status();
}

}  // namespace

Status addLayerPasses(LayeredVegetation& lv, rg::RenderGraph& g, LayerResources* out) {
  if (!lv.device) return Status::error("addLayerPasses: the layered vegetation was not created");
  const rg::State rest = rg::stateOf(lv.desc.restUse);
  LayerResources r;
  r.color = g.importImage("layers: colour", descOf(lv.targets.color), rest, rest);
  r.depth = g.importImage("layers: depth", descOf(lv.targets.depth), rest, rest);
  if (lv.desc.writeIds) r.ids = g.importImage("layers: ids", descOf(lv.targets.ids), rest, rest);
  r.backgroundColor = g.importImage("background: colour", descOf(lv.targets.backgroundColor), rest, rest);
  r.backgroundDepth = g.importImage("background: depth", descOf(lv.targets.backgroundDepth), rest, rest);
  MeshResources mesh;
  CANOPY_TRY(importMesh(lv.mesh, g, &mesh));
  r.meshVertices = mesh.vertices;
  r.meshIndices = mesh.indices;
  r.meshRoots = mesh.roots;
  const auto frame = g.importBuffer("layers: frame", lv.visible.frameBuffer.size, kFrameRead, kFrameRead);
  // Impostors (render/impostor_gpu.cpp): the re-slice's list, the box table and the baked atlas.
  rg::ResourceId impostorList = rg::kInvalidResource, impostorBoxes = rg::kInvalidResource,
                 atlasColor = rg::kInvalidResource, atlasDepth = rg::kInvalidResource;
  if (lv.impostors.enabled) {
    const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
    impostorList = g.importBuffer("impostors: instances", lv.impostors.instances.size, kFrameRead, kFrameRead);
    impostorBoxes = g.importBuffer("impostors: boxes", lv.impostors.boxTable.size, kFrameRead, kFrameRead);
    atlasColor = g.importImage("impostors: colour atlas", descOf(lv.impostors.color), sampled, sampled);
    atlasDepth = g.importImage("impostors: depth atlas", descOf(lv.impostors.depth), sampled, sampled);
    CANOPY_TRY(g.bindBuffer(impostorList, lv.impostors.instances.buffer));
    CANOPY_TRY(g.bindBuffer(impostorBoxes, lv.impostors.boxTable.buffer));
    CANOPY_TRY(g.bindImage(atlasColor, lv.impostors.color));
    CANOPY_TRY(g.bindImage(atlasDepth, lv.impostors.depth));
  }
  LayeredVegetation* p = &lv;
  // What every mesh draw reads: the frame block and the chunked mesh.
  auto drawsMesh = [&](rg::RenderGraph::PassBuilder b) { return readsMesh(b.access(frame, kFrameRead), mesh); };
  // The frame block holds the placement being drawn: the visible one for a re-slice at once, the
  // spread re-slice's from its first slice on.
  // Every layer pass runs only in the frames that have its work (rg `when`): a still frame records
  // neither the passes nor their barriers (the layer images stay in their rest state).
  auto constants = g.addPass("layers: frame constants", [p](rg::PassContext& c) {
     if (p->reslice.rebuildPending) c.device->vk.CmdUpdateBuffer(c.cmd, p->visible.frameBuffer.buffer, 0, sizeof(gpu::LayerFrame), &p->visible.frame);
     // A spread re-slice's first slice: its frame block, and its cut's impostor list (the visible
     // set's list was read only by the draw that made it); lists in vkCmdUpdateBuffer's 64 KiB pieces.
     const bool first = !p->reslice.rebuildPending && p->reslice.slicePending && p->reslice.spread.sliceClears;
     if (first) c.device->vk.CmdUpdateBuffer(c.cmd, p->visible.frameBuffer.buffer, 0, sizeof(gpu::LayerFrame), &p->reslice.spread.job.frame);
     const std::vector<gpu::ImpostorInstance>& list =
         p->reslice.rebuildPending ? p->visible.impostors.instances : p->reslice.spread.impostors.instances;
     if ((p->reslice.rebuildPending || first) && !list.empty()) {
       const size_t bytes = list.size() * sizeof(gpu::ImpostorInstance);
       for (size_t at = 0; at < bytes; at += 65536)
         c.device->vk.CmdUpdateBuffer(c.cmd, p->impostors.instances.buffer, at, std::min<size_t>(65536, bytes - at),
                                      reinterpret_cast<const uint8_t*>(list.data()) + at);
     }
     return Status();
   })
      .write(frame, rg::Use::TransferDst)
      .when([p] { return p->reslice.rebuildPending || (p->reslice.slicePending && p->reslice.spread.sliceClears); });
  if (impostorList != rg::kInvalidResource) constants.write(impostorList, rg::Use::TransferDst);
  auto foliage = g.addPass("layers: foliage", [p](rg::PassContext& c) {
                    return p->reslice.rebuildPending ? recordFoliage(*p, c.cmd, visibleTargets(*p), true, nullptr) : Status();
                  });
  drawsMesh(foliage)
      .write(r.color, rg::Use::ColorAttachmentWrite)
      .write(r.depth, rg::Use::DepthAttachmentWrite)
      .when([p] { return p->reslice.rebuildPending; });
  if (lv.desc.writeIds) foliage.write(r.ids, rg::Use::ColorAttachmentWrite);
  if (lv.impostors.enabled)
    foliage.access(impostorList, kFrameRead)
        .access(impostorBoxes, kFrameRead)
        .read(atlasColor, rg::Use::FragmentSampled)
        .read(atlasDepth, rg::Use::FragmentSampled);
  drawsMesh(g.addPass("layers: background", [p](rg::PassContext& c) {
     return p->reslice.rebuildPending && drawsBackground(*p) ? recordBackground(*p, c.cmd, visibleTargets(*p), true, nullptr)
                                                          : Status();
   }))
      .write(r.backgroundColor, rg::Use::ColorAttachmentWrite)
      .write(r.backgroundDepth, rg::Use::DepthAttachmentWrite)
      .when([p] { return p->reslice.rebuildPending && drawsBackground(*p); });
  if (lv.targets.next.color.image) {
    // Spread re-slicing (docs/design.md "Layers: spread re-slicing"): this frame's slice into the
    // next set (loaded: earlier slices are kept), then a cross-fade step into the visible set.
    const auto nextColor = g.importImage("layers (next set): colour", descOf(lv.targets.next.color), kNextRest, kNextRest);
    const auto nextDepth = g.importImage("layers (next set): depth", descOf(lv.targets.next.depth), kNextRest, kNextRest);
    const auto nextBgColor = g.importImage("background (next set): colour", descOf(lv.targets.next.backgroundColor), kNextRest, kNextRest);
    const auto nextBgDepth = g.importImage("background (next set): depth", descOf(lv.targets.next.backgroundDepth), kNextRest, kNextRest);
    auto slice = g.addPass("layers: spread slice", [p](rg::PassContext& c) -> Status {
       if (!p->reslice.slicePending) return Status();
       const bool clear = p->reslice.spread.sliceClears;
       // The fading impostors come with the last slice, which may hold rigid parts only.
       const bool lastImpostors = p->reslice.spread.sliceLast && p->reslice.spread.impostors.cut.active;
       if (clear || sliceHas(*p, true) || lastImpostors)
         CANOPY_TRY(recordFoliage(*p, c.cmd, nextTargets(*p), clear, &p->reslice.spread.slice));
       if (drawsBackground(*p) && (clear || sliceHas(*p, false)))
         CANOPY_TRY(recordBackground(*p, c.cmd, nextTargets(*p), clear, &p->reslice.spread.slice));
       return Status();
     });
    drawsMesh(slice)
        .write(nextColor, rg::Use::ColorAttachmentReadWrite)
        .write(nextDepth, rg::Use::DepthAttachmentWrite)
        .write(nextBgColor, rg::Use::ColorAttachmentReadWrite)
        .write(nextBgDepth, rg::Use::DepthAttachmentWrite)
        .when([p] { return p->reslice.slicePending; });
    if (lv.impostors.enabled)
      slice.access(impostorList, kFrameRead)
          .access(impostorBoxes, kFrameRead)
          .read(atlasColor, rg::Use::FragmentSampled)
          .read(atlasDepth, rg::Use::FragmentSampled);
    const bool rigid = lv.mesh.hasRigid;
    auto blend = g.addPass("layers: cross-fade", [p](rg::PassContext& c) {
      return p->reslice.fadePending && !p->reslice.spread.fadeCopy ? recordFadeBlend(*p, c.cmd) : Status();
    });
    blend.read(nextColor, rg::Use::FragmentSampled).write(r.color, rg::Use::ColorAttachmentReadWrite);
    blend.read(nextDepth, rg::Use::FragmentSampled).write(r.depth, rg::Use::DepthAttachmentWrite);
    blend.when([p] { return p->reslice.fadePending && !p->reslice.spread.fadeCopy; });
    if (rigid) blend.read(nextBgColor, rg::Use::FragmentSampled).write(r.backgroundColor, rg::Use::ColorAttachmentReadWrite);
    g.addPass("layers: cross-fade (last step)", [p](rg::PassContext& c) {
       return p->reslice.fadePending && p->reslice.spread.fadeCopy ? recordFadeCopy(*p, c.cmd) : Status();
     })
        .read(nextColor, rg::Use::TransferSrc)
        .read(nextDepth, rg::Use::TransferSrc)
        .read(nextBgColor, rg::Use::TransferSrc)
        .read(nextBgDepth, rg::Use::TransferSrc)
        .write(r.color, rg::Use::TransferDst)
        .write(r.depth, rg::Use::TransferDst)
        .write(r.backgroundColor, rg::Use::TransferDst)
        .write(r.backgroundDepth, rg::Use::TransferDst)
        .when([p] { return p->reslice.fadePending && p->reslice.spread.fadeCopy; });
    r.nextColor = nextColor;
    r.nextBackgroundColor = nextBgColor;
    CANOPY_TRY(g.bindImage(nextColor, lv.targets.next.color));
    CANOPY_TRY(g.bindImage(nextDepth, lv.targets.next.depth));
    CANOPY_TRY(g.bindImage(nextBgColor, lv.targets.next.backgroundColor));
    CANOPY_TRY(g.bindImage(nextBgDepth, lv.targets.next.backgroundDepth));
  }
  CANOPY_TRY(g.bindImage(r.color, lv.targets.color));
  CANOPY_TRY(g.bindImage(r.depth, lv.targets.depth));
  if (lv.desc.writeIds) CANOPY_TRY(g.bindImage(r.ids, lv.targets.ids));
  CANOPY_TRY(g.bindImage(r.backgroundColor, lv.targets.backgroundColor));
  CANOPY_TRY(g.bindImage(r.backgroundDepth, lv.targets.backgroundDepth));
  CANOPY_TRY(g.bindBuffer(frame, lv.visible.frameBuffer.buffer));
  if (out) *out = r;
  return Status();
}

}  // namespace canopy
