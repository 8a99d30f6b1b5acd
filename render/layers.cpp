#include "render/layers.h"

#include "render/impostor_gpu.h"

#include "engine/hash.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <glm/gtc/packing.hpp>

#include "engine/device.h"
#include "engine/timing.h"
#include "engine/transfer.h"

namespace canopy {
namespace {

static_assert(offsetof(gpu::LayerVertex, positionXY) == 0 && offsetof(gpu::LayerVertex, normal) == 8 &&
                  offsetof(gpu::LayerVertex, uv) == 12,
              "LayerVertex offsets differ from the attributes the pipelines declare");

constexpr VkFormat kDepthFormat = VK_FORMAT_D32_SFLOAT;
constexpr VkFormat kIdsFormat = VK_FORMAT_R32G32_UINT;

double msSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// The frame block is read by the vertex stage (boundaries, matrices) and the fragment stage (light).
const rg::State kFrameRead{VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                           VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_IMAGE_LAYOUT_UNDEFINED};

// The next set rests where the cross-fade reads it.
const rg::State kNextRest = rg::stateOf(rg::Use::FragmentSampled);

// Spread re-slicing needs the second layer set; the id output is re-sliced at once (its images are
// for tests and tools, and a cross-fade of ids means nothing).
bool spreadEnabled(const LayeredVegetation& lv) { return lv.settings.rebuildBudgetMs > 0 && !lv.desc.writeIds; }
// A streamed mesh is always drawn in slices into the second set (never with the id output).
bool usesNextSet(const LayeredVegetation& lv) { return spreadEnabled(lv) || lv.streamed; }

std::string mib(uint64_t bytes) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.1f MiB", double(bytes) / double(1 << 20));
  return buf;
}

// Frees the layer images once no host frame in flight can read them (deferRelease), so a new
// layer count or size never waits for the device; `now`: at once (images no frame has used).
void destroyTargets(LayeredVegetation& lv, bool now = false) {
  Device* d = lv.device;
  dropPreparedWork(*d, lv.pendingClear);  // a clear of these images never recorded: nothing to wait for
  std::vector<VkImageView> views;
  for (auto* v : {&lv.colorLayerViews, &lv.depthLayerViews, &lv.idsLayerViews, &lv.next.colorLayerViews,
                  &lv.next.depthLayerViews}) {
    views.insert(views.end(), v->begin(), v->end());
    v->clear();
  }
  std::vector<Image> images;
  for (Image* img : {&lv.color, &lv.depth, &lv.ids, &lv.backgroundColor, &lv.backgroundDepth, &lv.next.color,
                     &lv.next.depth, &lv.next.backgroundColor, &lv.next.backgroundDepth}) {
    if (img->image) images.push_back(*img);
    *img = Image{};
  }
  lv.spread = SpreadRebuild{};  // a spread re-slice drew into the old images
  auto release = [d, views, images]() mutable {
    for (VkImageView v : views) d->vk.DestroyImageView(d->device, v, d->allocationCallbacks);
    for (Image& img : images) destroyImage(*d, img);
  };
  if (now) release();
  else deferRelease(*d, std::move(release));
}

Status layerView(Device& d, const Image& img, uint32_t layer, VkImageView* out) {
  VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vi.image = img.image;
  vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
  vi.format = img.format;
  vi.subresourceRange = {img.aspect, 0, 1, layer, 1};
  CANOPY_VK(d.vk.CreateImageView(d.device, &vi, d.allocationCallbacks, out));
  return Status();
}

// What impostors on (LayerSettings.impostors.mode) need of the object and the other settings.
Status checkImpostorSettings(const LayeredVegetation& lv, const LayerSettings& s) {
  if (s.impostors.mode == ImpostorMode::Off && !s.impostors.debugView) return Status();
  if (!lv.imp.enabled)
    return Status::error("LayerSettings.impostors.mode: impostors need CanopyDesc.impostors.enable at creation (the box "
                         "hierarchy and its baked views)");
  if (s.rebuildBudgetMs > 0)
    return Status::error("LayerSettings.impostors.mode: impostors are drawn by re-slices at once; rebuildBudgetMs must be 0 "
                         "(it is " + std::to_string(s.rebuildBudgetMs) + ")");
  if (lv.desc.writeIds) return Status::error("LayerSettings.impostors.mode: the id output draws every leaf; impostors are off with it");
  return Status();
}

// The cross-fade pipelines and their sampler (texel fetches only), for the next set.
Status createFadePipelines(LayeredVegetation& lv) {
  Device& d = *lv.device;
  if (!lv.nearestSampler) {
    VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    si.magFilter = si.minFilter = VK_FILTER_NEAREST;
    si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
    si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
    CANOPY_VK(d.vk.CreateSampler(d.device, &si, d.allocationCallbacks, &lv.nearestSampler));
  }
  if (lv.fade.pipeline) return Status();
  GraphicsPipelineDesc p;
  p.bindings = {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER};
  p.pushConstantSize = sizeof(gpu::LayerFadePush);
  p.colorFormats = {lv.desc.colorFormat};
  p.blend = BlendMode::ConstantMix;
  p.depthTest = p.depthWrite = false;
  p.vertexShader = "layers_fade.vert";
  p.fragmentShader = "layers_fade.frag";
  CANOPY_TRY(createGraphicsPipeline(d, p, &lv.fade));
  p.fragmentShader = "layers_fade_bg.frag";
  return createGraphicsPipeline(d, p, &lv.fadeBackground);
}

// Creates the layer arrays and the background for the current layer count, cleared and left in
// the rest state so that every later graph can import them with a fixed initial state.
Status createTargets(LayeredVegetation& lv) {
  Device& d = *lv.device;
  const uint32_t n = lv.settings.layout.count();
  ImageDesc c;
  c.format = lv.desc.colorFormat;
  c.width = lv.desc.width;
  c.height = lv.desc.height;
  c.layers = n;
  c.arrayView = true;
  c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
            VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, c, &lv.color, "layers: colour"));
  ImageDesc z = c;
  z.format = kDepthFormat;
  z.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
            VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, z, &lv.depth, "layers: depth"));
  if (lv.desc.writeIds) {
    ImageDesc i = c;
    i.format = kIdsFormat;
    CANOPY_TRY(createImage(d, i, &lv.ids, "layers: ids"));
  }
  ImageDesc bc = c;
  bc.layers = 1;
  bc.arrayView = false;
  CANOPY_TRY(createImage(d, bc, &lv.backgroundColor, "background: colour"));
  ImageDesc bz = z;
  bz.layers = 1;
  bz.arrayView = false;
  CANOPY_TRY(createImage(d, bz, &lv.backgroundDepth, "background: depth"));
  if (usesNextSet(lv)) {
    CANOPY_TRY(createFadePipelines(lv));
    CANOPY_TRY(createImage(d, c, &lv.next.color, "layers (next set): colour"));
    CANOPY_TRY(createImage(d, z, &lv.next.depth, "layers (next set): depth"));
    CANOPY_TRY(createImage(d, bc, &lv.next.backgroundColor, "background (next set): colour"));
    CANOPY_TRY(createImage(d, bz, &lv.next.backgroundDepth, "background (next set): depth"));
    for (uint32_t l = 0; l < n; ++l) {
      VkImageView v;
      CANOPY_TRY(layerView(d, lv.next.color, l, &v));
      lv.next.colorLayerViews.push_back(v);
      CANOPY_TRY(layerView(d, lv.next.depth, l, &v));
      lv.next.depthLayerViews.push_back(v);
    }
  }
  for (uint32_t l = 0; l < n; ++l) {
    VkImageView v;
    CANOPY_TRY(layerView(d, lv.color, l, &v));
    lv.colorLayerViews.push_back(v);
    CANOPY_TRY(layerView(d, lv.depth, l, &v));
    lv.depthLayerViews.push_back(v);
    if (lv.desc.writeIds) {
      CANOPY_TRY(layerView(d, lv.ids, l, &v));
      lv.idsLayerViews.push_back(v);
    }
  }
  // Clear once (empty layers until the first rebuild) into the rest state.
  PreparedWork work;
  work.graph = std::make_shared<rg::RenderGraph>();
  rg::RenderGraph& g = *work.graph;
  const rg::State rest = rg::stateOf(lv.desc.restUse);
  std::vector<std::pair<rg::ResourceId, const Image*>> imgs;
  for (const Image* img : {&lv.color, &lv.depth, &lv.ids, &lv.backgroundColor, &lv.backgroundDepth}) {
    if (!img->image) continue;
    imgs.push_back({g.importImage("layer target", descOf(*img), {}, rest), img});
  }
  for (const Image* img : {&lv.next.color, &lv.next.depth, &lv.next.backgroundColor, &lv.next.backgroundDepth}) {
    if (!img->image) continue;
    imgs.push_back({g.importImage("layer target (next set)", descOf(*img), {}, kNextRest), img});
  }
  std::vector<rg::ResourceId> ids;
  for (auto& [id, img] : imgs) ids.push_back(id);
  // The images as bound to this graph (by value: the clear may be recorded frames later).
  auto pass = g.addPass("layers: initial clear", [ids](rg::PassContext& ctx) {
    for (rg::ResourceId id : ids) {
      const Image& img = ctx.image(id);
      const VkImageSubresourceRange range{img.aspect, 0, 1, 0, img.layers};
      if (img.aspect & VK_IMAGE_ASPECT_DEPTH_BIT) {
        VkClearDepthStencilValue v{1.0f, 0};
        ctx.device->vk.CmdClearDepthStencilImage(ctx.cmd, img.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &v, 1, &range);
      } else {
        VkClearColorValue v{};
        ctx.device->vk.CmdClearColorImage(ctx.cmd, img.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &v, 1, &range);
      }
    }
    return Status();
  });
  for (auto& [id, img] : imgs) {
    pass.write(id, rg::Use::TransferDst);
    CANOPY_TRY(g.bindImage(id, *img));
  }
  // On a host's device the clear is recorded into its next frame (lv.pendingClear), else now.
  std::vector<PreparedWork>* before = d.deferTarget;
  d.deferTarget = &lv.pendingClear;
  Status s = submitOrDefer(d, std::move(work));
  d.deferTarget = before;
  return s;
}

}  // namespace

GraphicsPipelineDesc layerMeshPipelineDesc(VkFormat colorFormat, VkFormat depthFormat) {
  GraphicsPipelineDesc p;
  // shaders/layers_common.glsl: frame block, chunk root table, base colour, normal map,
  // transmission factor and colour textures.
  p.bindings = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,         VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER};
  p.pushConstantSize = sizeof(gpu::LayerDrawPush);
  p.vertexStride = sizeof(gpu::LayerVertex);
  p.attributes = {{0, VK_FORMAT_R16G16B16A16_UINT, 0},  // quantised position, chunk-local leaf
                  {1, VK_FORMAT_R16G16_SNORM, 8},        // octahedral normal
                  {2, VK_FORMAT_R16G16_SFLOAT, 12}};     // texcoord 0
  p.colorFormats = {colorFormat};
  p.depthFormat = depthFormat;
  p.blend = BlendMode::PremultipliedOver;
  p.fragmentShader = "layers.frag";
  return p;
}

