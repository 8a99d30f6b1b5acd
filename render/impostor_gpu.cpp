// The GPU side of the impostors (render/impostors.h; docs/design.md "Impostors"): the atlas, the
// bake (each baked box's views drawn with the layers' own pipeline and shading, orthographic,
// into its tiles) and the draw of a cut's impostors into the layers.
#include "render/impostor_gpu.h"

#include <cstring>
#include <memory>

#include "engine/device.h"
#include "engine/hash.h"
#include "engine/pipeline.h"
#include "engine/shader_registry.h"
#include "engine/transfer.h"
#include "render/cache_file.h"
#include "render/layer_placement.h"
#include "render/layer_targets.h"

namespace canopy {
namespace {

constexpr VkFormat kAtlasColorFormat = VK_FORMAT_R8G8B8A8_UNORM;
constexpr VkFormat kAtlasDepthFormat = VK_FORMAT_D32_SFLOAT;
// The box table and the instance list are read by both stages (the fragment stage reads the box).
const rg::State kImpostorRead{VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                              VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_IMAGE_LAYOUT_UNDEFINED};

// The bake's shaders are part of the cache key: a shading change must not serve stale views.
constexpr const char* kBakeVertexShader = "layers_clip.vert";
constexpr const char* kBakeFragmentShader = "layers.frag";

uint64_t roundUpTo(uint64_t x, uint64_t a) { return (x + a - 1) / a * a; }

Status createDrawPipelines(Device& d, VkFormat colorFormat, Impostors& imp) {
  GraphicsPipelineDesc p;
  p.pushConstantSize = sizeof(gpu::ImpostorPush);
  p.colorFormats = {colorFormat};
  p.depthFormat = VK_FORMAT_D32_SFLOAT;
  p.blend = BlendMode::PremultipliedOver;
  p.fragmentShader = "layers_impostor.frag";
  // Boxes fading in (inside the transition band) are drawn after the leaves without writing depth,
  // so that the fading leaves of the same box are not hidden behind their own impostor.
  for (bool write : {true, false}) {
    p.depthWrite = write;
    if (d.shaderOutputLayer) {
      p.vertexShader = "layers_impostor.vert";
      CANOPY_TRY(createGraphicsPipeline(d, p, write ? &imp.layered : &imp.layeredFade));
    }
    if (d.shaderOutputLayer && d.shaderClipDistance) {
      p.vertexShader = "layers_impostor_half.vert";
      CANOPY_TRY(createGraphicsPipeline(d, p, write ? &imp.layeredHalf : &imp.layeredHalfFade));
    }
    if (d.shaderClipDistance) {
      p.vertexShader = "layers_impostor_clip.vert";
      CANOPY_TRY(createGraphicsPipeline(d, p, write ? &imp.perLayer : &imp.perLayerFade));
    }
  }
  // The bake: the background path of the layers (every triangle, no slicing), into the atlas formats.
  GraphicsPipelineDesc b = layerMeshPipelineDesc(kAtlasColorFormat, kAtlasDepthFormat);
  b.vertexShader = kBakeVertexShader;
  b.fragmentShader = kBakeFragmentShader;
  return createGraphicsPipeline(d, b, &imp.bake);
}

// The bake's frame block of each tile: the layers' lighting, the view's orthographic camera.
std::vector<uint8_t> bakeFrames(const Impostors& imp, const LayerSettings& settings, uint64_t stride) {
  std::vector<uint8_t> bytes(size_t(imp.tiles) * stride, 0);
  gpu::LayerFrame base = cameraFrame(settings, LayerView{});
  base.halfResolution = 0;  // the atlas tiles are drawn whole
  for (const ImpostorNode& n : imp.nodes) {
    if (n.firstTile == kNoTile) continue;
    for (uint32_t k = imp.firstView; k < IMPOSTOR_VIEWS; ++k) {
      gpu::LayerFrame f = base;
      f.viewProj = impostorViewProj(n, k);
      const glm::vec3 dir = gpu::impostorDirection(k);
      f.eye = glm::vec4(dir, 0.0f);
      f.depthRow = glm::vec4(-dir, glm::dot(n.center, dir));
      f.layerCount = 1;
      std::memcpy(bytes.data() + size_t(n.firstTile + k - imp.firstView) * stride, &f, sizeof f);
    }
  }
  return bytes;
}

uint64_t atlasBytes(const Impostors& imp) {
  return uint64_t(imp.atlasLayers) * imp.tilesPerRow * imp.rowsPerLayer * imp.tileSize * imp.tileSize * 4;
}

uint64_t bakeShaderKey() {
  uint64_t h = 0xa4093822299f31d0ull;
  for (const char* name : {kBakeVertexShader, kBakeFragmentShader})
    if (const EmbeddedShader* sh = findEmbeddedShader(name)) h = hashBytes(h, sh->code, sh->sizeBytes);
  return h;
}

// The cached views for `key` (colour, then depth, layer after layer; render/cache_file.h checks
// the header, size and checksum), uploaded into the atlas; false (with the reason) when there are none.
bool readCache(Device& d, Impostors& imp, uint64_t key, std::string* why) {
  const uint64_t bytes = atlasBytes(imp);
  std::vector<uint8_t> payload;
  if (!readCacheFile(imp.cachePath, CacheKind::ImpostorViews, key, 2 * bytes, &payload, why)) return false;
  const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
  Status s = uploadImage(d, &imp.pendingUploads, imp.color, payload.data(), bytes, sampled);
  if (s.ok()) s = uploadImage(d, &imp.pendingUploads, imp.depth, payload.data() + bytes, bytes, sampled);
  if (!s.ok()) {
    *why = s.message();
    return false;
  }
  return true;
}

// The atlas read back into the cache file; `note` gets what the folder's cap evicted.
Status writeCache(Device& d, const Impostors& imp, uint64_t key, std::string* note) {
  const uint64_t bytes = atlasBytes(imp), perLayer = bytes / std::max<uint32_t>(imp.atlasLayers, 1);
  std::vector<uint8_t> payload(2 * bytes);
  const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
  for (uint32_t l = 0; l < imp.atlasLayers; ++l) {
    CANOPY_TRY(readbackImage(d, imp.color, l, 4, payload.data() + l * perLayer, sampled));
    CANOPY_TRY(readbackImage(d, imp.depth, l, 4, payload.data() + bytes + l * perLayer, sampled));
  }
  return writeCacheFile(imp.cachePath, CacheKind::ImpostorViews, key, payload.data(), payload.size(), imp.cacheMaxBytes, note);
}

Status bake(Device& d, const ImpostorSources& src, Impostors& imp) {
  const auto t0 = std::chrono::steady_clock::now();
  const uint64_t align = std::max<VkDeviceSize>(d.properties.limits.minStorageBufferOffsetAlignment, 16);
  const uint64_t stride = roundUpTo(sizeof(gpu::LayerFrame), align);
  const std::vector<uint8_t> frames = bakeFrames(imp, *src.settings, stride);
  // The file cache (like the leaf roots'): the key adds the bake's cameras and lighting.
  const uint64_t key = hashBytes(imp.cacheKey ^ bakeShaderKey(), frames.data(), frames.size());
  if (!imp.cachePath.empty()) {
    std::string why;
    imp.cacheHit = readCache(d, imp, key, &why);
    imp.cacheNote = imp.cacheHit ? "read " + imp.cachePath : imp.cachePath + ": " + why;
    if (imp.cacheHit) {
      imp.bakeMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      return Status();
    }
  }
  PreparedWork work;
  Buffer frameBuf;
  CANOPY_TRY(createBuffer(d, std::max<uint64_t>(frames.size(), 16), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUsage::Upload,
                          &frameBuf, "impostors: bake frames"));
  work.staging.push_back(frameBuf);  // released with the work
  void* mapped = hostCoherentPointer(d, frameBuf.allocation);
  if (!mapped) return Status::error("impostors: the bake's frame buffer is not host-visible and coherent");
  std::memcpy(mapped, frames.data(), frames.size());
  work.graph = std::make_shared<rg::RenderGraph>();
  rg::RenderGraph& g = *work.graph;
  const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
  const auto color = g.importImage("impostors: colour atlas", descOf(imp.color), {}, sampled);
  const auto depth = g.importImage("impostors: depth atlas", descOf(imp.depth), {}, sampled);
  const auto frameId = g.importBuffer("impostors: bake frames", frameBuf.size, kImpostorRead, kImpostorRead);
  MeshResources mesh;
  CANOPY_TRY(importMesh(*src.mesh, g, &mesh));
  // The draw is recorded when the work is (a host's first frame): the mesh, the copies' table and
  // the atlas are read then, from the vegetation that owns them (their addresses are stable).
  const Impostors* ip = &imp;
  const LayerMesh* meshPart = src.mesh;
  const float transmission = src.settings->leafTransmission, opticalDepth = src.settings->leafOpticalDepth;
  const VkBuffer frameHandle = frameBuf.buffer;
  auto pass = g.addPass("impostors: bake", [ip, meshPart, transmission, opticalDepth, frameHandle, stride](rg::PassContext& c) -> Status {
     const Impostors& im = *ip;
     const Device& dev = *c.device;
     MeshDraw md;
     md.device = c.device;
     md.mesh = meshPart;
     md.instances = im.identityCopy.buffer;
     md.leafTransmission = transmission;
     md.leafOpticalDepth = opticalDepth;
     const uint32_t T = im.tileSize, perLayer = im.tilesPerLayer();
     std::vector<std::vector<ChunkPart>> parts(im.nodes.size());
     for (uint32_t layer = 0; layer < im.atlasLayers; ++layer) {
       VkRenderingAttachmentInfo ca{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
       ca.imageView = im.colorLayerViews[layer];
       ca.imageLayout = VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
       ca.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
       ca.storeOp = VK_ATTACHMENT_STORE_OP_STORE;
       VkRenderingAttachmentInfo da = ca;
       da.imageView = im.depthLayerViews[layer];
       da.imageLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
       da.clearValue.depthStencil = {1.0f, 0};
       VkRenderingInfo ri{VK_STRUCTURE_TYPE_RENDERING_INFO};
       ri.renderArea = {{0, 0}, {im.tilesPerRow * T, im.rowsPerLayer * T}};
       ri.layerCount = 1;
       ri.colorAttachmentCount = 1;
       ri.pColorAttachments = &ca;
       ri.pDepthAttachment = &da;
       dev.cmdBeginRendering(c.cmd, &ri);
       Status s;
       for (uint32_t i = 0; i < im.nodes.size() && s.ok(); ++i) {
         const ImpostorNode& n = im.nodes[i];
         if (n.firstTile == kNoTile) continue;
         for (uint32_t k = im.firstView; k < IMPOSTOR_VIEWS && s.ok(); ++k) {
           const uint32_t tile = n.firstTile + k - im.firstView;
           if (tile / perLayer != layer) continue;
           if (parts[i].empty())
             for (uint32_t m = 0; m < im.materials; ++m)
               appendRunParts(meshPart->chunks, im.ownFirst(i, m), im.subtreeEnd(i, m) - im.ownFirst(i, m), 1.0f, n.level, &parts[i]);
           const uint32_t x = (tile % perLayer) % im.tilesPerRow, y = (tile % perLayer) / im.tilesPerRow;
           const VkViewport vp{float(x * T), float(y * T), float(T), float(T), 0.0f, 1.0f};
           const VkRect2D sc{{int32_t(x * T), int32_t(y * T)}, {T, T}};
           dev.vk.CmdSetViewport(c.cmd, 0, 1, &vp);
           dev.vk.CmdSetScissor(c.cmd, 0, 1, &sc);
           MeshDrawOptions o;
           o.frame = frameHandle;
           o.frameOffset = uint64_t(tile) * stride;
           o.keepViewport = true;
           s = drawMeshParts(md, c.cmd, im.bake, LAYER_PASS_BACKGROUND, 0, parts[i], o);
         }
       }
       dev.cmdEndRendering(c.cmd);
       CANOPY_TRY(s);
     }
     return Status();
   })
      .write(color, rg::Use::ColorAttachmentWrite)
      .write(depth, rg::Use::DepthAttachmentWrite)
      .access(frameId, kImpostorRead);
  readsMesh(pass, mesh);
  CANOPY_TRY(g.bindImage(color, imp.color));
  CANOPY_TRY(g.bindImage(depth, imp.depth));
  CANOPY_TRY(g.bindBuffer(frameId, frameBuf.buffer));
  const bool deferred = d.deferUploads;
  CANOPY_TRY(submitOrDefer(d, std::move(work), &imp.pendingUploads));
  imp.bakeMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (!imp.cachePath.empty()) {
    if (deferred) {
      imp.cacheNote += "; not written: the bake is recorded into the host's first frame";
    } else {
      std::string evicted;
      const Status w = writeCache(d, imp, key, &evicted);
      imp.cacheNote += w.ok() ? "; wrote it" : "; not written: " + w.message();
      if (!evicted.empty()) imp.cacheNote += "; " + evicted;
    }
  }
  return Status();
}

}  // namespace

Status createImpostors(Device& d, const ImpostorSources& src, Impostors& imp) {
  if (!d.shaderClipDistance)
    return Status::error("impostors: the bake needs shaderClipDistance (the layers' background path)");
  ImageDesc c;
  c.format = kAtlasColorFormat;
  c.width = imp.tilesPerRow * imp.tileSize;
  c.height = imp.rowsPerLayer * imp.tileSize;
  c.layers = imp.atlasLayers;
  c.arrayView = true;
  c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
            VK_IMAGE_USAGE_TRANSFER_DST_BIT;  // uploaded from the file cache, read back to write it
  CANOPY_TRY(createImage(d, c, &imp.color, "impostors: colour atlas"));
  ImageDesc z = c;
  z.format = kAtlasDepthFormat;
  z.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
            VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, z, &imp.depth, "impostors: depth atlas"));
  for (uint32_t l = 0; l < imp.atlasLayers; ++l) {
    VkImageView v;
    CANOPY_TRY(imageLayerView(d, imp.color, l, &v));
    imp.colorLayerViews.push_back(v);
    CANOPY_TRY(imageLayerView(d, imp.depth, l, &v));
    imp.depthLayerViews.push_back(v);
  }
  VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  si.magFilter = si.minFilter = VK_FILTER_LINEAR;
  si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  CANOPY_VK(d.vk.CreateSampler(d.device, &si, d.allocationCallbacks, &imp.linearSampler));
  si.magFilter = si.minFilter = VK_FILTER_NEAREST;
  CANOPY_VK(d.vk.CreateSampler(d.device, &si, d.allocationCallbacks, &imp.nearestSampler));
  // The box table (baked boxes, in gpuIndex order) and room for a cut that draws every one of them.
  std::vector<gpu::ImpostorBox> table(std::max<uint32_t>(imp.baked, 1));
  for (const ImpostorNode& n : imp.nodes) {
    if (n.gpuIndex == kNoTile) continue;
    gpu::ImpostorBox& b = table[n.gpuIndex];
    b.center = glm::vec4(n.center, 0.0f);
    b.halfExtent = glm::vec4(n.half, float(n.level));
    b.root = glm::vec4(n.root, 1.0f);
    b.firstTile = n.firstTile;
  }
  const VkDeviceSize tableBytes = table.size() * sizeof(gpu::ImpostorBox);
  CANOPY_TRY(createBuffer(d, tableBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                          MemoryUsage::DeviceLocal, &imp.boxTable, "impostors: boxes"));
  CANOPY_TRY(uploadBuffer(d, &imp.pendingUploads, imp.boxTable, table.data(), tableBytes, kImpostorRead));
  CANOPY_TRY(reserveImpostorList(d, imp, *src.instances));
  // The bake draws each species' model at its origin, untinted: a copies' table of one.
  gpu::LayerInstance identity{};
  identity.model = glm::mat4(1.0f);
  identity.normalColumn0 = glm::vec4(1, 0, 0, 0);
  identity.normalColumn1 = glm::vec4(0, 1, 0, 0);
  identity.normalColumn2 = glm::vec4(0, 0, 1, 0);
  identity.tint = glm::vec4(1, 1, 1, 0);
  CANOPY_TRY(createBuffer(d, sizeof identity, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                          MemoryUsage::DeviceLocal, &imp.identityCopy, "impostors: the bake's copy"));
  if (void* direct = hostCoherentPointer(d, imp.identityCopy.allocation)) std::memcpy(direct, &identity, sizeof identity);
  else CANOPY_TRY(uploadBuffer(d, &imp.pendingUploads, imp.identityCopy, &identity, sizeof identity, rg::stateOf(rg::Use::VertexBuffer)));
  CANOPY_TRY(createDrawPipelines(d, src.colorFormat, imp));
  return imp.baked ? bake(d, src, imp) : Status();
}

