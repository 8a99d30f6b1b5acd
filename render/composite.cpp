#include "render/composite.h"

#include <cmath>
#include <string>

#include "compute/dynamics.h"
#include "engine/device.h"
#include "engine/pass_slots.h"

namespace canopy {
namespace {

uint32_t tilesFor(uint32_t pixels) { return (pixels + COMPOSITE_TILE - 1) / COMPOSITE_TILE; }

bool isMotionFormat(VkFormat f) { return f == VK_FORMAT_R16G16_SFLOAT || f == VK_FORMAT_R32G32_SFLOAT; }

Status makeSampler(Device& d, VkFilter filter, VkBorderColor border, VkSampler* out) {
  VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  si.magFilter = si.minFilter = filter;
  si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  // Outside a layer there is nothing: transparent colour, far depth.
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_BORDER;
  si.borderColor = border;
  si.maxLod = 0.0f;
  CANOPY_VK(d.vk.CreateSampler(d.device, &si, d.allocationCallbacks, out));
  return Status();
}

// The compute path (CompositePath::Compute; docs/performance.md): displacement image, tile list
// reset, classification, the tile kernel (indirect dispatch) and the resolve draw (indirect).
Status addComputePath(Compositor& c, rg::RenderGraph& g, const LayerResources& l, rg::ResourceId displacement,
                      rg::ResourceId previous, const CompositeTargets& t, rg::ResourceId sums, rg::ResourceId view) {
  // Every frame rewrites these images before reading them: they enter with their contents
  // discarded (UNDEFINED), ordered after the previous frame's reads.
  const rg::State fs = rg::stateOf(rg::Use::FragmentSampled), indirect = rg::stateOf(rg::Use::IndirectBuffer);
  const rg::State discard{VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
                          VK_ACCESS_2_SHADER_SAMPLED_READ_BIT, VK_IMAGE_LAYOUT_UNDEFINED};
  const auto dispImage = g.importImage("composite: displacement image", descOf(c.displacementImage), discard, fs);
  const auto composed = g.importImage("composite: composed pixels", descOf(c.composed), discard, fs);
  const auto tileList = g.importBuffer("composite: tile list", c.tileList.size, indirect, indirect);
  CANOPY_TRY(g.bindImage(dispImage, c.displacementImage));
  CANOPY_TRY(g.bindImage(composed, c.composed));
  CANOPY_TRY(g.bindBuffer(tileList, c.tileList.buffer));
  Compositor* cp = &c;
  // The compute path's passes run in the frames prepareComposite chose it (the graph leaves them
  // and their barriers out in the others; the fragment path's passes are their complement).
  auto computePath = [cp] { return cp->computeThisFrame; };
  using rg::Use;
  rg::addSlotPass(g, "composite: displacement image",
                  {rg::slot(displacement, Use::ComputeStorageRead), rg::slot(previous, Use::ComputeStorageRead),
                   rg::slot(dispImage, Use::ComputeStorageWrite)},
                  [cp](rg::PassContext& x, const rg::Slots& s) {
                    const gpu::CompositePush& p = cp->push;
                    return rg::dispatchSlots(x, cp->displacementPipeline, s, p.gridX * p.gridY, p.layerCount, 1, p);
                  })
      .when(computePath);
  g.addPass("composite: tile list reset", [cp](rg::PassContext& x) {
     const gpu::CompositeTileHeader empty{0, 1, 1, 0, 6, 0, 0, 0};
     x.device->vk.CmdUpdateBuffer(x.cmd, cp->tileList.buffer, 0, sizeof empty, &empty);
     return Status();
   })
      .write(tileList, rg::Use::TransferDst)
      .when(computePath);
  rg::addSlotPass(g, "composite: classify",
                  {rg::slot(dispImage, Use::ComputeSampled, c.displacementSampler), rg::slot(sums, Use::ComputeStorageRead),
                   rg::slot(tileList, Use::ComputeStorageReadWrite), rg::slot(view, Use::ComputeUniform)},
                  [cp](rg::PassContext& x, const rg::Slots& s) {
                    const gpu::CompositePush& p = cp->push;
                    return rg::dispatchSlots(x, cp->classifyPipeline, s, p.tilesX * p.tilesY, 1, 1, p);
                  })
      .when(computePath);
  // The layer colour's sampler follows CompositeParams.bilinear (slot 0's, chosen per frame).
  const rg::Slots tileSlots = {rg::slot(l.color, Use::ComputeSampled, c.linear),
                               rg::slot(l.depth, Use::ComputeSampled, c.depthSampler),
                               rg::slot(l.backgroundColor, Use::ComputeSampled, c.nearest),
                               rg::slot(l.backgroundDepth, Use::ComputeSampled, c.depthSampler),
                               rg::slot(t.depth, Use::ComputeSampled, c.depthSampler),
                               rg::slot(dispImage, Use::ComputeSampled, c.displacementSampler),
                               rg::slot(tileList, Use::ComputeStorageRead),
                               rg::slot(composed, Use::ComputeStorageWrite),
                               rg::slot(view, Use::ComputeUniform)};
  rg::addSlotPass(g, "composite: warp + composite (tiles)", tileSlots, [cp](rg::PassContext& x, const rg::Slots& s) {
    rg::Slots now = s;
    now[0].sampler = cp->params.bilinear ? cp->linear : cp->nearest;
    return rg::dispatchIndirectSlots(x, cp->tilesPipelines[gpu::compositeTileVariant(cp->push.flags)], now, cp->tileList.buffer, 0,
                                     cp->push);
  })
      .read(tileList, rg::Use::IndirectBuffer)  // the dispatch's arguments, not a descriptor
      .when(computePath);
  const bool hasMotion = c.desc.motionFormat != VK_FORMAT_UNDEFINED;
  auto resolve = rg::addSlotPass(g, "composite: resolve",
                                 {rg::slot(tileList, Use::VertexStorageRead), rg::slot(composed, Use::FragmentSampled, c.nearest)},
                                 [cp, t, hasMotion](rg::PassContext& x, const rg::Slots& slots) {
                                   beginHostRendering(x, t, cp->desc.width, cp->desc.height, hasMotion);
                                   Status s = rg::bindGraphicsSlots(x, cp->resolve, slots, cp->push);
                                   if (s.ok())
                                     x.device->vk.CmdDrawIndirect(x.cmd, cp->tileList.buffer,
                                                                  offsetof(gpu::CompositeTileHeader, vertexCount), 1, 0);
                                   x.device->cmdEndRendering(x.cmd);
                                   return s;
                                 });
  resolve.read(tileList, rg::Use::IndirectBuffer)
      .write(t.color, rg::Use::ColorAttachmentReadWrite)
      .write(t.depth, rg::Use::DepthAttachmentWrite);
  if (hasMotion) resolve.write(t.motion, rg::Use::ColorAttachmentReadWrite);
  resolve.when(computePath);
  return Status();
}

}  // namespace

// Rendering into the host's targets with their contents kept (colour and motion blended over,
// depth written): the fragment path's composite and the compute path's resolve.
void beginHostRendering(rg::PassContext& x, const CompositeTargets& t, uint32_t width, uint32_t height, bool motion) {
  VkRenderingAttachmentInfo colors[2] = {{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO},
                                         {VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO}};
  colors[0].imageView = x.graph->image(t.color).view;
  colors[0].imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  colors[0].loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
  colors[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  if (motion) {
    colors[1] = colors[0];
    colors[1].imageView = x.graph->image(t.motion).view;
  }
  VkRenderingAttachmentInfo depth{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  depth.imageView = x.graph->image(t.depth).view;
  depth.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
  depth.loadOp = VK_ATTACHMENT_LOAD_OP_LOAD;
  depth.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
  VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
  // The viewport's rectangle: the projection maps into it (render/host_camera.h), the scissor keeps
  // the foliage reaching past it off the rest of the host's image.
  const VkRect2D area = t.scissor ? *t.scissor : VkRect2D{{0, 0}, {width, height}};
  ri.renderArea = area;
  ri.layerCount = 1;
  ri.colorAttachmentCount = motion ? 2 : 1;
  ri.pColorAttachments = colors;
  ri.pDepthAttachment = &depth;
  x.device->cmdBeginRendering(x.cmd, &ri);
  setViewportScissor(*x.device, x.cmd, width, height);
  if (t.scissor) x.device->vk.CmdSetScissor(x.cmd, 0, 1, &area);
}

Status validateCompositeParams(const CompositeParams& p) {
  static_assert(COMPOSITE_DEBUG_GRID == 3, "CANOPY_COMPOSITE_PARAMS's debugView range");
  return checkParams(p, "CompositeParams.");
}

Status validateCompositorDesc(Device& d, const CompositorDesc& desc) {
  if (desc.width < 1 || desc.height < 1 || desc.width > 16384 || desc.height > 16384)
    return Status::error("compositor: size " + std::to_string(desc.width) + "x" + std::to_string(desc.height) +
                         " is outside 1..16384 per side");
  if (desc.guardX % COMPOSITE_TILE != 0 || desc.guardY % COMPOSITE_TILE != 0 || compositorLayerWidth(desc) > 16384 ||
      compositorLayerHeight(desc) > 16384)
    return Status::error("compositor: guard band " + std::to_string(desc.guardX) + "x" + std::to_string(desc.guardY) +
                         " px is not a multiple of " + std::to_string(COMPOSITE_TILE) + " or makes the layers wider than 16384");
  if (desc.minCellSize < 2 || desc.minCellSize > 256)
    return Status::error("compositor: minCellSize = " + std::to_string(desc.minCellSize) + " is outside 2..256");
  if (desc.maxLayers < 1 || desc.maxLayers > CANOPY_MAX_LAYERS)
    return Status::error("compositor: maxLayers = " + std::to_string(desc.maxLayers) + " is outside 1.." +
                         std::to_string(CANOPY_MAX_LAYERS));
  if (desc.tilesPerGroup > 64)
    return Status::error("compositor: tilesPerGroup = " + std::to_string(desc.tilesPerGroup) + " is outside 0..64 (0 = by device class)");
  VkFormatProperties fp{};
  d.vk.GetPhysicalDeviceFormatProperties(d.physical, desc.colorFormat, &fp);
  const VkFormatFeatureFlags blendable = VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT;
  if ((fp.optimalTilingFeatures & blendable) != blendable)
    return Status::error(Result::UnsupportedDevice, "compositor: colour format " + std::to_string(int(desc.colorFormat)) +
                         " is not a blendable colour attachment on this device");
  // Depth-stencil formats: only the depth aspect is read (the host's depth-only view) and written
  // (no stencil attachment), so the stencil stays as the host left it.
  const VkFormat df = desc.depthFormat;
  if (df != VK_FORMAT_D32_SFLOAT && df != VK_FORMAT_D16_UNORM && df != VK_FORMAT_D24_UNORM_S8_UINT &&
      df != VK_FORMAT_D32_SFLOAT_S8_UINT)
    return Status::error(Result::UnsupportedDevice, "compositor: depth format " + std::to_string(int(df)) +
                         " is not supported (D32_SFLOAT, D16_UNORM, D24_UNORM_S8_UINT or D32_SFLOAT_S8_UINT, with sampled usage)");
  d.vk.GetPhysicalDeviceFormatProperties(d.physical, desc.depthFormat, &fp);
  const VkFormatFeatureFlags depthNeeds = VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT;
  if ((fp.optimalTilingFeatures & depthNeeds) != depthNeeds)
    return Status::error(Result::UnsupportedDevice, "compositor: depth format " + std::to_string(int(desc.depthFormat)) +
                         " cannot be both sampled and a depth attachment on this device");
  if (desc.motionFormat != VK_FORMAT_UNDEFINED && !isMotionFormat(desc.motionFormat))
    return Status::error("compositor: motion format " + std::to_string(int(desc.motionFormat)) +
                         " is not supported (R16G16_SFLOAT or R32G32_SFLOAT, or UNDEFINED for none)");
  return Status();
}

Status createCompositor(Device& d, const CompositorDesc& desc, Compositor* out) {
  *out = Compositor{};
  CANOPY_TRY(validateCompositorDesc(d, desc));
  out->device = &d;
  out->desc = desc;
  Status s = [&]() -> Status {
    GraphicsPipelineDesc gp;
    gp.vertexShader = "composite.vert";
    gp.fragmentShader = "composite.frag";
    gp.pushConstantSize = sizeof(gpu::CompositePush);
    gp.colorFormats = {desc.colorFormat};
    if (desc.motionFormat != VK_FORMAT_UNDEFINED) gp.colorFormats.push_back(desc.motionFormat);
    gp.depthFormat = desc.depthFormat;
    // Premultiplied "over" on both attachments: the motion output carries a = 1 where the
    // vegetation is frontmost (replace) and a = 0 elsewhere (keep the host's).
    gp.blend = BlendMode::PremultipliedOver;
    gp.blendedAttachments = uint32_t(gp.colorFormats.size());
    gp.depthTest = true;  // the test is ALWAYS: the shader already ordered everything by depth
    gp.depthCompare = VK_COMPARE_OP_ALWAYS;
    gp.depthWrite = true;
    CANOPY_TRY(createGraphicsPipeline(d, gp, &out->composite));
    ComputePipelineDesc cp;
    cp.pushConstantSize = sizeof(gpu::CompositePush);
    cp.shader = "composite_scene_depth.comp";
    CANOPY_TRY(createComputePipeline(d, cp, &out->sceneDepthPipeline));
    cp.shader = "composite_occupancy.comp";
    CANOPY_TRY(createComputePipeline(d, cp, &out->occupancyPipeline));
    cp.shader = "composite_occupancy_sums.comp";
    CANOPY_TRY(createComputePipeline(d, cp, &out->occupancySumsPipeline));
    const uint32_t layerW = compositorLayerWidth(desc), layerH = compositorLayerHeight(desc);
    const VkDeviceSize tiles = VkDeviceSize(tilesFor(desc.width)) * tilesFor(desc.height);
    const VkDeviceSize layerTiles = VkDeviceSize(tilesFor(layerW)) * tilesFor(layerH);
    CANOPY_TRY(createBuffer(d, layerTiles * (desc.maxLayers + 1) * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUsage::DeviceLocal,
                            &out->occupancy, "composite: occupancy"));
    CANOPY_TRY(createBuffer(d, VkDeviceSize(gpu::compositeSumsEntries(tilesFor(layerW), tilesFor(layerH), desc.maxLayers + 1)) * 4,
                            VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUsage::DeviceLocal, &out->occupancySums,
                            "composite: occupancy sums"));
    // Compute path: needs RGBA32F as a linearly filtered storage image (the displacement image).
    VkFormatProperties df{};
    d.vk.GetPhysicalDeviceFormatProperties(d.physical, VK_FORMAT_R32G32B32A32_SFLOAT, &df);
    const VkFormatFeatureFlags dispNeeds = VK_FORMAT_FEATURE_STORAGE_IMAGE_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT |
                                           VK_FORMAT_FEATURE_SAMPLED_IMAGE_FILTER_LINEAR_BIT;
    out->computeAvailable = (df.optimalTilingFeatures & dispNeeds) == dispNeeds;
    if (out->computeAvailable) {
      cp.shader = "composite_displacement.comp";
      CANOPY_TRY(createComputePipeline(d, cp, &out->displacementPipeline));
      cp.shader = "composite_classify.comp";
      CANOPY_TRY(createComputePipeline(d, cp, &out->classifyPipeline));
      GraphicsPipelineDesc rp = gp;
      rp.vertexShader = "composite_resolve.vert";
      rp.fragmentShader = "composite_resolve.frag";
      CANOPY_TRY(createGraphicsPipeline(d, rp, &out->resolve));
      ImageDesc id;
      id.format = VK_FORMAT_R32G32B32A32_SFLOAT;
      id.width = gridCorners(layerW, desc.minCellSize);
      id.height = gridCorners(layerH, desc.minCellSize);
      id.layers = desc.maxLayers;
      id.usage = VK_IMAGE_USAGE_STORAGE_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
      id.arrayView = true;
      CANOPY_TRY(createImage(d, id, &out->displacementImage, "composite: displacement image"));
      id.width = desc.width;
      id.height = desc.height;
      id.layers = 1;
      id.arrayView = false;
      id.format = VK_FORMAT_R32G32B32A32_UINT;  // storage support is required of every device
      CANOPY_TRY(createImage(d, id, &out->composed, "composite: composed pixels"));
      CANOPY_TRY(createBuffer(d, sizeof(gpu::CompositeTileHeader) + tiles * 8,
                              VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_INDIRECT_BUFFER_BIT |
                                  VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                              MemoryUsage::DeviceLocal, &out->tileList, "composite: tile list"));
      VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
      si.magFilter = si.minFilter = VK_FILTER_LINEAR;
      si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
      si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
      si.maxLod = 0.0f;
      CANOPY_VK(d.vk.CreateSampler(d.device, &si, d.allocationCallbacks, &out->displacementSampler));
    }
    CANOPY_TRY(createBuffer(d, VkDeviceSize(desc.width) * desc.height * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                            MemoryUsage::DeviceLocal, &out->sceneDepth, "composite: scene depth"));
    CANOPY_TRY(createBuffer(d, sizeof(gpu::AnimFrame), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUsage::DeviceLocal,
                            &out->debugStandIn, "composite: debug stand-in"));
    CANOPY_TRY(createBuffer(d, sizeof(gpu::CompositeView), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                            MemoryUsage::DeviceLocal, &out->viewBuffer, "composite: view"));
    CANOPY_TRY(makeSampler(d, VK_FILTER_LINEAR, VK_BORDER_COLOR_FLOAT_TRANSPARENT_BLACK, &out->linear));
    CANOPY_TRY(makeSampler(d, VK_FILTER_NEAREST, VK_BORDER_COLOR_FLOAT_TRANSPARENT_BLACK, &out->nearest));
    CANOPY_TRY(makeSampler(d, VK_FILTER_NEAREST, VK_BORDER_COLOR_FLOAT_OPAQUE_WHITE, &out->depthSampler));
    return Status();
  }();
  if (!s.ok()) destroyCompositor(*out);
  return s;
}

void destroyCompositor(Compositor& c) {
  if (!c.device) return;
  Device& d = *c.device;
  destroyGraphicsPipeline(d, c.composite);
  destroyComputePipeline(d, c.occupancyPipeline);
  destroyComputePipeline(d, c.occupancySumsPipeline);
  destroyComputePipeline(d, c.sceneDepthPipeline);
  destroyComputePipeline(d, c.displacementPipeline);
  destroyComputePipeline(d, c.classifyPipeline);
  for (ComputePipeline& p : c.tilesPipelines) destroyComputePipeline(d, p);
  destroyGraphicsPipeline(d, c.resolve);
  for (Image* img : {&c.displacementImage, &c.composed}) destroyImage(d, *img);
  destroyBuffer(d, c.tileList);
  destroyBuffer(d, c.occupancy);
  destroyBuffer(d, c.occupancySums);
  destroyBuffer(d, c.sceneDepth);
  destroyBuffer(d, c.debugStandIn);
  destroyBuffer(d, c.viewBuffer);
  for (VkSampler s : {c.linear, c.nearest, c.depthSampler, c.displacementSampler})
    if (s) d.vk.DestroySampler(d.device, s, d.allocationCallbacks);
  c = Compositor{};
}

Status prepareComposite(Compositor& c, const CompositeParams& params, const gpu::AnimFrame& anim, bool hasBackground,
                        bool layersRebuilt, bool motionValid, const VkRect2D* foliageRect, bool uniteNext) {
  if (!c.device) return Status::error("prepareComposite: the compositor was not created");
  // `params` were checked when they were given (validateCompositeParams; setCanopyParams).
  if (anim.layerCount < 1 || anim.layerCount > c.desc.maxLayers)
    return Status::error("prepareComposite: " + std::to_string(anim.layerCount) + " layers, the compositor holds 1.." +
                         std::to_string(c.desc.maxLayers));
  const uint32_t layerW = compositorLayerWidth(c.desc), layerH = compositorLayerHeight(c.desc);
  if (uint32_t(anim.width) != layerW || uint32_t(anim.height) != layerH)
    return Status::error("prepareComposite: the dynamics frame is " + std::to_string(uint32_t(anim.width)) + "x" +
                         std::to_string(uint32_t(anim.height)) + ", the compositor's layers " + std::to_string(layerW) + "x" +
                         std::to_string(layerH));
  gpu::CompositePush& p = c.push;
  p = gpu::CompositePush{};
  p.layerCount = anim.layerCount;
  p.gridX = anim.gridX;
  p.gridY = anim.gridY;
  p.cellSize = anim.cellSize;
  p.width = float(c.desc.width);
  p.height = float(c.desc.height);
  p.depthAlpha = params.depthAlpha;
  p.tilesX = tilesFor(c.desc.width);
  p.tilesY = tilesFor(c.desc.height);
  p.layerWidth = float(layerW);
  p.layerHeight = float(layerH);
  p.originX = float(c.desc.guardX);
  p.originY = float(c.desc.guardY);
  p.layerTilesX = tilesFor(layerW);
  p.layerTilesY = tilesFor(layerH);
  p.halfResolution = anim.halfResolution;
  p.occupancyX1 = p.layerTilesX;
  p.occupancyY1 = p.layerTilesY;
  if (foliageRect) {
    // One tile of margin: a tile counts the texels one pixel around it.
    const uint32_t x0 = uint32_t(std::max(foliageRect->offset.x, 0)), y0 = uint32_t(std::max(foliageRect->offset.y, 0));
    p.occupancyX0 = std::min(x0 / COMPOSITE_TILE, p.layerTilesX) - std::min(x0 / COMPOSITE_TILE, 1u);
    p.occupancyY0 = std::min(y0 / COMPOSITE_TILE, p.layerTilesY) - std::min(y0 / COMPOSITE_TILE, 1u);
    p.occupancyX1 = std::min(tilesFor(x0 + foliageRect->extent.width) + 1, p.layerTilesX);
    p.occupancyY1 = std::min(tilesFor(y0 + foliageRect->extent.height) + 1, p.layerTilesY);
  }
  p.debugView = uint32_t(params.debugView);
  p.debugScale = params.debugVelocityScale;
  p.exposure = params.exposure;
  p.sharpness = params.bilinear ? params.sharpness : 1.0f;
  p.flags = COMPOSITE_SCENE_DEPTH;
  if (c.desc.reverseZ) p.flags |= COMPOSITE_REVERSE_Z;
  if (params.earlyExit) p.flags |= COMPOSITE_EARLY_EXIT;
  if (params.skipEmptyTiles) p.flags |= COMPOSITE_SKIP_EMPTY;
  if (params.bilinear) p.flags |= COMPOSITE_BILINEAR;
  if (c.desc.motionFormat != VK_FORMAT_UNDEFINED) p.flags |= COMPOSITE_MOTION;
  if (motionValid) p.flags |= COMPOSITE_MOTION_VALID;
  if (hasBackground) p.flags |= COMPOSITE_BACKGROUND;
  c.computeThisFrame = params.path == CompositePath::Compute && params.debugView == CompositeDebugView::None &&
                       c.computeAvailable;
  if (c.computeThisFrame && (anim.gridX > c.displacementImage.extent.width || anim.gridY > c.displacementImage.extent.height))
    return Status::error("prepareComposite: the warp grid (" + std::to_string(anim.gridX) + "x" + std::to_string(anim.gridY) +
                         ") exceeds the compositor's displacement image, sized for cells down to " +
                         std::to_string(c.desc.minCellSize) + " pixels");
  p.dispWidth = c.displacementImage.extent.width;
  p.dispHeight = c.displacementImage.extent.height;
  // A workgroup launch on lavapipe costs more than one 8x8 tile's pixels (docs/performance.md);
  // GPUs want one workgroup per tile for parallelism.
  const bool cpuDevice = cpuClass(*c.device);
  p.tilesPerGroup = c.desc.tilesPerGroup != 0 ? c.desc.tilesPerGroup : cpuDevice ? 16u : 1u;
  if (c.computeAvailable) {
    // Both variants of this bilinear setting (a still frame's and a moving camera's), so the first
    // moving frame does not compile one.
    for (uint32_t reproject : {0u, COMPOSITE_VARIANT_REPROJECT}) {
      const uint32_t v = reproject | (params.bilinear ? COMPOSITE_VARIANT_BILINEAR : 0u);
      if (c.tilesPipelines[v].pipeline != VK_NULL_HANDLE) continue;
      ComputePipelineDesc cp;
      cp.pushConstantSize = sizeof(gpu::CompositePush);
      cp.shader = "composite_tiles.comp";
      cp.specialization = {v};
      CANOPY_TRY(createComputePipeline(*c.device, cp, &c.tilesPipelines[v]));
    }
  }
  c.params = params;
  c.occupancyPending = c.occupancyPending || layersRebuilt;
  c.occupancyUnitePending = c.occupancyUnitePending || uniteNext;
  return Status();
}

void setCompositeReprojection(Compositor& c, const gpu::CompositeView* view) {
  if (view) {
    c.view = *view;
    c.push.flags |= COMPOSITE_REPROJECT;
  } else {
    c.push.flags &= ~COMPOSITE_REPROJECT;
  }
}

Status addCompositePasses(Compositor& c, rg::RenderGraph& g, const LayerResources& layers, rg::ResourceId displacement,
                          rg::ResourceId previous, const CompositeTargets& t, const CompositeDebugSources& debug) {
  if (!c.device) return Status::error("addCompositePasses: the compositor was not created");
  if (t.color == rg::kInvalidResource || t.depth == rg::kInvalidResource)
    return Status::error("addCompositePasses: the host's colour and depth targets are required");
  const bool motion = c.desc.motionFormat != VK_FORMAT_UNDEFINED;
  if (motion != (t.motion != rg::kInvalidResource))
    return Status::error(motion ? "addCompositePasses: the compositor was created with a motion format but no motion target was given"
                                : "addCompositePasses: a motion target was given but the compositor has no motion format");
  const rg::State storageRead = rg::stateOf(rg::Use::ComputeStorageRead);
  const auto occupancy = g.importBuffer("composite: occupancy", c.occupancy.size, storageRead, storageRead);
  const auto sums = g.importBuffer("composite: occupancy sums", c.occupancySums.size, storageRead, storageRead);
  const auto scene = g.importBuffer("composite: scene depth", c.sceneDepth.size, storageRead, storageRead);
  // A uniform buffer: its reads are the same for every lane (CPU drivers load storage buffers lane by lane).
  const rg::State uniformRead = rg::stateOf(rg::Use::ComputeUniform);
  const auto view = g.importBuffer("composite: view", c.viewBuffer.size, uniformRead, uniformRead);
  CANOPY_TRY(g.bindBuffer(occupancy, c.occupancy.buffer));
  CANOPY_TRY(g.bindBuffer(sums, c.occupancySums.buffer));
  CANOPY_TRY(g.bindBuffer(scene, c.sceneDepth.buffer));
  CANOPY_TRY(g.bindBuffer(view, c.viewBuffer.buffer));
  Compositor* cp = &c;
  g.addPass("composite: view", [cp](rg::PassContext& x) {
     x.device->vk.CmdUpdateBuffer(x.cmd, cp->viewBuffer.buffer, 0, sizeof(gpu::CompositeView), &cp->view);
     return Status();
   })
      .write(view, rg::Use::TransferDst)
      .when([cp] { return (cp->push.flags & COMPOSITE_REPROJECT) != 0u; });
  const LayerResources l = layers;
  // One dispatch a frame: a pending recompute from the visible layers first, a union with the next
  // set (spread re-slicing) in the frame after if both are pending.
  // Slots 3 and 4 are the next set's images (spread re-slicing; without it the visible set's
  // again); a frame that does not unite the two binds the visible set's there too (the union flag
  // off, the shader does not read them).
  using rg::Use;
  const bool hasNext = l.nextColor != rg::kInvalidResource;
  const rg::Slots occupancySlots = {rg::slot(l.color, Use::ComputeSampled, c.nearest), rg::slot(occupancy, Use::ComputeStorageReadWrite),
                                    rg::slot(l.backgroundColor, Use::ComputeSampled, c.nearest),
                                    rg::slot(hasNext ? l.nextColor : l.color, Use::ComputeSampled, c.nearest),
                                    rg::slot(hasNext ? l.nextBackgroundColor : l.backgroundColor, Use::ComputeSampled, c.nearest)};
  rg::addSlotPass(g, "composite: occupancy", occupancySlots, [cp, l, hasNext](rg::PassContext& x, const rg::Slots& s) {
    const bool unite = !cp->occupancyPending && cp->occupancyUnitePending && hasNext;
    if (unite) cp->occupancyUnitePending = false;
    cp->occupancyPending = false;
    gpu::CompositePush p = cp->push;
    if (unite) p.flags |= COMPOSITE_OCCUPANCY_UNION;
    rg::Slots now = s;
    if (!unite) now[3] = s[0], now[4] = s[2];
    return rg::dispatchSlots(x, cp->occupancyPipeline, now, p.layerTilesX * p.layerTilesY, p.layerCount + 1, 1, p);
  }).when([cp, hasNext] { return cp->occupancyPending || (cp->occupancyUnitePending && hasNext); });
  // Whenever the occupancy changes (the graph reads every pass's condition before recording, so
  // this one sees the flags the occupancy pass clears).
  rg::addSlotPass(g, "composite: occupancy sums",
                  {rg::slot(occupancy, Use::ComputeStorageRead), rg::slot(sums, Use::ComputeStorageWrite)},
                  [cp](rg::PassContext& x, const rg::Slots& s) {
                    const gpu::CompositePush& p = cp->push;
                    return rg::dispatchSlots(x, cp->occupancySumsPipeline, s, COMPOSITE_SUMS_GROUP, p.layerCount + 1, 1, p);
                  })
      .when([cp, hasNext] { return cp->occupancyPending || (cp->occupancyUnitePending && hasNext); });
  rg::addSlotPass(g, "composite: scene depth",
                  {rg::slot(t.depth, Use::ComputeSampled, c.depthSampler), rg::slot(scene, Use::ComputeStorageWrite)},
                  [cp](rg::PassContext& x, const rg::Slots& s) {
                    return rg::dispatchSlots(x, cp->sceneDepthPipeline, s, cp->desc.width * cp->desc.height, 1, 1, cp->push);
                  })
      .when([cp] { return !cp->computeThisFrame; });
  const bool debugSources = debug.animFrame != rg::kInvalidResource && debug.tiled != rg::kInvalidResource;
  c.hasDebugSources = debugSources;
  // Without the simulation's field (CompositeDebugSources) the velocity view's two bindings get a
  // stand-in outside the graph; the view is then refused.
  auto debugSlot = [&](rg::ResourceId id) {
    return debugSources ? rg::slot(id, Use::FragmentStorageRead) : rg::outsideGraph(bindBuffer(c.debugStandIn.buffer));
  };
  const rg::Slots fragmentSlots = {rg::slot(l.color, Use::FragmentSampled, c.linear),
                                   rg::slot(l.depth, Use::FragmentSampled, c.depthSampler),
                                   rg::slot(l.backgroundColor, Use::FragmentSampled, c.nearest),
                                   rg::slot(l.backgroundDepth, Use::FragmentSampled, c.depthSampler),
                                   rg::slot(displacement, Use::FragmentStorageRead),
                                   rg::slot(previous, Use::FragmentStorageRead),
                                   rg::slot(occupancy, Use::FragmentStorageRead),
                                   rg::slot(scene, Use::FragmentStorageRead),
                                   debugSlot(debug.animFrame),
                                   debugSlot(debug.tiled),
                                   rg::slot(view, Use::FragmentUniform)};
  auto pass = rg::addSlotPass(g, "composite: warp + composite", fragmentSlots, [cp, t, motion, debugSources](rg::PassContext& x,
                                                                                                        const rg::Slots& slots) {
    const gpu::CompositePush& p = cp->push;
    if (p.debugView == COMPOSITE_DEBUG_VELOCITY && !debugSources)
      return Status::error("composite: the velocity debug view needs the simulation's field (CompositeDebugSources)");
    const Image& color = x.graph->image(t.color);
    const Image& depth = x.graph->image(t.depth);
    if (color.extent.width != cp->desc.width || color.extent.height != cp->desc.height ||
        depth.extent.width != cp->desc.width || depth.extent.height != cp->desc.height)
      return Status::error("composite: the host targets are not " + std::to_string(cp->desc.width) + "x" +
                           std::to_string(cp->desc.height));
    beginHostRendering(x, t, cp->desc.width, cp->desc.height, motion);
    rg::Slots now = slots;
    now[0].sampler = cp->params.bilinear ? cp->linear : cp->nearest;
    Status s = rg::bindGraphicsSlots(x, cp->composite, now, p);
    if (s.ok()) x.device->vk.CmdDraw(x.cmd, 3, 1, 0, 0);
    x.device->cmdEndRendering(x.cmd);
    return s;
  });
  pass.write(t.color, rg::Use::ColorAttachmentReadWrite).write(t.depth, rg::Use::DepthAttachmentWrite);
  if (motion) pass.write(t.motion, rg::Use::ColorAttachmentReadWrite);
  pass.when([cp] { return !cp->computeThisFrame; });
  if (c.computeAvailable) CANOPY_TRY(addComputePath(c, g, layers, displacement, previous, t, sums, view));
  return Status();
}

}  // namespace canopy