namespace {

Status createPipelines(LayeredVegetation& lv) {
  Device& d = *lv.device;
  GraphicsPipelineDesc p = layerMeshPipelineDesc(lv.desc.colorFormat, kDepthFormat);
  if (d.shaderClipDistance) {
    p.vertexShader = "layers_clip.vert";
    CANOPY_TRY(createGraphicsPipeline(d, p, &lv.background));
  }
  if (lv.desc.writeIds) {
    p.colorFormats.push_back(kIdsFormat);
    p.fragmentShader = "layers_ids.frag";
  }
  if (d.shaderClipDistance) {
    p.vertexShader = "layers_clip.vert";
    CANOPY_TRY(createGraphicsPipeline(d, p, &lv.perLayer));
  }
  if (d.shaderOutputLayer) {
    p.vertexShader = "layers.vert";
    CANOPY_TRY(createGraphicsPipeline(d, p, &lv.layered));
  }
  return Status();
}

// Picks the draw path for the settings on this device.
Status chooseDrawPath(const LayeredVegetation& lv, const LayerSettings& s, bool* singlePass) {
  const Device& d = *lv.device;
  const bool canSingle = d.shaderOutputLayer && s.slice == SliceMode::LeafRoots;
  if (s.draw == LayerDrawMode::SinglePass && !canSingle)
    return Status::error(s.slice == SliceMode::Geometry
                             ? "layer draw mode SinglePass: geometric slicing cuts triangles and is drawn per layer"
                             : "layer draw mode SinglePass: the device lacks shaderOutputLayer (gl_Layer from the vertex shader)");
  *singlePass = s.draw == LayerDrawMode::PerLayer ? false : canSingle;
  if (!*singlePass && !d.shaderClipDistance)
    return Status::error("layers: the device has neither shaderOutputLayer nor shaderClipDistance; cannot slice");
  return Status();
}

// The GPU triangle order and the compact chunked mesh, in host memory.
Status buildMesh(LayeredVegetation& lv, const VegetationModel& m, const std::vector<uint8_t>& foliage,
                 const LeafRoots& roots, CompactMesh* mesh) {
  Device& d = *lv.device;
  const size_t nt = m.triangleCount();
  // GPU triangle order: foliage grouped by material, then rigid by material (one draw each).
  const size_t nm = m.materials.size();
  std::vector<uint64_t> start(2 * nm + 1, 0);
  for (size_t t = 0; t < nt; ++t) start[(foliage[t] ? 0 : nm) + m.triangleMaterial[t] + 1]++;
  for (size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  // The GPU order as a permutation of the model's triangles (4 bytes a face, not a copy of the
  // indices); the id output keeps it, since its triangle ids are in GPU order.
  std::vector<uint32_t> order(nt);
  std::vector<uint64_t> cursor(start.begin(), start.end() - 1);
  for (size_t t = 0; t < nt; ++t) order[cursor[(foliage[t] ? 0 : nm) + m.triangleMaterial[t]]++] = uint32_t(t);
  // With impostors the foliage of each material is laid out box by box, depth first
  // (render/impostors.h), so a box's subtree is one run per material.
  if (lv.desc.impostors.enable) {
    CANOPY_TRY(buildImpostorOrder(m, foliage, roots, lv.desc.impostors, start, &lv.imp, &order));
    CANOPY_TRY(planImpostorAtlas(lv.desc.impostors, d.properties.limits.maxImageDimension2D,
                                 d.properties.limits.maxImageArrayLayers, &lv.imp));
  }
  // The compact chunked mesh (render/mesh_chunks.h): 16-byte vertices, 16-bit indices and a
  // leaf-root table per chunk, so no buffer is indexed past the device's storage range; one
  // triangle range per (foliage or rigid, material) run of the GPU order.
  std::vector<TriangleRange> ranges;
  for (size_t k = 0; k < 2 * nm; ++k)
    if (start[k + 1] > start[k]) ranges.push_back({uint32_t(k % nm), k < nm, start[k], start[k + 1] - start[k]});
  lv.hasRigid = start[2 * nm] > start[nm];
  CompactMeshOptions co;
  co.maxChunkVertices = lv.desc.maxChunkVertices;
  co.bend = lv.desc.keepBend && !m.bend.empty();
  const VkDeviceSize align = std::max<VkDeviceSize>(d.properties.limits.minStorageBufferOffsetAlignment, 1);
  co.rootAlignment = uint32_t((align + sizeof(gpu::LayerLeafRoot) - 1) / sizeof(gpu::LayerLeafRoot));
  if (align % sizeof(gpu::LayerLeafRoot) && sizeof(gpu::LayerLeafRoot) % align)
    return Status::error("layers: minStorageBufferOffsetAlignment " + std::to_string(align) + " is not a power of two");
  lv.ring.rootAlignment = co.rootAlignment;
  CANOPY_TRY(buildCompactMesh(m, order, ranges, roots, co, mesh, lv.desc.progress));
  if (lv.desc.writeIds) lv.gpuToModelTriangle = std::move(order);
  lv.stats.meshChunks = uint32_t(mesh->chunks.size());
  lv.stats.meshBytes = mesh->bytes();
  lv.chunks = std::move(mesh->chunks);  // the one chunk list (the host mesh keeps none)
  return Status();
}

// The frame block, the material textures and their sampler.
Status uploadTextures(LayeredVegetation& lv, const VegetationModel& m) {
  Device& d = *lv.device;
  CANOPY_TRY(createBuffer(d, sizeof(gpu::LayerFrame), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                          MemoryUsage::DeviceLocal, &lv.frameBuffer, "layers: frame"));
  // Textures: sRGB base colour, so the shader reads linear values; a white texel for untextured materials.
  const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
  for (size_t i = 0; i <= m.images.size(); ++i) {
    static const uint8_t white[4] = {255, 255, 255, 255};
    const bool isWhite = i == m.images.size();
    ImageDesc t;
    t.format = !isWhite && m.images[i].linear ? VK_FORMAT_R8G8B8A8_UNORM : VK_FORMAT_R8G8B8A8_SRGB;
    t.width = isWhite ? 1 : m.images[i].width;
    t.height = isWhite ? 1 : m.images[i].height;
    t.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    Image img;
    CANOPY_TRY(createImage(d, t, &img, isWhite ? "white texel" : m.images[i].name.c_str()));
    lv.textures.push_back(img);
    CANOPY_TRY(uploadImage(d, img, isWhite ? white : m.images[i].rgba.data(),
                           isWhite ? 4 : m.images[i].rgba.size(), sampled));
  }
  VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  si.magFilter = si.minFilter = VK_FILTER_LINEAR;
  si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  si.maxLod = 0.0f;
  CANOPY_VK(d.vk.CreateSampler(d.device, &si, d.allocationCallbacks, &lv.sampler));
  return Status();
}


uint64_t roundUp(uint64_t x, uint64_t a) { return (x + a - 1) / a * a; }

// Where the compact mesh lives (docs/design.md "Layers: mesh budget and staging ring"): resident
// when it fits the budget beside everything else this object allocates, with room for the second
// layer set (a spread re-slice needs it, and settings may ask for it later); else in host memory,
// streamed through rings sized from desc.stagingRingBytes, which needs the second set now. Called
// after the textures, frame block and targets, so the bytes are the allocator's, not estimates.
Status chooseMeshResidency(LayeredVegetation& lv, uint64_t liveAtStart, uint64_t meshBytes) {
  const uint64_t budget = lv.desc.deviceMemoryBudget;
  lv.streamed = false;
  if (budget == 0) return Status();
  const uint64_t used = lv.device->allocator->liveBytes - liveAtStart;
  uint64_t nextSet = 0;  // the second set is the visible one's twin
  if (!lv.next.color.image)
    for (const Image* img : {&lv.color, &lv.depth, &lv.backgroundColor, &lv.backgroundDepth}) nextSet += img->allocation.size;
  if (used + nextSet + meshBytes + 3 * 256 <= budget) return Status();
  if (lv.desc.keepBend)
    return Status::error("layers: the per-vertex wind baseline (CanopyDesc.allowPerVertex) draws the whole mesh every "
                         "frame and needs it resident: the compact mesh with its branch hierarchy (" + mib(meshBytes) +
                         ") with the layer images and textures (" + mib(used + nextSet) + ") is over deviceMemoryBudget " +
                         mib(budget) + "; raise it (or 0: no limit)");
  if (lv.desc.writeIds)
    return Status::error("layers: the id output draws the mesh at once and needs it resident: the compact mesh (" +
                         mib(meshBytes) + ") with the layer images and textures (" + mib(used + nextSet) +
                         ") is over deviceMemoryBudget " + mib(budget));
  lv.streamed = true;
  if (lv.next.color.image) return Status();
  // Never used by a frame (their clear was submitted and waited for, or is dropped): freed now,
  // so the allocator's count is exact for the ring that follows.
  destroyTargets(lv, true);
  return createTargets(lv);
}

// Creates the resident buffers and fills them, or the staging rings; the mesh stays in lv.hostMesh.
Status placeMesh(LayeredVegetation& lv, CompactMesh&& compact, uint64_t liveAtStart) {
  Device& d = *lv.device;
  lv.hostMesh = std::move(compact);
  const CompactMesh& mesh = lv.hostMesh;
  const uint64_t budget = lv.desc.deviceMemoryBudget;
  if (lv.streamed) {
    // Per segment each ring holds at least the largest chunk (its vertices, its root block, and
    // 1024 of its triangles), so every frame's slice makes progress; the rest of the ring's bytes
    // are shared in the proportions of the whole mesh.
    MeshRing& r = lv.ring;
    r.segments = std::max<uint32_t>(d.framesInFlight, 1);
    uint64_t minV = 0, minR = 0, minI = 3;
    for (const MeshChunk& c : lv.chunks) {
      minV = std::max<uint64_t>(minV, c.vertexCount);
      minR = std::max<uint64_t>(minR, roundUp(std::max<uint32_t>(c.rootCount, 1), r.rootAlignment));
      minI = std::max<uint64_t>(minI, 3ull * std::min<uint32_t>(c.triangleCount, 1024));
    }
    const uint64_t vb = mesh.vertices.size() * sizeof(gpu::LayerVertex), ib = mesh.indices.size() * 2,
                   rb = mesh.roots.size() * sizeof(gpu::LayerLeafRoot);
    const uint64_t total = std::max<uint64_t>(vb + ib + rb, 1);
    const double share = double(lv.desc.stagingRingBytes) / double(r.segments) / double(total);
    r.vertexCapacity = std::min<uint64_t>(std::max<uint64_t>(minV, uint64_t(share * vb) / sizeof(gpu::LayerVertex)), mesh.vertices.size());
    r.indexCapacity = std::min<uint64_t>(std::max<uint64_t>(minI, uint64_t(share * ib) / 2), mesh.indices.size());
    r.rootCapacity = roundUp(std::max<uint64_t>(minR, uint64_t(share * rb) / sizeof(gpu::LayerLeafRoot)), r.rootAlignment);
    r.bytes = r.segments * (r.vertexCapacity * sizeof(gpu::LayerVertex) + roundUp(r.indexCapacity * 2, 4) +
                            r.rootCapacity * sizeof(gpu::LayerLeafRoot));
    const uint64_t used = d.allocator->liveBytes - liveAtStart;
    if (used + r.bytes > budget)
      return Status::error("layers: deviceMemoryBudget " + mib(budget) + ": the layer images and textures take " + mib(used) +
                           ", the mesh (" + mib(mesh.bytes()) + ") does not fit and its staging ring needs " + mib(r.bytes) +
                           " (" + std::to_string(r.segments) + " segments, each at least the largest chunk; stagingRingBytes " +
                           mib(lv.desc.stagingRingBytes) + "); raise the budget");
    CANOPY_TRY(createBuffer(d, r.segments * r.vertexCapacity * sizeof(gpu::LayerVertex), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT,
                            MemoryUsage::Upload, &lv.vertices, "layers: vertex ring"));
    CANOPY_TRY(createBuffer(d, r.segments * roundUp(r.indexCapacity * 2, 4), VK_BUFFER_USAGE_INDEX_BUFFER_BIT,
                            MemoryUsage::Upload, &lv.indexBuffer, "layers: index ring"));
    CANOPY_TRY(createBuffer(d, r.segments * r.rootCapacity * sizeof(gpu::LayerLeafRoot), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                            MemoryUsage::Upload, &lv.leafRoots, "layers: leaf-root ring"));
    for (const Buffer* b : {&lv.vertices, &lv.indexBuffer, &lv.leafRoots})
      if (!hostCoherentPointer(d, b->allocation))
        return Status::error("layers: the staging ring's memory is not host-visible and coherent");
    lv.stats.meshResident = false;
    lv.stats.meshRingBytes = r.bytes;
    return Status();
  }
  lv.stats.meshResident = true;
  lv.stats.meshRingBytes = 0;
  auto upload = [&](Buffer& buf, const void* data, VkDeviceSize bytes, VkBufferUsageFlags usage, rg::Use use,
                    const char* name) -> Status {
    CANOPY_TRY(createBuffer(d, std::max<VkDeviceSize>(bytes, 16), usage | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                            MemoryUsage::DeviceLocal, &buf, name));
    if (bytes == 0) return Status();
    // Where device memory is host-visible and coherent (CPU drivers, UMA and ReBAR GPUs) the data is
    // written in place: no staging copy of a mesh of hundreds of MB. The queue submission that first
    // reads it makes the host writes visible.
    if (void* direct = hostCoherentPointer(d, buf.allocation)) {
      std::memcpy(direct, data, bytes);
      return Status();
    }
    return uploadBuffer(d, buf, data, bytes, rg::stateOf(use));
  };
  CANOPY_TRY(upload(lv.vertices, mesh.vertices.data(), mesh.vertices.size() * sizeof(gpu::LayerVertex),
                    VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, rg::Use::VertexBuffer, "layers: vertices"));
  CANOPY_TRY(upload(lv.indexBuffer, mesh.indices.data(), mesh.indices.size() * 2, VK_BUFFER_USAGE_INDEX_BUFFER_BIT,
                    rg::Use::IndexBuffer, "layers: indices"));
  if (!mesh.bend.empty())
    CANOPY_TRY(upload(lv.bendVertices, mesh.bend.data(), mesh.bend.size() * sizeof(gpu::BendVertex),
                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, rg::Use::VertexStorageRead, "per-vertex: branch and w per vertex"));
  return upload(lv.leafRoots, mesh.roots.data(), mesh.roots.size() * sizeof(gpu::LayerLeafRoot),
                VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, rg::Use::VertexStorageRead, "layers: leaf roots");
}

bool matricesDiffer(const glm::mat4& a, const glm::mat4& b) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (std::abs(a[c][r] - b[c][r]) > 1e-5f * std::max(1.0f, std::abs(b[c][r]))) return true;
  return false;
}

float angleDegrees(const glm::vec3& a, const glm::vec3& b) {
  return glm::degrees(std::acos(std::clamp(glm::dot(a, b), -1.0f, 1.0f)));
}

using Clock = std::chrono::steady_clock;

// Starts the placement for `view`: the frame constants the layer draws read.
void beginPlacement(const LayeredVegetation& lv, const LayerView& view, PlacementJob& job) {
  job = PlacementJob{};
  const LayerSettings& s = lv.settings;
  gpu::LayerFrame& f = job.frame;
  f = cameraFrame(s, view);
  f.layerCount = s.layout.count();
  f.sliceMode = s.slice == SliceMode::Geometry ? LAYER_SLICE_GEOMETRY : LAYER_SLICE_LEAF_ROOT;
  job.zMin = INFINITY;
  job.zMax = -INFINITY;
  job.bottom = -INFINITY;
  job.leafDepth.resize(lv.leafCount);
}

// Runs the placement's stages (leaf-root depths, their range, the layer boundaries, each leaf's
// layer, per-layer top and the root line over the vertices, triangles per layer) until it is done
// or `deadline` (null: none) has passed; the clock is read every kBatch items.
Status advancePlacement(const LayeredVegetation& lv, PlacementJob& job, const Clock::time_point* deadline, bool* done) {
  constexpr size_t kBatch = 1 << 14;
  const auto t0 = Clock::now();
  const LayerSettings& s = lv.settings;
  gpu::LayerFrame& f = job.frame;
  const bool geometric = s.slice == SliceMode::Geometry;
  auto depthOf = [&](const glm::vec3& p) { return glm::dot(f.depthRow, glm::vec4(p, 1.0f)); };
  // Per vertex the placement reads the compact host mesh (decoded as the vertex shader decodes it),
  // chunk by chunk: foliage chunks come first, each chunk's vertices and indices contiguous.
  const CompactMesh& hm = lv.hostMesh;
  const size_t nLeaves = lv.leafCount, nVertices = hm.vertices.size(), nChunks = lv.chunks.size();
  size_t foliageIndices = 0;
  for (const MeshChunk& c : lv.chunks)
    if (c.foliage) foliageIndices = std::max<size_t>(foliageIndices, c.firstIndex + 3ull * c.triangleCount);
  auto chunkOf = [&](size_t item, bool index) -> const MeshChunk& {
    for (;; ++job.chunk) {
      const MeshChunk& c = lv.chunks[job.chunk];
      if (job.chunk + 1 == lv.chunks.size() || item < (index ? c.firstIndex + 3ull * c.triangleCount : c.firstVertex + c.vertexCount))
        return c;
    }
  };
  auto leafOf = [&](const MeshChunk& c, const gpu::LayerVertex& v) {
    const uint32_t l = chunkLeaf(v);
    return l == LAYER_CHUNK_NO_LEAF ? kNoLeaf : hm.roots[c.firstRoot + l].leaf;
  };
  const glm::vec4 rowY(f.viewProj[0][1], f.viewProj[1][1], f.viewProj[2][1], f.viewProj[3][1]);
  const glm::vec4 rowW(f.viewProj[0][3], f.viewProj[1][3], f.viewProj[2][3], f.viewProj[3][3]);
  const float h = float(lv.desc.height);
  *done = false;
  while (!*done) {
    size_t end = 0;
    switch (job.stage) {
      case 0: {  // the keys the layers are assigned by: leaf roots (or, below, every foliage vertex),
                 // read from the chunks' root tables (a leaf in two chunks is written twice, alike)
        size_t roots = 0;
        for (end = job.next; end < nChunks && roots < kBatch; ++end) {
          const MeshChunk& c = lv.chunks[end];
          for (uint64_t i = c.firstRoot; i < c.firstRoot + c.rootCount; ++i) {
            const float z = depthOf(hm.roots[i].position);
            job.leafDepth[hm.roots[i].leaf] = z;
            if (!geometric) {
              job.zMin = std::min(job.zMin, z);
              job.zMax = std::max(job.zMax, z);
            }
          }
          roots += c.rootCount + 1;
        }
        if (end == nChunks) job.stage = geometric ? 1 : 2, end = 0;
        break;
      }
      case 1:
        end = std::min(job.next + kBatch, nVertices);
        for (size_t v = job.next; v < end; ++v)
          if (chunkLeaf(hm.vertices[v]) != LAYER_CHUNK_NO_LEAF) {
            const float z = depthOf(decodePosition(chunkOf(v, false), hm.vertices[v]));
            job.zMin = std::min(job.zMin, z);
            job.zMax = std::max(job.zMax, z);
          }
        if (end == nVertices) job.stage = 2, end = 0;
        break;
      case 2: {
        if (!(job.zMin <= job.zMax)) job.zMin = job.zMax = 0.0f;  // no foliage: empty layers
        std::vector<LayerSlab> slabs;
        std::vector<float> bounds;
        CANOPY_TRY(placeLayers(s.layout, s.regions, job.zMin, job.zMax, &slabs, &bounds));
        for (uint32_t i = 0; i <= CANOPY_MAX_LAYERS; ++i) f.boundaries[i] = bounds[std::min<size_t>(i, bounds.size() - 1)];
        job.layers.assign(f.layerCount, LayerInfo{});
        for (uint32_t i = 0; i < f.layerCount; ++i) {
          job.layers[i].slab = slabs[i];
          job.layers[i].top = INFINITY;
        }
        job.leafLayer.resize(nLeaves);
        job.stage = 3;
        break;
      }
      case 3:
        end = std::min(job.next + kBatch, nLeaves);
        for (size_t i = job.next; i < end; ++i) {
          job.leafLayer[i] = uint8_t(gpu::layerOfDepth(f, job.leafDepth[i]));
          job.layers[job.leafLayer[i]].leaves++;
        }
        if (end == nLeaves) job.stage = 4, end = 0;
        break;
      case 4:  // the screen-space root line and per-layer tops (eq. 7)
        end = std::min(job.next + kBatch, nVertices);
        for (size_t v = job.next; v < end; ++v) {
          const MeshChunk& c = chunkOf(v, false);
          const glm::vec4 p(decodePosition(c, hm.vertices[v]), 1.0f);
          const float w = glm::dot(rowW, p);
          if (w <= 1e-6f) continue;
          const float y = (glm::dot(rowY, p) / w * 0.5f + 0.5f) * h;
          job.bottom = std::max(job.bottom, y);
          const uint32_t leaf = leafOf(c, hm.vertices[v]);
          if (leaf == kNoLeaf) continue;
          const uint32_t layer = geometric ? gpu::layerOfDepth(f, glm::dot(f.depthRow, p)) : job.leafLayer[leaf];
          job.layers[layer].top = std::min(job.layers[layer].top, y);
        }
        if (end == nVertices) job.stage = 5, end = 0;
        break;
      case 5:  // foliage triangles come first in GPU order: indices [0, foliageIndices)
        end = std::min(job.next + 3 * kBatch, foliageIndices);
        for (size_t k = job.next; k < end; k += 3) {
          const MeshChunk& c = chunkOf(k, true);
          const gpu::LayerVertex& v = hm.vertices[c.firstVertex + hm.indices[k]];
          const uint32_t layer = geometric ? gpu::layerOfDepth(f, depthOf(decodePosition(c, v))) : job.leafLayer[leafOf(c, v)];
          job.layers[layer].triangles++;
        }
        if (end == foliageIndices) job.stage = 6, end = 0;
        break;
      default: {
        float bottom = job.bottom;
        if (!std::isfinite(bottom)) bottom = h;
        for (LayerInfo& li : job.layers) {
          li.rootLineY = bottom;
          if (!std::isfinite(li.top)) li.top = bottom;
          li.height = std::max(bottom - li.top, 1.0f);
        }
        job.leafDepth = {};
        job.leafLayer = {};
        *done = true;
        break;
      }
    }
    job.next = end;
    if (end == 0) job.chunk = 0;  // a new stage starts at the first chunk
    if (!*done && deadline && Clock::now() >= *deadline) break;
  }
  job.ms += msSince(t0);
  return Status();
}

// The impostor cut of the visible placement (LayerSettings.impostors; render/impostors.h): which
// boxes are drawn as impostors, with which weight, and the remaining foliage as chunk parts.
void planImpostorCut(LayeredVegetation& lv, const LayerView& view) {
  const auto t0 = Clock::now();
  lv.cut = ImpostorCut{};
  lv.cutParts.clear();
  lv.cutInstances.clear();
  lv.cutOpaque = 0;
  const LayerSettings& s = lv.settings;
  if ((s.impostors.mode == ImpostorMode::Off && !s.impostors.debugView) || !lv.imp.enabled) return;
  ImpostorCutInput in;
  in.settings = s.impostors;
  in.depthRow = lv.frame.depthRow;
  in.perspective = view.proj[2][3] != 0.0f;
  in.pixelScale = std::abs(view.proj[1][1]) * 0.5f * float(lv.desc.height);
  // The far region begins at the first far layer's near boundary (none: no far region); boxes ramp
  // in over band x the mean layer thickness before it.
  const LayerLayout& l = s.layout;
  const uint32_t n = l.count();
  in.farStart = l.region[2] ? lv.frame.boundaries[l.region[0] + l.region[1]] : INFINITY;
  in.farBand = s.impostors.band * (lv.frame.boundaries[n] - lv.frame.boundaries[0]) / float(n);
  impostorCut(lv.imp, in, &lv.cut);
  for (const ImpostorCut::Run& r : lv.cut.geometry) appendRunParts(lv, r.first, r.count, r.weight, r.level, &lv.cutParts);
  lv.cutInstances = lv.cut.opaque;
  lv.cutOpaque = uint32_t(lv.cut.opaque.size());
  lv.cutInstances.insert(lv.cutInstances.end(), lv.cut.fading.begin(), lv.cut.fading.end());
  lv.stats.lastImpostors = uint32_t(lv.cutInstances.size());
  lv.stats.lastFadingBoxes = uint32_t(lv.cut.fading.size());
  lv.stats.lastDrawnTriangles = lv.cut.triangles;
  lv.stats.lastPlacementMs += msSince(t0);
}

// The whole placement for `view` at once, made the visible one.
Status placeForView(LayeredVegetation& lv, const LayerView& view) {
  PlacementJob job;
  beginPlacement(lv, view, job);
  bool done = false;
  CANOPY_TRY(advancePlacement(lv, job, nullptr, &done));
  lv.frame = job.frame;
  lv.layers = std::move(job.layers);
  lv.stats.lastPlacementMs = job.ms;
  planImpostorCut(lv, view);
  return Status();
}

// Binds the mesh and draws its foliage or rigid chunks with `pipe` (`parts`: only those parts of
// chunks; null: every chunk whole); the push constants say how the vertex shader routes triangles
// (passKind, targetLayer).
// `perVertex`: the per-vertex baseline's frame block (binding 0) and its four bindings after the
// six of the layers (render/per_vertex.cpp).
Status drawMaterials(LayeredVegetation& lv, VkCommandBuffer cmd, const GraphicsPipeline& pipe, bool foliage,
                     uint32_t passKind, uint32_t target, const std::vector<ChunkPart>* parts,
                     const PerVertexBindings* perVertex = nullptr, const MeshDrawOptions* options = nullptr) {
  const Device& d = *lv.device;
  const VkDeviceSize zero = 0;
  const MeshDrawOptions plain;
  const MeshDrawOptions& o = options ? *options : plain;
  d.vk.CmdBindVertexBuffers(cmd, 0, 1, &lv.vertices.buffer, &zero);
  d.vk.CmdBindIndexBuffer(cmd, lv.indexBuffer.buffer, 0, VK_INDEX_TYPE_UINT16);
  if (!o.keepViewport) setViewportScissor(d, cmd, lv.desc.width, lv.desc.height);
  // One draw per mesh chunk: its bounds decode the quantised positions, its block of the root table
  // is bound at its own offset (render/mesh_chunks.h).
  auto draw = [&](const MeshChunk& c, const ChunkPart* part, uint32_t first, uint32_t count) -> Status {
    const ModelMaterial& mat = lv.materials[c.material];
    auto textureOf = [&](int32_t image) -> const Image& { return image >= 0 ? lv.textures[size_t(image)] : lv.textures.back(); };
    const Image& tex = textureOf(mat.baseColorImage);
    gpu::LayerDrawPush push{};
    push.baseColor = mat.baseColorFactor;
    push.chunkOrigin = glm::vec4(c.origin, 0.0f);
    push.chunkScale = glm::vec4(c.scale, 0.0f);
    push.alphaCutoff = mat.alphaCutoff;
    push.alphaMode = uint32_t(mat.alphaMode);
    push.targetLayer = target;
    // Leaf shading (shared/leaf_shading.h): foliage has the front's lobe and its transmission (the
    // file's, else the settings' in the leaf's own colour); rigid parts neither.
    push.specular = c.foliage ? 1.0f : 0.0f;
    const bool fileTransmission = mat.transmissionFactor >= 0.0f;
    push.transmission = !c.foliage ? glm::vec4(0.0f)
                        : fileTransmission ? glm::vec4(mat.transmissionColor, mat.transmissionFactor)
                                           : glm::vec4(1.0f, 1.0f, 1.0f, lv.settings.leafTransmission);
    push.shadingFlags = (c.foliage && !fileTransmission ? LAYER_SHADE_TINT_FROM_BASE : 0u) |
                        (mat.transmissionImage >= 0 ? LAYER_SHADE_TRANSMISSION_TEXTURE : 0u) |
                        (mat.transmissionColorImage >= 0 ? LAYER_SHADE_TRANSMISSION_COLOR_TEXTURE : 0u);
    push.normalScale = mat.normalImage >= 0 ? mat.normalScale : 0.0f;
    push.passKind = passKind;
    push.lod = glm::vec4(part ? part->weight : 1.0f, o.debugLevels ? float((part ? part->level : 0u) + 1u) : 0.0f, 0.0f, 0.0f);
    push.triangleBase = uint32_t(c.firstTriangle);
    const VkDeviceSize rootBytes = std::max<VkDeviceSize>(c.rootCount, 1) * sizeof(gpu::LayerLeafRoot);
    // A streamed mesh's part sits in this frame's ring segment (planSlice copied it there).
    const bool ring = lv.streamed;
    const uint64_t rootAt = ring ? part->ringRoot : c.firstRoot;
    const uint64_t indexAt = ring ? part->ringIndex : c.firstIndex + 3ull * first;
    const uint64_t vertexAt = ring ? part->ringVertex : c.firstVertex;
    const VkImageLayout ro = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    const Binding frame = o.frame ? bindBuffer(o.frame, o.frameOffset, sizeof(gpu::LayerFrame))
                                  : bindBuffer(perVertex ? perVertex->frame : lv.frameBuffer.buffer);
    const Binding roots = bindBuffer(lv.leafRoots.buffer, rootAt * sizeof(gpu::LayerLeafRoot), rootBytes);
    const Binding base = bindImage(tex.view, ro, lv.sampler), normal = bindImage(textureOf(mat.normalImage).view, ro, lv.sampler),
                  trans = bindImage(textureOf(mat.transmissionImage).view, ro, lv.sampler),
                  transColor = bindImage(textureOf(mat.transmissionColorImage).view, ro, lv.sampler);
    if (perVertex)
      CANOPY_TRY(bindGraphics(*lv.device, cmd, pipe,
                              {frame, roots, base, normal, trans, transColor, bindBuffer(perVertex->bendFrame),
                               bindBuffer(perVertex->branches), bindBuffer(perVertex->bendVertices),
                               bindBuffer(perVertex->tips)},
                              push));
    else
      CANOPY_TRY(bindGraphics(*lv.device, cmd, pipe, {frame, roots, base, normal, trans, transColor}, push));
    // gl_PrimitiveID restarts at each draw: a part's ids would start at its first triangle, so the
    // id output (re-sliced at once) never draws parts.
    d.vk.CmdDrawIndexed(cmd, count * 3, 1, uint32_t(indexAt), int32_t(vertexAt), 0);
    return Status();
  };
  if (parts) {
    for (const ChunkPart& p : *parts)
      if (lv.chunks[p.chunk].foliage == foliage) CANOPY_TRY(draw(lv.chunks[p.chunk], &p, p.firstTriangle, p.triangleCount));
    return Status();
  }
  if (lv.streamed) return Status::error("layers: a streamed mesh is drawn in slices only");  // updateLayerView never asks
  for (const MeshChunk& c : lv.chunks)
    if (c.foliage == foliage) CANOPY_TRY(draw(c, nullptr, 0, c.triangleCount));
  return Status();
}

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
};
DrawTargets visibleTargets(const LayeredVegetation& lv) {
  return {lv.color.view, lv.depth.view, lv.ids.view, &lv.colorLayerViews, &lv.depthLayerViews, &lv.idsLayerViews,
          lv.backgroundColor.view, lv.backgroundDepth.view};
}
DrawTargets nextTargets(const LayeredVegetation& lv) {
  return {lv.next.color.view, lv.next.depth.view, VK_NULL_HANDLE, &lv.next.colorLayerViews, &lv.next.depthLayerViews,
          nullptr, lv.next.backgroundColor.view, lv.next.backgroundDepth.view};
}