Status reserveImpostorList(Device& d, Impostors& imp, const LayerInstances& copies) {
  // A cut draws a box at most once per visible copy of its species.
  uint64_t bound = imp.baked;
  if (!copies.identity) {
    bound = 0;
    for (uint32_t sp : copies.species) bound += sp < imp.speciesBaked.size() ? imp.speciesBaked[sp] : 0;
  }
  bound = std::max<uint64_t>(bound, 1);
  if (bound <= imp.instanceCapacity) return Status();
  if (bound > (256ull << 20) / sizeof(gpu::ImpostorInstance))
    return Status::error(Result::InvalidArgument, "impostors: " + std::to_string(copies.models.size()) + " copies of up to " +
                                                      std::to_string(imp.baked) + " baked boxes each need a list of " +
                                                      std::to_string(bound) + " impostors, over 256 MiB; lower CanopyDesc.impostors.maxLevel");
  if (imp.instances.buffer) destroyBufferLater(d, imp.instances);  // frames in flight may read the old list
  imp.instanceCapacity = uint32_t(bound);
  return createBuffer(d, bound * sizeof(gpu::ImpostorInstance), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                      MemoryUsage::DeviceLocal, &imp.instances, "impostors: instances");
}

void destroyImpostors(Device& d, Impostors& imp) {
  dropPreparedWork(d, imp.pendingUploads);
  for (VkImageView v : imp.colorLayerViews) d.vk.DestroyImageView(d.device, v, d.allocationCallbacks);
  for (VkImageView v : imp.depthLayerViews) d.vk.DestroyImageView(d.device, v, d.allocationCallbacks);
  imp.colorLayerViews.clear();
  imp.depthLayerViews.clear();
  destroyImage(d, imp.color);
  destroyImage(d, imp.depth);
  destroyBuffer(d, imp.boxTable);
  destroyBuffer(d, imp.instances);
  destroyBuffer(d, imp.identityCopy);
  for (GraphicsPipeline* p : {&imp.bake, &imp.layered, &imp.layeredFade, &imp.perLayer, &imp.perLayerFade, &imp.layeredHalf, &imp.layeredHalfFade})
    destroyGraphicsPipeline(d, *p);
  for (VkSampler s : {imp.linearSampler, imp.nearestSampler})
    if (s) d.vk.DestroySampler(d.device, s, d.allocationCallbacks);
  imp = Impostors{};
}