Status recordFoliage(LayeredVegetation& lv, VkCommandBuffer cmd, const DrawTargets& t, bool clear,
                     const std::vector<ChunkPart>* parts) {
  const uint32_t n = lv.settings.layout.count();
  const uint32_t passes = lv.singlePass ? 1 : n;
  const bool ids = t.ids != VK_NULL_HANDLE;
  for (uint32_t i = 0; i < passes; ++i) {
    const VkRenderingAttachmentInfo colors[2] = {
        attachment(lv.singlePass ? t.color : (*t.colorLayers)[i], false, clear),
        attachment(ids ? (lv.singlePass ? t.ids : (*t.idsLayers)[i]) : VK_NULL_HANDLE, false, clear)};
    const VkRenderingAttachmentInfo depth = attachment(lv.singlePass ? t.depth : (*t.depthLayers)[i], true, clear);
    // With an impostor cut (a re-slice at once): the opaque impostors, the foliage left, then the
    // impostors fading in over their fading leaves (docs/design.md "Impostors").
    const bool cut = lv.cut.active && !parts;
    MeshDrawOptions o;
    o.debugLevels = cut && lv.settings.impostors.debugView;
    CANOPY_TRY(renderInto(*lv.device, cmd, lv, lv.singlePass ? n : 1, colors, ids ? 2 : 1, depth, [&]() -> Status {
      if (cut) CANOPY_TRY(recordImpostors(lv, cmd, false, i));
      const std::vector<ChunkPart>* drawn = cut ? &lv.cutParts : parts;
      if (!cut || !lv.cutParts.empty())
        CANOPY_TRY(lv.singlePass ? drawMaterials(lv, cmd, lv.layered, true, LAYER_PASS_LAYERED, 0, drawn, nullptr, &o)
                                 : drawMaterials(lv, cmd, lv.perLayer, true, LAYER_PASS_ONE_LAYER, i, drawn, nullptr, &o));
      return cut ? recordImpostors(lv, cmd, true, i) : Status();
    }));
  }
  return Status();
}

Status recordBackground(LayeredVegetation& lv, VkCommandBuffer cmd, const DrawTargets& t, bool clear,
                        const std::vector<ChunkPart>* parts) {
  const VkRenderingAttachmentInfo color = attachment(t.backgroundColor, false, clear);
  const VkRenderingAttachmentInfo depth = attachment(t.backgroundDepth, true, clear);
  return renderInto(*lv.device, cmd, lv, 1, &color, 1, depth, [&] {
    return drawMaterials(lv, cmd, lv.background, false, LAYER_PASS_BACKGROUND, 0, parts);
  });
}

// Whether a spread slice holds parts of foliage (rigid) chunks.
bool sliceHas(const LayeredVegetation& lv, bool foliage) {
  for (const ChunkPart& p : lv.spread.slice)
    if (lv.chunks[p.chunk].foliage == foliage) return true;
  return false;
}

}  // namespace

Status imageLayerView(Device& device, const Image& image, uint32_t layer, VkImageView* out) {
  return layerView(device, image, layer, out);
}

Status drawMeshParts(LayeredVegetation& lv, VkCommandBuffer cmd, const GraphicsPipeline& pipe, uint32_t passKind,
                     uint32_t target, const std::vector<ChunkPart>& parts, const MeshDrawOptions& options) {
  return drawMaterials(lv, cmd, pipe, true, passKind, target, &parts, nullptr, &options);
}

void appendRunParts(const LayeredVegetation& lv, uint64_t first, uint64_t count, float weight, uint32_t level,
                    std::vector<ChunkPart>* out) {
  // Chunks are in GPU triangle order and never span materials: find the one holding `first`.
  auto it = std::upper_bound(lv.chunks.begin(), lv.chunks.end(), first,
                             [](uint64_t t, const MeshChunk& c) { return t < c.firstTriangle; });
  if (it == lv.chunks.begin()) return;
  for (size_t c = size_t(it - lv.chunks.begin()) - 1; count > 0 && c < lv.chunks.size(); ++c) {
    const MeshChunk& ch = lv.chunks[c];
    const uint64_t local = first - ch.firstTriangle;
    if (local >= ch.triangleCount) continue;
    const uint64_t take = std::min<uint64_t>(count, ch.triangleCount - local);
    ChunkPart p;
    p.chunk = uint32_t(c);
    p.firstTriangle = uint32_t(local);
    p.triangleCount = uint32_t(take);
    p.weight = weight;
    p.level = level;
    out->push_back(p);
    first += take;
    count -= take;
  }
}

gpu::LayerFrame cameraFrame(const LayerSettings& s, const LayerView& view) {
  gpu::LayerFrame f{};
  f.viewProj = view.proj * view.view;
  f.depthRow = -glm::vec4(view.view[0][2], view.view[1][2], view.view[2][2], view.view[3][2]);
  const glm::vec3 dir = toGlm(s.lightDirection);
  const glm::vec3 l = glm::length(dir) > 0 ? glm::normalize(dir) : glm::vec3(0, 1, 0);
  f.lightDirection = glm::vec4(l, s.ambient);
  f.lightColor = glm::vec4(toGlm(s.lightColor), 1.0f);
  // The viewer for the shading's view vector: the camera position, or for an orthographic
  // projection (no perspective row) the direction towards the viewer.
  const glm::mat4 cameraToWorld = glm::inverse(view.view);
  const bool orthographic = view.proj[0][3] == 0.0f && view.proj[1][3] == 0.0f && view.proj[2][3] == 0.0f;
  f.eye = orthographic ? glm::vec4(glm::normalize(glm::vec3(cameraToWorld[2])), 0.0f) : glm::vec4(glm::vec3(cameraToWorld[3]), 1.0f);
  f.leafShading = glm::vec4(s.leafRefractiveIndex, s.leafRoughness, s.translucency ? 1.0f : 0.0f, 0.0f);
  return f;
}