Status recordImpostors(const MeshDraw& target, const Impostors& imp, const LayerSettings& settings, bool singlePass,
                       VkCommandBuffer cmd, const ImpostorDraws& draws, bool fading, uint32_t layer) {
  const uint32_t total = uint32_t(draws.instances.size());
  const uint32_t first = fading ? draws.opaque : 0, count = fading ? total - draws.opaque : draws.opaque;
  if (!count) return Status();
  const bool half = settings.halfResolutionLayers > 0;  // the single pass's clip-distance variant
  const GraphicsPipeline& pipe = singlePass
                                     ? (half ? (fading ? imp.layeredHalfFade : imp.layeredHalf) : (fading ? imp.layeredFade : imp.layered))
                                     : (fading ? imp.perLayerFade : imp.perLayer);
  const Device& d = *target.device;
  setViewportScissor(d, cmd, target.width, target.height);
  gpu::ImpostorPush push{};
  push.passKind = singlePass ? LAYER_PASS_LAYERED : LAYER_PASS_ONE_LAYER;
  push.targetLayer = layer;
  push.tileSize = imp.tileSize;
  push.tilesPerRow = imp.tilesPerRow;
  push.rowsPerLayer = imp.rowsPerLayer;
  push.fading = fading ? 1u : 0u;
  push.debugLevels = settings.impostors.debugView ? 1u : 0u;
  push.firstView = imp.firstView;
  push.shape = settings.impostors.shape == ImpostorShape::CrossedPolygons ? IMPOSTOR_SHAPE_CROSSED : IMPOSTOR_SHAPE_FACING;
  const VkImageLayout ro = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
  CANOPY_TRY(bindGraphics(*target.device, cmd, pipe,
                          {bindBuffer(target.frame), bindBuffer(imp.boxTable.buffer), bindBuffer(imp.instances.buffer),
                           bindImage(imp.color.view, ro, imp.linearSampler), bindImage(imp.depth.view, ro, imp.nearestSampler),
                           bindBuffer(target.instances)},
                          push));
  d.vk.CmdDraw(cmd, 6, count, 0, first);
  return Status();
}

}  // namespace canopy