Status drawWholeMesh(LayeredVegetation& lv, VkCommandBuffer cmd, const GraphicsPipeline& pipe,
                     const PerVertexBindings& bindings) {
  CANOPY_TRY(drawMaterials(lv, cmd, pipe, true, LAYER_PASS_BACKGROUND, 0, nullptr, &bindings));
  return lv.hasRigid ? drawMaterials(lv, cmd, pipe, false, LAYER_PASS_BACKGROUND, 0, nullptr, &bindings) : Status();
}

VkRect2D layerFootprint(const LayeredVegetation& lv) {
  const float w = float(lv.desc.width), h = float(lv.desc.height);
  const VkRect2D all{{0, 0}, {lv.desc.width, lv.desc.height}};
  glm::vec2 lo(INFINITY), hi(-INFINITY);
  std::vector<const glm::mat4*> views{&lv.frame.viewProj};
  if (lv.spread.phase == SpreadPhase::Drawing || lv.spread.phase == SpreadPhase::CrossFading)
    views.push_back(&lv.spread.job.frame.viewProj);
  for (const glm::mat4* vp : views)
    for (int c = 0; c < 8; ++c) {
      const glm::vec3 p((c & 1) ? lv.boundsMax.x : lv.boundsMin.x, (c & 2) ? lv.boundsMax.y : lv.boundsMin.y,
                        (c & 4) ? lv.boundsMax.z : lv.boundsMin.z);
      const glm::vec4 q = *vp * glm::vec4(p, 1.0f);
      if (!(q.w > 1e-6f)) return all;  // a corner behind the camera (or no view yet)
      const glm::vec2 px((q.x / q.w * 0.5f + 0.5f) * w, (q.y / q.w * 0.5f + 0.5f) * h);
      lo = glm::min(lo, px);
      hi = glm::max(hi, px);
    }
  if (!std::isfinite(lo.x) || !std::isfinite(lo.y) || !std::isfinite(hi.x) || !std::isfinite(hi.y)) return all;
  const int x0 = int(std::clamp(std::floor(lo.x) - 2.0f, 0.0f, w)), y0 = int(std::clamp(std::floor(lo.y) - 2.0f, 0.0f, h));
  const int x1 = int(std::clamp(std::ceil(hi.x) + 2.0f, 0.0f, w)), y1 = int(std::clamp(std::ceil(hi.y) + 2.0f, 0.0f, h));
  return {{x0, y0}, {uint32_t(std::max(x1 - x0, 0)), uint32_t(std::max(y1 - y0, 0))}};
}

namespace {

// A cross-fade step before the last (shared/layers.h LayerFadePush): the visible layers' colours
// (and the background's) with a weight this frame blended towards the next set inside
// layerFootprint. Only colour: the composite reads depth where a layer is opaque enough, and the
// old depth for a few frames is cheaper than a depth pass per layer (with gl_FragDepth, ~15 ms a
// layer at 1024x768 on lavapipe).
Status recordFadeBlend(LayeredVegetation& lv, VkCommandBuffer cmd) {
  Device& d = *lv.device;
  const VkRect2D rect = layerFootprint(lv);
  if (rect.extent.width == 0 || rect.extent.height == 0) return Status();
  auto step = [&](const GraphicsPipeline& pipe, VkImageView color, const Image& newColor, uint32_t layer, float w) -> Status {
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
    Status s = bindGraphics(d, cmd, pipe, {bindImage(newColor.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, lv.nearestSampler)},
                            push);
    if (s.ok()) {
      setViewportScissor(d, cmd, lv.desc.width, lv.desc.height);
      d.vk.CmdSetScissor(cmd, 0, 1, &rect);
      d.vk.CmdSetBlendConstants(cmd, constants);
      d.vk.CmdDraw(cmd, 3, 1, 0, 0);
    }
    d.cmdEndRendering(cmd);
    return s;
  };
  const std::vector<float>& w = lv.spread.fadeWeights;
  const uint32_t n = lv.settings.layout.count();
  for (uint32_t i = 0; i < n; ++i) CANOPY_TRY(step(lv.fade, lv.colorLayerViews[i], lv.next.color, i, w[i]));
  if (!lv.hasRigid) return Status();  // both backgrounds stay cleared
  return step(lv.fadeBackground, lv.backgroundColor.view, lv.next.backgroundColor, 0, w[n]);
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
  copy(lv.next.color, lv.color);
  copy(lv.next.depth, lv.depth);
  copy(lv.next.backgroundColor, lv.backgroundColor);
  copy(lv.next.backgroundDepth, lv.backgroundDepth);
  return Status();
}

}  // namespace

bool operator==(const LayerSettings& a, const LayerSettings& b) {
  return a.layout == b.layout && a.regions == b.regions && a.slice == b.slice && a.draw == b.draw && a.policy == b.policy &&
         a.moveThreshold == b.moveThreshold && a.turnThresholdDegrees == b.turnThresholdDegrees &&
         a.lightDirection == b.lightDirection && a.lightColor == b.lightColor && a.ambient == b.ambient &&
         a.leafRefractiveIndex == b.leafRefractiveIndex && a.leafRoughness == b.leafRoughness &&
         a.leafTransmission == b.leafTransmission && a.translucency == b.translucency &&
         a.rebuildBudgetMs == b.rebuildBudgetMs && a.crossFadeFrames == b.crossFadeFrames && a.impostors == b.impostors;
}

Status validateLayerSettings(const LayerSettings& s) {
  // Each region first: their sum could wrap around 2^32.
  for (int i = 0; i < 3; ++i)
    if (s.layout.region[i] > kMaxLayers)
      return Status::error("layer settings: layout.region[" + std::to_string(i) + "] = " + std::to_string(s.layout.region[i]) +
                           " is outside [0, " + std::to_string(kMaxLayers) + "]");
  if (uint32_t(s.slice) > uint32_t(SliceMode::Geometry))
    return Status::error("layer settings: slice = " + std::to_string(uint32_t(s.slice)) + " is outside LeafRoots (0)..Geometry (1)");
  if (uint32_t(s.draw) > uint32_t(LayerDrawMode::PerLayer))
    return Status::error("layer settings: draw = " + std::to_string(uint32_t(s.draw)) + " is outside Auto (0)..PerLayer (2)");
  if (uint32_t(s.policy) > uint32_t(ReslicePolicy::EveryFrame))
    return Status::error("layer settings: policy = " + std::to_string(uint32_t(s.policy)) + " is outside OnViewChange (0)..EveryFrame (1)");
  if (s.layout.count() < 1 || s.layout.count() > kMaxLayers)
    return Status::error("layer settings: layout " + toString(s.layout) + " must hold 1.." + std::to_string(kMaxLayers) + " layers");
  CANOPY_TRY(validateRegionSplit(s.regions));
  if (!(s.moveThreshold >= 0 && s.moveThreshold <= 10))
    return Status::error("layer settings: moveThreshold " + std::to_string(s.moveThreshold) + " is outside [0, 10]");
  if (!(s.turnThresholdDegrees >= 0 && s.turnThresholdDegrees <= 180))
    return Status::error("layer settings: turnThresholdDegrees " + std::to_string(s.turnThresholdDegrees) + " is outside [0, 180]");
  if (!(s.rebuildBudgetMs >= 0 && s.rebuildBudgetMs <= 1000))
    return Status::error("layer settings: rebuildBudgetMs " + std::to_string(s.rebuildBudgetMs) + " is outside [0, 1000]");
  if (s.crossFadeFrames < 1 || s.crossFadeFrames > 240)
    return Status::error("layer settings: crossFadeFrames " + std::to_string(s.crossFadeFrames) + " is outside [1, 240]");
  if (!(s.ambient >= 0 && s.ambient <= 1))
    return Status::error("layer settings: ambient " + std::to_string(s.ambient) + " is outside [0, 1]");
  // The measured ranges Habel takes from Bousquet et al. (seed 004, III.B).
  if (!(s.leafRefractiveIndex >= LEAF_IOR_MIN && s.leafRefractiveIndex <= LEAF_IOR_MAX))
    return Status::error("layer settings: leafRefractiveIndex " + std::to_string(s.leafRefractiveIndex) +
                         " is outside the measured range [1.2, 1.7]");
  if (!(s.leafRoughness >= LEAF_ROUGHNESS_MIN && s.leafRoughness <= LEAF_ROUGHNESS_MAX))
    return Status::error("layer settings: leafRoughness " + std::to_string(s.leafRoughness) +
                         " is outside the measured range [0.078, 0.5]");
  if (!(s.leafTransmission >= 0 && s.leafTransmission <= 1))
    return Status::error("layer settings: leafTransmission " + std::to_string(s.leafTransmission) + " is outside [0, 1]");
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(toGlm(s.lightDirection)[i])) return Status::error("layer settings: lightDirection must be finite");
    if (!(toGlm(s.lightColor)[i] >= 0 && toGlm(s.lightColor)[i] <= 1000))
      return Status::error("layer settings: lightColor[" + std::to_string(i) + "] = " + std::to_string(toGlm(s.lightColor)[i]) +
                           " is outside [0, 1000]");
  }
  const ImpostorSettings& im = s.impostors;
  if (uint32_t(im.mode) > uint32_t(ImpostorMode::ByProjectedSize))
    return Status::error("layer settings: impostors.mode " + std::to_string(uint32_t(im.mode)) + " is not an ImpostorMode");
  if (!(im.switchPixels >= 1.0f && im.switchPixels <= 4096.0f))
    return Status::error("layer settings: impostors.switchPixels " + std::to_string(im.switchPixels) + " is outside [1, 4096]");
  if (!(im.band >= 0.0f && im.band <= 4.0f))
    return Status::error("layer settings: impostors.band " + std::to_string(im.band) + " is outside [0, 4]");
  return Status();
}

Status createLayeredVegetation(Device& d, const VegetationModel& m, const LayeredVegetationDesc& desc,
                               LayeredVegetation* out) {
  *out = LayeredVegetation{};
  LayeredVegetation& lv = *out;
  lv.device = &d;
  lv.desc = desc;
  lv.settings = desc.settings;
  if (desc.width < 1 || desc.width > 16384 || desc.height < 1 || desc.height > 16384)
    return Status::error("layers: size " + std::to_string(desc.width) + "x" + std::to_string(desc.height) +
                         " is outside 1..16384 per side");
  if (desc.colorFormat != VK_FORMAT_R16G16B16A16_SFLOAT && desc.colorFormat != VK_FORMAT_R8G8B8A8_UNORM)
    return Status::error("layers: colour format must be R16G16B16A16_SFLOAT or R8G8B8A8_UNORM");
  if (desc.writeIds && (!d.fragmentPrimitiveId || !d.independentBlend))
    return Status::error("layers: the id output needs gl_PrimitiveID in fragment shaders (geometryShader) and independentBlend");
  CANOPY_TRY(validateLayerSettings(desc.settings));
  if (m.uvs.size() != m.positions.size() || m.indices.size() % 3 || m.triangleMaterial.size() != m.triangleCount())
    return Status::error("layers: inconsistent model arrays in " + m.path);
  for (size_t i = 0; i < m.materials.size(); ++i) {
    const ModelMaterial& mm = m.materials[i];
    for (int32_t image : {mm.baseColorImage, mm.normalImage, mm.transmissionImage, mm.transmissionColorImage})
      if (image < -1 || image >= int32_t(m.images.size()))
        return Status::error("layers: material " + std::to_string(i) + " ('" + mm.name + "') names image " +
                             std::to_string(image) + " of " + std::to_string(m.images.size()));
  }
  if (desc.stagingRingBytes < 1 || desc.stagingRingBytes > (4ull << 30))
    return Status::error("layers: stagingRingBytes " + std::to_string(desc.stagingRingBytes) + " is outside [1, 4 GiB]");
  const uint64_t liveAtStart = d.allocator->liveBytes;
  Status s = [&]() -> Status {
    const auto t0 = std::chrono::steady_clock::now();
    CANOPY_TRY(splitMaterials(m, desc.split, &lv.split));
    lv.stats.foliageTriangles = lv.split.foliageTriangles;
    lv.stats.rigidTriangles = lv.split.rigidTriangles;
    std::vector<uint8_t> foliage(m.triangleCount());
    for (size_t t = 0; t < foliage.size(); ++t) foliage[t] = lv.split.role[m.triangleMaterial[t]] == MaterialRole::Foliage;
    LeafRoots roots;
    bool cached = false;
    const bool cacheOn = !desc.rootCacheDir.empty() && !m.path.empty();
    const std::string cachePath = cacheOn ? leafRootCachePath(m.path, desc.rootCacheDir) : std::string();
    uint64_t key = 0;
    if (cacheOn) {
      key = leafRootKey(m, foliage, desc.roots);
      std::string why;
      cached = readLeafRootCache(cachePath, key, m.positions.size(), &roots, &why);
      lv.stats.rootCacheNote = cached ? "read " + cachePath : cachePath + ": " + why;
    } else {
      lv.stats.rootCacheNote = "cache off";
    }
    if (!cached) {
      CANOPY_TRY(computeLeafRoots(m, foliage, desc.roots, &roots, desc.progress));
      if (cacheOn) {
        std::string evicted;
        Status w = writeLeafRootCache(cachePath, key, roots, desc.cacheMaxBytes, &evicted);
        lv.stats.rootCacheNote += w.ok() ? "; wrote it" : "; not written: " + w.message();
        if (!evicted.empty()) lv.stats.rootCacheNote += "; " + evicted;
      }
    }
    // Only the per-vertex leaf and the per-leaf root are used from here on, by the compaction; the
    // per-vertex root goes now and the rest after it (the placement reads the compact mesh).
    std::vector<uint32_t>().swap(roots.rootOfVertex);
    lv.stats.rootCacheHit = cached;
    lv.stats.leafCount = roots.leafCount();
    lv.stats.preprocessMs = msSince(t0);
    lv.materials = m.materials;
    lv.boundsMin = m.boundsMin;
    lv.boundsMax = m.boundsMax;
    lv.leafCount = roots.leafCount();
    CANOPY_TRY(chooseDrawPath(lv, lv.settings, &lv.singlePass));
    CompactMesh mesh;
    CANOPY_TRY(buildMesh(lv, m, foliage, roots, &mesh));
    roots = LeafRoots{};
    CANOPY_TRY(uploadTextures(lv, m));
    CANOPY_TRY(createTargets(lv));
    CANOPY_TRY(chooseMeshResidency(lv, liveAtStart, mesh.bytes()));
    CANOPY_TRY(placeMesh(lv, std::move(mesh), liveAtStart));
    CANOPY_TRY(createPipelines(lv));
    if (lv.imp.enabled) {
      if (lv.streamed)
        return Status::error("impostors (CanopyDesc.impostors.enable) bake from the resident mesh and cut it into draw "
                             "ranges: the mesh (" + mib(lv.stats.meshBytes) + ") is streamed under deviceMemoryBudget " +
                             mib(desc.deviceMemoryBudget) + "; raise it (or 0: no limit)");
      if (cacheOn) {
        // The views' file cache sits beside the leaf roots' and is keyed by what they are drawn from.
        const CompactMesh& hm = lv.hostMesh;
        const std::vector<uint64_t> meshHashes = {
            hashBytes(key, hm.vertices.data(), hm.vertices.size() * sizeof(gpu::LayerVertex)),
            hashBytes(key, hm.indices.data(), hm.indices.size() * 2),
            hashBytes(key, hm.roots.data(), hm.roots.size() * sizeof(gpu::LayerLeafRoot))};
        lv.imp.cachePath = impostorCachePath(m.path, desc.rootCacheDir);
        lv.imp.cacheKey = impostorModelKey(lv.imp, m, meshHashes);
        lv.imp.cacheMaxBytes = desc.cacheMaxBytes;
      }
      CANOPY_TRY(createImpostors(lv));
      lv.stats.impostorBoxes = uint32_t(lv.imp.nodes.size());
      lv.stats.impostorBakedBoxes = lv.imp.baked;
      lv.stats.impostorTilePixels = lv.imp.tileSize;
      lv.stats.impostorBytes = lv.imp.bytes;
      lv.stats.impostorBakeMs = lv.imp.bakeMs;
      lv.stats.impostorCacheHit = lv.imp.cacheHit;
      lv.stats.impostorCacheNote = lv.imp.cacheNote;
    }
    CANOPY_TRY(checkImpostorSettings(lv, lv.settings));
    lv.stats.singlePass = lv.singlePass;
    return Status();
  }();
  if (!s.ok()) {
    destroyLayeredVegetation(lv);
    return s.context("layers");
  }
  return Status();
}

void destroyLayeredVegetation(LayeredVegetation& lv) {
  if (!lv.device) return;
  Device& d = *lv.device;
  destroyTargets(lv);
  destroyImpostors(lv);
  for (GraphicsPipeline* p : {&lv.layered, &lv.perLayer, &lv.background, &lv.fade, &lv.fadeBackground})
    destroyGraphicsPipeline(d, *p);
  for (Image& t : lv.textures) destroyImage(d, t);
  for (VkSampler smp : {lv.sampler, lv.nearestSampler})
    if (smp) d.vk.DestroySampler(d.device, smp, d.allocationCallbacks);
  for (Buffer* b : {&lv.vertices, &lv.indexBuffer, &lv.leafRoots, &lv.frameBuffer, &lv.bendVertices}) destroyBuffer(d, *b);
  lv = LayeredVegetation{};
}

Status setLayerSettings(LayeredVegetation& lv, const LayerSettings& s, bool* targetsRecreated) {
  if (targetsRecreated) *targetsRecreated = false;
  CANOPY_TRY(validateLayerSettings(s));
  CANOPY_TRY(checkImpostorSettings(lv, s));
  bool single = false;
  CANOPY_TRY(chooseDrawPath(lv, s, &single));
  const bool nextSetBefore = usesNextSet(lv);
  const bool countChanged = s.layout.count() != lv.settings.layout.count();
  // How a re-slice is scheduled does not change what the layers hold: no re-slice for it.
  LayerSettings content = s;
  content.rebuildBudgetMs = lv.settings.rebuildBudgetMs;
  content.crossFadeFrames = lv.settings.crossFadeFrames;
  const bool contentChanged = !(content == lv.settings);
  if (s.rebuildBudgetMs != lv.settings.rebuildBudgetMs) {
    // A slice's cost is not linear in its triangles (fixed costs per frame): a rate measured with
    // other slice sizes does not carry over to the new budget. The still baseline does.
    lv.rate.trianglesPerMs = SliceRateControl{}.trianglesPerMs;
    lv.rate.rateSamples.clear();
  }
  lv.settings = s;
  lv.singlePass = single;
  lv.stats.singlePass = single;
  lv.settingsChanged = lv.settingsChanged || contentChanged;
  if (countChanged || usesNextSet(lv) != nextSetBefore) {
    destroyTargets(lv);
    CANOPY_TRY(createTargets(lv));
    if (targetsRecreated) *targetsRecreated = true;
    lv.settingsChanged = true;  // new images: empty until re-sliced
    lv.forceImmediate = true;   // nothing to fade from
  } else if (contentChanged && lv.spread.phase != SpreadPhase::Idle) {
    lv.spread = SpreadRebuild{};  // drawn with the old settings: start again
  }
  return Status();
}

Status setLayerTargetSize(LayeredVegetation& lv, uint32_t width, uint32_t height) {
  if (width < 1 || width > 16384 || height < 1 || height > 16384)
    return Status::error("layers: size " + std::to_string(width) + "x" + std::to_string(height) +
                         " is outside 1..16384 per side");
  if (width == lv.desc.width && height == lv.desc.height) return Status();
  destroyTargets(lv);
  lv.desc.width = width;
  lv.desc.height = height;
  lv.settingsChanged = true;  // the placement is in pixels of the old size: re-slice
  lv.forceImmediate = true;
  return createTargets(lv);
}

namespace {

// The interval since the last view update tells what the last frame's layer work cost
// (SliceRateControl); a drawing frame's triangles over its cost above the still baseline update
// the rate (frame times are noisy: see below).
void updateSliceRate(LayeredVegetation& lv) {
  SliceRateControl& r = lv.rate;
  const auto now = Clock::now();
  if (r.haveLast) {
    const double ms = std::chrono::duration<double, std::milli>(now - r.lastUpdate).count();
    constexpr size_t kStill = 15;
    // A placement frame is a still frame plus its (timed) CPU placement: a baseline sample too, so
    // an orbiting camera that never stands still still has one.
    if (r.lastWork == SliceRateControl::Work::None || r.lastWork == SliceRateControl::Work::Placement) {
      const double still = r.lastWork == SliceRateControl::Work::None ? ms : std::max(ms - r.lastPlacementMs, 0.0);
      if (r.stillMs.size() < kStill) r.stillMs.push_back(still);
      else r.stillMs[r.stillNext++ % kStill] = still;
    } else if (r.lastWork == SliceRateControl::Work::Slice && r.stillMs.size() >= 3 && r.lastTriangles > 0) {
      // Cautious up, quick down: a slice is never believed to cost under a quarter of the budget
      // (a lucky fast frame would otherwise ask for a huge next slice), the estimate follows the
      // median of the last five slices by at most x1.2 up / x0.5 down a frame, and a slice that
      // cost over twice the budget halves it at once.
      const double budget = std::max<double>(lv.settings.rebuildBudgetMs, 1e-3);
      const double raw = ms - median(r.stillMs);
      const double measured = double(r.lastTriangles) / std::max(raw, 0.25 * budget);
      constexpr size_t kSamples = 5;
      if (r.rateSamples.size() < kSamples) r.rateSamples.push_back(measured);
      else r.rateSamples[r.rateNext++ % kSamples] = measured;
      r.trianglesPerMs *= std::clamp(median(r.rateSamples) / r.trianglesPerMs, 0.5, 1.2);
      if (raw > 2.0 * budget) r.trianglesPerMs = std::min(r.trianglesPerMs, 0.5 * double(r.lastTriangles) / budget);
    }
  }
  r.haveLast = true;
  r.lastUpdate = now;
  r.lastWork = SliceRateControl::Work::None;
  r.lastTriangles = 0;
}

// The next frame's draws of a spread re-slice: triangles from the cursor, as many as the budget
// and the measured rate allow (at least 1024, so it always ends); a streamed mesh also stops at
// what this frame's ring segment holds, and its parts are copied there now (the frame that reads
// them is the one being recorded: docs/design.md "Layers: mesh budget and staging ring").
void planSlice(LayeredVegetation& lv) {
  SpreadRebuild& sp = lv.spread;
  const uint64_t want = sp.immediate ? UINT64_MAX
                        : lv.desc.fixedSliceTriangles
                            ? lv.desc.fixedSliceTriangles
                            : std::max<uint64_t>(1024, uint64_t(lv.settings.rebuildBudgetMs * lv.rate.trianglesPerMs));
  sp.slice.clear();
  sp.sliceClears = sp.cursorChunk == 0 && sp.cursorTriangle == 0;
  MeshRing& r = lv.ring;
  uint64_t segment = 0, usedV = 0, usedI = 0, usedR = 0;
  if (lv.streamed) {
    const Device& d = *lv.device;
    segment = (d.anyFrame ? d.frameNumber : r.counter++) % r.segments;
  }
  uint64_t drawn = 0;
  while (sp.cursorChunk < lv.chunks.size() && drawn < want) {
    const MeshChunk& c = lv.chunks[sp.cursorChunk];
    uint32_t count = uint32_t(std::min<uint64_t>(c.triangleCount - sp.cursorTriangle, want - drawn));
    ChunkPart part{sp.cursorChunk, sp.cursorTriangle, count};
    if (lv.streamed && count) {
      const uint64_t roots = roundUp(std::max<uint32_t>(c.rootCount, 1), r.rootAlignment);
      if (usedV + c.vertexCount > r.vertexCapacity || usedR + roots > r.rootCapacity || usedI + 3 > r.indexCapacity) break;
      part.triangleCount = count = uint32_t(std::min<uint64_t>(count, (r.indexCapacity - usedI) / 3));
      part.ringVertex = segment * r.vertexCapacity + usedV;
      part.ringIndex = segment * roundUp(r.indexCapacity * 2, 4) / 2 + usedI;
      part.ringRoot = segment * r.rootCapacity + usedR;
      auto* v = static_cast<gpu::LayerVertex*>(lv.vertices.allocation.mapped);
      auto* ix = static_cast<uint16_t*>(lv.indexBuffer.allocation.mapped);
      auto* rt = static_cast<gpu::LayerLeafRoot*>(lv.leafRoots.allocation.mapped);
      std::memcpy(v + part.ringVertex, lv.hostMesh.vertices.data() + c.firstVertex, size_t(c.vertexCount) * sizeof(gpu::LayerVertex));
      std::memcpy(ix + part.ringIndex, lv.hostMesh.indices.data() + c.firstIndex + 3ull * part.firstTriangle, size_t(count) * 6);
      std::memcpy(rt + part.ringRoot, lv.hostMesh.roots.data() + c.firstRoot, size_t(c.rootCount) * sizeof(gpu::LayerLeafRoot));
      usedV += c.vertexCount;
      usedI += 3ull * count;
      usedR += roots;
    }
    if (count) sp.slice.push_back(part);
    drawn += count;
    sp.cursorTriangle += count;
    if (sp.cursorTriangle >= c.triangleCount) {
      sp.cursorChunk++;
      sp.cursorTriangle = 0;
    }
  }
  lv.slicePending = true;
  // A slice sized by the ring alone says nothing about the drawing rate the budget sizes.
  lv.rate.lastWork = sp.immediate ? SliceRateControl::Work::Other : SliceRateControl::Work::Slice;
  lv.rate.lastTriangles = drawn;
  lv.stats.lastSliceTriangles = drawn;
  lv.stats.maxSliceTriangles = std::max(lv.stats.maxSliceTriangles, drawn);
}

LayerInfo mixLayerInfo(const LayerInfo& a, const LayerInfo& b, float t) {
  LayerInfo m = b;
  m.slab.depth = glm::mix(a.slab.depth, b.slab.depth, t);
  m.slab.distance = glm::mix(a.slab.distance, b.slab.distance, t);
  m.top = glm::mix(a.top, b.top, t);
  m.rootLineY = glm::mix(a.rootLineY, b.rootLineY, t);
  m.height = glm::mix(a.height, b.height, t);
  return m;
}

// The frame of the last step (the copy of the next set): its placement becomes the visible one.
void finishSpread(LayeredVegetation& lv) {
  SpreadRebuild& sp = lv.spread;
  lv.frame = sp.job.frame;
  lv.layers = std::move(sp.job.layers);
  lv.stats.spreadRebuilds++;
  lv.stats.lastSpreadFrames = sp.frames;
  lv.stats.crossFade = 1.0f;
  sp.phase = SpreadPhase::Idle;
  sp.job = PlacementJob{};
  sp.fadeFrom.clear();
}

// One frame of a spread re-slice: placement for up to the budget, then slices, then the fade.
Status advanceSpread(LayeredVegetation& lv) {
  SpreadRebuild& sp = lv.spread;
  sp.frames++;
  switch (sp.phase) {
    case SpreadPhase::Placing: {
      const auto deadline = Clock::now() + std::chrono::duration<double, std::milli>(lv.settings.rebuildBudgetMs);
      const auto deadlineTp = std::chrono::time_point_cast<Clock::duration>(deadline);
      bool done = false;
      const double before = sp.job.ms;
      CANOPY_TRY(advancePlacement(lv, sp.job, sp.immediate ? nullptr : &deadlineTp, &done));
      lv.rate.lastWork = SliceRateControl::Work::Placement;
      lv.rate.lastPlacementMs = sp.job.ms - before;
      if (done) {
        lv.stats.lastPlacementMs = sp.job.ms;
        sp.phase = SpreadPhase::Drawing;
        // No visible placement of this layer count yet (the first view, or new layer images, of a
        // streamed mesh): the new one describes the visible images, still empty, until the copy.
        if (lv.layers.size() != sp.job.layers.size()) {
          lv.layers = sp.job.layers;
          lv.frame = sp.job.frame;
        }
      }
      if (!done || !sp.immediate) break;
      [[fallthrough]];  // asked at once: the first slice in the placement's frame
    }
    case SpreadPhase::Drawing:
      planSlice(lv);
      if (sp.cursorChunk < lv.chunks.size()) break;
      if (!sp.immediate) {
        sp.phase = SpreadPhase::CrossFading;  // from the next frame
        break;
      }
      // Asked at once: the next set is copied in behind the last slice (the copy pass follows the
      // slice pass), without a fade, and the occupancy recomputed in this frame.
      sp.fadeCopy = true;
      lv.fadePending = true;
      lv.occupancyRecomputeNow = true;
      finishSpread(lv);
      break;
    case SpreadPhase::CrossFading: {
      lv.rate.lastWork = SliceRateControl::Work::Other;
      if (!sp.united) {  // the composite unites the next set's occupancy in; no blend this frame
        sp.united = true;
        lv.occupancyUniteNext = true;
        break;
      }
      // F frames: F - 1 blend frames, then a copy of the next set (depth included). Each frame blends
      // every other image (layers and background alternate), which halves a blend frame's cost; an
      // image blended H times before the copy takes weight 1 / (H + 2 - j) at its j-th blend, so its
      // new share is j / (H + 1) and the copy ends it at 1.
      const uint32_t f = lv.settings.crossFadeFrames, n = lv.settings.layout.count(), blends = f - 1;
      if (sp.fadeStep == 0) sp.fadeFrom = lv.layers;
      sp.fadeStep++;
      sp.fadeCopy = sp.fadeStep >= f;
      sp.fadeWeights.assign(n + 1, 0.0f);
      if (!sp.fadeCopy) {
        for (uint32_t i = 0; i <= n; ++i) {
          const bool alternate = blends >= 2;
          if (alternate && (sp.fadeStep + i) % 2 != 0) continue;
          const uint32_t h = !alternate ? blends : (i % 2 == 0 ? blends / 2 : (blends + 1) / 2);
          // Image i blends at frames k with k + i even: its j-th blend is at k = 2j - (i odd).
          const uint32_t j = !alternate ? sp.fadeStep : (sp.fadeStep + i % 2) / 2;
          sp.fadeWeights[i] = 1.0f / float(h + 2 - std::min(j, h));
        }
      }
      const float share = float(sp.fadeStep) / float(f);
      lv.fadePending = true;
      lv.stats.crossFade = share;
      if (sp.fadeCopy) {
        lv.occupancyRecomputeNext = true;
        finishSpread(lv);
      } else {
        for (size_t i = 0; i < lv.layers.size(); ++i) lv.layers[i] = mixLayerInfo(sp.fadeFrom[i], sp.job.layers[i], share);
      }
      break;
    }
    case SpreadPhase::Idle: break;
  }
  return Status();
}

}  // namespace

Status updateLayerView(LayeredVegetation& lv, const LayerView& view, bool* changed) {
  lv.stats.viewUpdates++;
  updateSliceRate(lv);
  lv.rebuildPending = lv.slicePending = lv.fadePending = lv.occupancyUniteNext = lv.occupancyRecomputeNow = false;
  const bool recomputeOccupancy = lv.occupancyRecomputeNext;
  lv.occupancyRecomputeNext = false;
  std::string reason;
  const LayerSettings& s = lv.settings;
  bool forced = false;
  if (!lv.haveView) {
    reason = "first view";
  } else if (!lv.forcedReason.empty()) {
    reason = lv.forcedReason;
    forced = true;
  } else if (lv.settingsChanged) {
    reason = "settings changed";
    forced = true;
  } else if (s.policy == ReslicePolicy::EveryFrame) {
    reason = "every frame";
  } else {
    const float radius = std::max(0.5f * glm::length(lv.boundsMax - lv.boundsMin), 1e-6f);
    const float moved = glm::length(viewPosition(view.view) - viewPosition(lv.lastRebuildView.view)) / radius;
    const float turned = std::max(angleDegrees(viewForward(view.view), viewForward(lv.lastRebuildView.view)),
                                  angleDegrees(viewUp(view.view), viewUp(lv.lastRebuildView.view)));
    if (moved > s.moveThreshold) {
      reason = "camera moved " + std::to_string(moved) + " radii (threshold " + std::to_string(s.moveThreshold) + ")";
    } else if (turned > s.turnThresholdDegrees) {
      reason = "camera turned " + std::to_string(turned) + " degrees (threshold " + std::to_string(s.turnThresholdDegrees) + ")";
    } else if (matricesDiffer(view.proj, lv.lastRebuildView.proj)) {
      reason = "projection changed";
    }
  }
  const bool wantAtOnce = !lv.haveView || lv.forceImmediate || !spreadEnabled(lv) || s.policy == ReslicePolicy::EveryFrame;
  // A streamed mesh cannot be drawn in one frame: "at once" becomes slices as large as the ring
  // allows, copied in without a fade (SpreadRebuild.immediate).
  const bool atOnce = wantAtOnce && !lv.streamed;
  const bool spreading = lv.spread.phase != SpreadPhase::Idle;
  // A spread re-slice runs to its end for its own view; the policy looks again afterwards (a forced
  // re-slice or new settings restart it).
  if (!reason.empty() && (atOnce || !spreading || forced)) {
    lv.haveView = true;
    lv.settingsChanged = false;
    lv.forcedReason.clear();
    lv.forceImmediate = false;
    lv.lastRebuildView = view;
    lv.stats.rebuilds++;
    lv.stats.lastRebuildReason = reason;
    if (atOnce) {
      lv.spread = SpreadRebuild{};
      CANOPY_TRY(placeForView(lv, view));
      lv.rebuildPending = true;
      lv.rate.lastWork = SliceRateControl::Work::Other;
      lv.stats.crossFade = 1.0f;
    } else {
      lv.spread = SpreadRebuild{};
      lv.spread.phase = SpreadPhase::Placing;
      lv.spread.immediate = wantAtOnce;
      lv.stats.maxSliceTriangles = 0;
      beginPlacement(lv, view, lv.spread.job);
      lv.stats.crossFade = 0.0f;
    }
  }
  if (lv.spread.phase != SpreadPhase::Idle) CANOPY_TRY(advanceSpread(lv));
  lv.stats.spreadPhase = uint32_t(lv.spread.phase);
  lv.stats.trianglesPerMs = lv.rate.trianglesPerMs;
  *changed = lv.rebuildPending || lv.fadePending;
  // The composite's occupancy: recomputed after a re-slice at once and in the frame after a
  // cross-fade's copy; the frame after the last slice unites the next set's tiles in
  // (occupancyUniteNext), which covers every fade step (old and new both partly visible) without
  // a recompute in a fade frame. (Marking the views' whole footprint occupied instead was tried:
  // the composite then works through every footprint tile of every layer, 60-70 ms a fade frame
  // more at 80K faces on lavapipe.)
  lv.occupancyDirty = lv.rebuildPending || recomputeOccupancy || lv.occupancyRecomputeNow;
  return Status();
}

Status importMesh(const LayeredVegetation& lv, rg::RenderGraph& g, MeshResources* out) {
  const rg::State vb = rg::stateOf(rg::Use::VertexBuffer), ib = rg::stateOf(rg::Use::IndexBuffer),
                  roots = rg::stateOf(rg::Use::VertexStorageRead);
  out->vertices = g.importBuffer("layers: vertices", lv.vertices.size, vb, vb);
  out->indices = g.importBuffer("layers: indices", lv.indexBuffer.size, ib, ib);
  out->roots = g.importBuffer("layers: leaf roots", lv.leafRoots.size, roots, roots);
  CANOPY_TRY(g.bindBuffer(out->vertices, lv.vertices.buffer));
  CANOPY_TRY(g.bindBuffer(out->indices, lv.indexBuffer.buffer));
  return g.bindBuffer(out->roots, lv.leafRoots.buffer);
}

rg::RenderGraph::PassBuilder& readsMesh(rg::RenderGraph::PassBuilder& pass, const MeshResources& mesh) {
  return pass.read(mesh.vertices, rg::Use::VertexBuffer)
      .read(mesh.indices, rg::Use::IndexBuffer)
      .read(mesh.roots, rg::Use::VertexStorageRead);
}

Status addLayerPasses(LayeredVegetation& lv, rg::RenderGraph& g, LayerResources* out) {
  if (!lv.device) return Status::error("addLayerPasses: the layered vegetation was not created");
  const rg::State rest = rg::stateOf(lv.desc.restUse);
  LayerResources r;
  r.color = g.importImage("layers: colour", descOf(lv.color), rest, rest);
  r.depth = g.importImage("layers: depth", descOf(lv.depth), rest, rest);
  if (lv.desc.writeIds) r.ids = g.importImage("layers: ids", descOf(lv.ids), rest, rest);
  r.backgroundColor = g.importImage("background: colour", descOf(lv.backgroundColor), rest, rest);
  r.backgroundDepth = g.importImage("background: depth", descOf(lv.backgroundDepth), rest, rest);
  MeshResources mesh;
  CANOPY_TRY(importMesh(lv, g, &mesh));
  const auto frame = g.importBuffer("layers: frame", lv.frameBuffer.size, kFrameRead, kFrameRead);
  // Impostors (render/impostor_gpu.cpp): the re-slice's list, the box table and the baked atlas.
  rg::ResourceId impostorList = rg::kInvalidResource, impostorBoxes = rg::kInvalidResource,
                 atlasColor = rg::kInvalidResource, atlasDepth = rg::kInvalidResource;
  if (lv.imp.enabled) {
    const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
    impostorList = g.importBuffer("impostors: instances", lv.imp.instances.size, kFrameRead, kFrameRead);
    impostorBoxes = g.importBuffer("impostors: boxes", lv.imp.boxTable.size, kFrameRead, kFrameRead);
    atlasColor = g.importImage("impostors: colour atlas", descOf(lv.imp.color), sampled, sampled);
    atlasDepth = g.importImage("impostors: depth atlas", descOf(lv.imp.depth), sampled, sampled);
    CANOPY_TRY(g.bindBuffer(impostorList, lv.imp.instances.buffer));
    CANOPY_TRY(g.bindBuffer(impostorBoxes, lv.imp.boxTable.buffer));
    CANOPY_TRY(g.bindImage(atlasColor, lv.imp.color));
    CANOPY_TRY(g.bindImage(atlasDepth, lv.imp.depth));
  }
  LayeredVegetation* p = &lv;
  // What every mesh draw reads: the frame block and the chunked mesh.
  auto drawsMesh = [&](rg::RenderGraph::PassBuilder b) { return readsMesh(b.access(frame, kFrameRead), mesh); };
  // The frame block holds the placement being drawn: the visible one for a re-slice at once, the
  // spread re-slice's from its first slice on.
  // Every layer pass runs only in the frames that have its work (rg `when`): a still frame records
  // neither the passes nor their barriers (the layer images stay in their rest state).
  auto constants = g.addPass("layers: frame constants", [p](rg::PassContext& c) {
     if (p->rebuildPending) c.device->vk.CmdUpdateBuffer(c.cmd, p->frameBuffer.buffer, 0, sizeof(gpu::LayerFrame), &p->frame);
     // The cut's impostor list, in vkCmdUpdateBuffer's 64 KiB pieces.
     if (p->rebuildPending && !p->cutInstances.empty()) {
       const size_t bytes = p->cutInstances.size() * sizeof(gpu::ImpostorInstance);
       for (size_t at = 0; at < bytes; at += 65536)
         c.device->vk.CmdUpdateBuffer(c.cmd, p->imp.instances.buffer, at, std::min<size_t>(65536, bytes - at),
                                      reinterpret_cast<const uint8_t*>(p->cutInstances.data()) + at);
     }
     else if (p->slicePending && p->spread.sliceClears)
       c.device->vk.CmdUpdateBuffer(c.cmd, p->frameBuffer.buffer, 0, sizeof(gpu::LayerFrame), &p->spread.job.frame);
     return Status();
   })
      .write(frame, rg::Use::TransferDst)
      .when([p] { return p->rebuildPending || (p->slicePending && p->spread.sliceClears); });
  if (impostorList != rg::kInvalidResource) constants.write(impostorList, rg::Use::TransferDst);
  auto foliage = g.addPass("layers: foliage", [p](rg::PassContext& c) {
                    return p->rebuildPending ? recordFoliage(*p, c.cmd, visibleTargets(*p), true, nullptr) : Status();
                  });
  drawsMesh(foliage)
      .write(r.color, rg::Use::ColorAttachmentWrite)
      .write(r.depth, rg::Use::DepthAttachmentWrite)
      .when([p] { return p->rebuildPending; });
  if (lv.desc.writeIds) foliage.write(r.ids, rg::Use::ColorAttachmentWrite);
  if (lv.imp.enabled)
    foliage.access(impostorList, kFrameRead)
        .access(impostorBoxes, kFrameRead)
        .read(atlasColor, rg::Use::FragmentSampled)
        .read(atlasDepth, rg::Use::FragmentSampled);
  drawsMesh(g.addPass("layers: background", [p](rg::PassContext& c) {
     return p->rebuildPending && p->hasRigid ? recordBackground(*p, c.cmd, visibleTargets(*p), true, nullptr)
                                                        : Status();
   }))
      .write(r.backgroundColor, rg::Use::ColorAttachmentWrite)
      .write(r.backgroundDepth, rg::Use::DepthAttachmentWrite)
      .when([p] { return p->rebuildPending && p->hasRigid; });
  if (lv.next.color.image) {
    // Spread re-slicing (docs/design.md "Layers: spread re-slicing"): this frame's slice into the
    // next set (loaded: earlier slices are kept), then a cross-fade step into the visible set.
    const auto nextColor = g.importImage("layers (next set): colour", descOf(lv.next.color), kNextRest, kNextRest);
    const auto nextDepth = g.importImage("layers (next set): depth", descOf(lv.next.depth), kNextRest, kNextRest);
    const auto nextBgColor = g.importImage("background (next set): colour", descOf(lv.next.backgroundColor), kNextRest, kNextRest);
    const auto nextBgDepth = g.importImage("background (next set): depth", descOf(lv.next.backgroundDepth), kNextRest, kNextRest);
    drawsMesh(g.addPass("layers: spread slice", [p](rg::PassContext& c) -> Status {
       if (!p->slicePending) return Status();
       const bool clear = p->spread.sliceClears;
       if (clear || sliceHas(*p, true)) CANOPY_TRY(recordFoliage(*p, c.cmd, nextTargets(*p), clear, &p->spread.slice));
       if (p->hasRigid && (clear || sliceHas(*p, false)))
         CANOPY_TRY(recordBackground(*p, c.cmd, nextTargets(*p), clear, &p->spread.slice));
       return Status();
     }))
        .write(nextColor, rg::Use::ColorAttachmentReadWrite)
        .write(nextDepth, rg::Use::DepthAttachmentWrite)
        .write(nextBgColor, rg::Use::ColorAttachmentReadWrite)
        .write(nextBgDepth, rg::Use::DepthAttachmentWrite)
        .when([p] { return p->slicePending; });
    const bool rigid = lv.hasRigid;
    auto blend = g.addPass("layers: cross-fade", [p](rg::PassContext& c) {
      return p->fadePending && !p->spread.fadeCopy ? recordFadeBlend(*p, c.cmd) : Status();
    });
    blend.read(nextColor, rg::Use::FragmentSampled).write(r.color, rg::Use::ColorAttachmentReadWrite);
    blend.when([p] { return p->fadePending && !p->spread.fadeCopy; });
    if (rigid) blend.read(nextBgColor, rg::Use::FragmentSampled).write(r.backgroundColor, rg::Use::ColorAttachmentReadWrite);
    g.addPass("layers: cross-fade (last step)", [p](rg::PassContext& c) {
       return p->fadePending && p->spread.fadeCopy ? recordFadeCopy(*p, c.cmd) : Status();
     })
        .read(nextColor, rg::Use::TransferSrc)
        .read(nextDepth, rg::Use::TransferSrc)
        .read(nextBgColor, rg::Use::TransferSrc)
        .read(nextBgDepth, rg::Use::TransferSrc)
        .write(r.color, rg::Use::TransferDst)
        .write(r.depth, rg::Use::TransferDst)
        .write(r.backgroundColor, rg::Use::TransferDst)
        .write(r.backgroundDepth, rg::Use::TransferDst)
        .when([p] { return p->fadePending && p->spread.fadeCopy; });
    r.nextColor = nextColor;
    r.nextBackgroundColor = nextBgColor;
    CANOPY_TRY(g.bindImage(nextColor, lv.next.color));
    CANOPY_TRY(g.bindImage(nextDepth, lv.next.depth));
    CANOPY_TRY(g.bindImage(nextBgColor, lv.next.backgroundColor));
    CANOPY_TRY(g.bindImage(nextBgDepth, lv.next.backgroundDepth));
  }
  CANOPY_TRY(g.bindImage(r.color, lv.color));
  CANOPY_TRY(g.bindImage(r.depth, lv.depth));
  if (lv.desc.writeIds) CANOPY_TRY(g.bindImage(r.ids, lv.ids));
  CANOPY_TRY(g.bindImage(r.backgroundColor, lv.backgroundColor));
  CANOPY_TRY(g.bindImage(r.backgroundDepth, lv.backgroundDepth));
  CANOPY_TRY(g.bindBuffer(frame, lv.frameBuffer.buffer));
  if (out) *out = r;
  return Status();
}

namespace {
Status readColorImage(LayeredVegetation& lv, const Image& img, uint32_t layer, std::vector<glm::vec4>* rgba) {
  const size_t n = size_t(img.extent.width) * img.extent.height;
  rgba->assign(n, glm::vec4(0));
  if (img.format == VK_FORMAT_R16G16B16A16_SFLOAT) {
    std::vector<uint64_t> raw(n);
    CANOPY_TRY(readbackImage(*lv.device, img, layer, 8, raw.data(), rg::stateOf(lv.desc.restUse)));
    for (size_t i = 0; i < n; ++i) {
      const glm::uvec2 halves(uint32_t(raw[i]), uint32_t(raw[i] >> 32));
      (*rgba)[i] = glm::vec4(glm::unpackHalf2x16(halves.x), glm::unpackHalf2x16(halves.y));
    }
  } else {
    std::vector<uint32_t> raw(n);
    CANOPY_TRY(readbackImage(*lv.device, img, layer, 4, raw.data(), rg::stateOf(lv.desc.restUse)));
    for (size_t i = 0; i < n; ++i) (*rgba)[i] = glm::unpackUnorm4x8(raw[i]);
  }
  return Status();
}
}  // namespace

Status readLayerColor(LayeredVegetation& lv, uint32_t layer, std::vector<glm::vec4>* rgba) {
  return readColorImage(lv, lv.color, layer, rgba);
}

Status readLayerDepth(LayeredVegetation& lv, uint32_t layer, std::vector<float>* depth) {
  depth->assign(size_t(lv.desc.width) * lv.desc.height, 0.0f);
  return readbackImage(*lv.device, lv.depth, layer, 4, depth->data(), rg::stateOf(lv.desc.restUse));
}

Status readLayerIds(LayeredVegetation& lv, uint32_t layer, std::vector<glm::uvec2>* ids) {
  if (!lv.desc.writeIds) return Status::error("readLayerIds: created without writeIds");
  ids->assign(size_t(lv.desc.width) * lv.desc.height, glm::uvec2(0));
  return readbackImage(*lv.device, lv.ids, layer, 8, ids->data(), rg::stateOf(lv.desc.restUse));
}

Status readBackground(LayeredVegetation& lv, std::vector<glm::vec4>* rgba, std::vector<float>* depth) {
  CANOPY_TRY(readColorImage(lv, lv.backgroundColor, 0, rgba));
  depth->assign(size_t(lv.desc.width) * lv.desc.height, 0.0f);
  return readbackImage(*lv.device, lv.backgroundDepth, 0, 4, depth->data(), rg::stateOf(lv.desc.restUse));
}

}  // namespace canopy
