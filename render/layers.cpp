#include "render/layers.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <glm/gtc/packing.hpp>

#include "engine/device.h"
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

// Frees the layer images once no host frame in flight can read them (deferRelease), so a new
// layer count or size never waits for the device.
void destroyTargets(LayeredVegetation& lv) {
  Device* d = lv.device;
  dropPreparedWork(*d, lv.pendingClear);  // a clear of these images never recorded: nothing to wait for
  std::vector<VkImageView> views;
  for (auto* v : {&lv.colorLayerViews, &lv.depthLayerViews, &lv.idsLayerViews}) {
    views.insert(views.end(), v->begin(), v->end());
    v->clear();
  }
  std::vector<Image> images;
  for (Image* img : {&lv.color, &lv.depth, &lv.ids, &lv.backgroundColor, &lv.backgroundDepth}) {
    if (img->image) images.push_back(*img);
    *img = Image{};
  }
  deferRelease(*d, [d, views, images]() mutable {
    for (VkImageView v : views) d->vk.DestroyImageView(d->device, v, d->allocationCallbacks);
    for (Image& img : images) destroyImage(*d, img);
  });
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

Status createPipelines(LayeredVegetation& lv) {
  Device& d = *lv.device;
  GraphicsPipelineDesc p;
  p.bindings = {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER};
  p.pushConstantSize = sizeof(gpu::LayerDrawPush);
  p.vertexStride = sizeof(gpu::LayerVertex);
  p.attributes = {{0, VK_FORMAT_R16G16B16A16_UINT, 0},  // quantised position, chunk-local leaf
                  {1, VK_FORMAT_R16G16_SNORM, 8},        // octahedral normal
                  {2, VK_FORMAT_R16G16_SFLOAT, 12}};     // texcoord 0
  p.colorFormats = {lv.desc.colorFormat};
  p.depthFormat = kDepthFormat;
  p.blend = BlendMode::PremultipliedOver;
  p.fragmentShader = "layers.frag";
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

Status uploadMesh(LayeredVegetation& lv, const VegetationModel& m, const std::vector<uint8_t>& foliage,
                  const LeafRoots& roots) {
  Device& d = *lv.device;
  const size_t nt = m.triangleCount();
  // GPU triangle order: foliage grouped by material, then rigid by material (one draw each).
  const size_t nm = m.materials.size();
  std::vector<uint64_t> start(2 * nm + 1, 0);
  for (size_t t = 0; t < nt; ++t) start[(foliage[t] ? 0 : nm) + m.triangleMaterial[t] + 1]++;
  for (size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  lv.indices.assign(nt * 3, 0);
  lv.gpuToModelTriangle.assign(nt, 0);
  std::vector<uint64_t> cursor(start.begin(), start.end() - 1);
  for (size_t t = 0; t < nt; ++t) {
    const uint64_t slot = cursor[(foliage[t] ? 0 : nm) + m.triangleMaterial[t]]++;
    std::memcpy(&lv.indices[slot * 3], &m.indices[t * 3], 12);
    lv.gpuToModelTriangle[slot] = uint32_t(t);
  }
  for (size_t k = 0; k < 2 * nm; ++k) {
    if (start[k + 1] == start[k]) continue;
    LayerDraw draw{uint32_t(k % nm), uint32_t(start[k] * 3), uint32_t((start[k + 1] - start[k]) * 3)};
    (k < nm ? lv.foliageDraws : lv.rigidDraws).push_back(draw);
  }
  // The compact chunked mesh (render/mesh_chunks.h): 16-byte vertices, 16-bit indices and a
  // leaf-root table per chunk, so no buffer is indexed past the device's storage range.
  std::vector<TriangleRange> ranges;
  for (const LayerDraw& dr : lv.foliageDraws) ranges.push_back({dr.material, true, dr.firstIndex / 3, dr.indexCount / 3});
  for (const LayerDraw& dr : lv.rigidDraws) ranges.push_back({dr.material, false, dr.firstIndex / 3, dr.indexCount / 3});
  CompactMeshOptions co;
  co.maxChunkVertices = lv.desc.maxChunkVertices;
  const VkDeviceSize align = std::max<VkDeviceSize>(d.properties.limits.minStorageBufferOffsetAlignment, 1);
  co.rootAlignment = uint32_t((align + sizeof(gpu::LayerLeafRoot) - 1) / sizeof(gpu::LayerLeafRoot));
  if (align % sizeof(gpu::LayerLeafRoot) && sizeof(gpu::LayerLeafRoot) % align)
    return Status::error("layers: minStorageBufferOffsetAlignment " + std::to_string(align) + " is not a power of two");
  CompactMesh mesh;
  CANOPY_TRY(buildCompactMesh(m, lv.indices, ranges, roots, co, &mesh, lv.desc.progress));
  lv.stats.meshChunks = uint32_t(mesh.chunks.size());
  lv.stats.meshBytes = mesh.bytes();
  lv.chunks = std::move(mesh.chunks);
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
  CANOPY_TRY(upload(lv.leafRoots, mesh.roots.data(), mesh.roots.size() * sizeof(gpu::LayerLeafRoot),
                    VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, rg::Use::VertexStorageRead, "layers: leaf roots"));
  CANOPY_TRY(createBuffer(d, sizeof(gpu::LayerFrame), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                          MemoryUsage::DeviceLocal, &lv.frameBuffer, "layers: frame"));
  // Textures: sRGB base colour, so the shader reads linear values; a white texel for untextured materials.
  const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
  for (size_t i = 0; i <= m.images.size(); ++i) {
    static const uint8_t white[4] = {255, 255, 255, 255};
    const bool isWhite = i == m.images.size();
    ImageDesc t;
    t.format = VK_FORMAT_R8G8B8A8_SRGB;
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

bool matricesDiffer(const glm::mat4& a, const glm::mat4& b) {
  for (int c = 0; c < 4; ++c)
    for (int r = 0; r < 4; ++r)
      if (std::abs(a[c][r] - b[c][r]) > 1e-5f * std::max(1.0f, std::abs(b[c][r]))) return true;
  return false;
}

float angleDegrees(const glm::vec3& a, const glm::vec3& b) {
  return glm::degrees(std::acos(std::clamp(glm::dot(a, b), -1.0f, 1.0f)));
}

// Depth range of the slicing keys, layer boundaries and per-layer bounds for `view`.
Status placeForView(LayeredVegetation& lv, const LayerView& view) {
  const auto t0 = std::chrono::steady_clock::now();
  const LayerSettings& s = lv.settings;
  gpu::LayerFrame& f = lv.frame;
  f = gpu::LayerFrame{};
  f.viewProj = view.proj * view.view;
  f.depthRow = -glm::vec4(view.view[0][2], view.view[1][2], view.view[2][2], view.view[3][2]);
  const glm::vec3 dir = toGlm(s.lightDirection);
  const glm::vec3 l = glm::length(dir) > 0 ? glm::normalize(dir) : glm::vec3(0, 1, 0);
  f.lightDirection = glm::vec4(l, s.ambient);
  f.lightColor = glm::vec4(toGlm(s.lightColor), 1.0f);
  f.layerCount = s.layout.count();
  f.sliceMode = s.slice == SliceMode::Geometry ? LAYER_SLICE_GEOMETRY : LAYER_SLICE_LEAF_ROOT;
  auto depthOf = [&](const glm::vec3& p) { return glm::dot(f.depthRow, glm::vec4(p, 1.0f)); };
  const bool geometric = s.slice == SliceMode::Geometry;
  const uint32_t nLeaves = uint32_t(lv.leafRootPosition.size());
  // The keys the layers are assigned by: leaf roots, or every foliage vertex for geometric slicing.
  float zMin = INFINITY, zMax = -INFINITY;
  std::vector<float> leafDepth(nLeaves);
  for (uint32_t i = 0; i < nLeaves; ++i) {
    leafDepth[i] = depthOf(lv.leafRootPosition[i]);
    if (!geometric) {
      zMin = std::min(zMin, leafDepth[i]);
      zMax = std::max(zMax, leafDepth[i]);
    }
  }
  if (geometric)
    for (size_t v = 0; v < lv.positions.size(); ++v)
      if (lv.leafOfVertex[v] != kNoLeaf) {
        const float z = depthOf(lv.positions[v]);
        zMin = std::min(zMin, z);
        zMax = std::max(zMax, z);
      }
  if (!(zMin <= zMax)) zMin = zMax = 0.0f;  // no foliage: empty layers
  std::vector<LayerSlab> slabs;
  std::vector<float> bounds;
  CANOPY_TRY(placeLayers(s.layout, s.regions, zMin, zMax, &slabs, &bounds));
  for (uint32_t i = 0; i <= CANOPY_MAX_LAYERS; ++i) f.boundaries[i] = bounds[std::min<size_t>(i, bounds.size() - 1)];
  // Per-layer statistics and the screen-space root line / heights (eq. 7).
  const uint32_t n = f.layerCount;
  lv.layers.assign(n, LayerInfo{});
  for (uint32_t i = 0; i < n; ++i) {
    lv.layers[i].slab = slabs[i];
    lv.layers[i].top = INFINITY;
  }
  std::vector<uint8_t> leafLayer(nLeaves);
  for (uint32_t i = 0; i < nLeaves; ++i) {
    leafLayer[i] = uint8_t(gpu::layerOfDepth(f, leafDepth[i]));
    lv.layers[leafLayer[i]].leaves++;
  }
  const glm::vec4 rowY(f.viewProj[0][1], f.viewProj[1][1], f.viewProj[2][1], f.viewProj[3][1]);
  const glm::vec4 rowW(f.viewProj[0][3], f.viewProj[1][3], f.viewProj[2][3], f.viewProj[3][3]);
  const float h = float(lv.desc.height);
  float bottom = -INFINITY;
  for (size_t v = 0; v < lv.positions.size(); ++v) {
    const glm::vec4 p(lv.positions[v], 1.0f);
    const float w = glm::dot(rowW, p);
    if (w <= 1e-6f) continue;
    const float y = (glm::dot(rowY, p) / w * 0.5f + 0.5f) * h;
    bottom = std::max(bottom, y);
    const uint32_t leaf = lv.leafOfVertex[v];
    if (leaf == kNoLeaf) continue;
    const uint32_t layer = geometric ? gpu::layerOfDepth(f, depthOf(lv.positions[v])) : leafLayer[leaf];
    lv.layers[layer].top = std::min(lv.layers[layer].top, y);
  }
  for (const LayerDraw& dr : lv.foliageDraws)
    for (uint32_t k = dr.firstIndex; k < dr.firstIndex + dr.indexCount; k += 3) {
      const uint32_t v = lv.indices[k];
      const uint32_t layer = geometric ? gpu::layerOfDepth(f, depthOf(lv.positions[v])) : leafLayer[lv.leafOfVertex[v]];
      lv.layers[layer].triangles++;
    }
  if (!std::isfinite(bottom)) bottom = h;
  for (LayerInfo& li : lv.layers) {
    li.rootLineY = bottom;
    if (!std::isfinite(li.top)) li.top = bottom;
    li.height = std::max(bottom - li.top, 1.0f);
  }
  lv.stats.lastPlacementMs = msSince(t0);
  return Status();
}

// Binds the mesh and draws its foliage or rigid chunks with `pipe`; the push constants say how the
// vertex shader routes triangles (passKind, targetLayer).
Status drawMaterials(LayeredVegetation& lv, VkCommandBuffer cmd, const GraphicsPipeline& pipe, bool foliage,
                     uint32_t passKind, uint32_t target) {
  const Device& d = *lv.device;
  const VkDeviceSize zero = 0;
  d.vk.CmdBindVertexBuffers(cmd, 0, 1, &lv.vertices.buffer, &zero);
  d.vk.CmdBindIndexBuffer(cmd, lv.indexBuffer.buffer, 0, VK_INDEX_TYPE_UINT16);
  setViewportScissor(d, cmd, lv.desc.width, lv.desc.height);
  // One draw per mesh chunk: its bounds decode the quantised positions, its block of the root table
  // is bound at its own offset (render/mesh_chunks.h).
  for (const MeshChunk& c : lv.chunks) {
    if (c.foliage != foliage) continue;
    const ModelMaterial& mat = lv.materials[c.material];
    const Image& tex = mat.baseColorImage >= 0 ? lv.textures[size_t(mat.baseColorImage)] : lv.textures.back();
    gpu::LayerDrawPush push{};
    push.baseColor = mat.baseColorFactor;
    push.chunkOrigin = glm::vec4(c.origin, 0.0f);
    push.chunkScale = glm::vec4(c.scale, 0.0f);
    push.alphaCutoff = mat.alphaCutoff;
    push.alphaMode = uint32_t(mat.alphaMode);
    push.targetLayer = target;
    push.passKind = passKind;
    push.triangleBase = uint32_t(c.firstTriangle);
    const VkDeviceSize rootBytes = std::max<VkDeviceSize>(c.rootCount, 1) * sizeof(gpu::LayerLeafRoot);
    CANOPY_TRY(bindGraphics(*lv.device, cmd, pipe,
                            {bindBuffer(lv.frameBuffer.buffer),
                             bindBuffer(lv.leafRoots.buffer, c.firstRoot * sizeof(gpu::LayerLeafRoot), rootBytes),
                             bindImage(tex.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, lv.sampler)},
                            push));
    d.vk.CmdDrawIndexed(cmd, c.triangleCount * 3, 1, uint32_t(c.firstIndex), int32_t(c.firstVertex), 0);
  }
  return Status();
}

VkRenderingAttachmentInfo clearedAttachment(VkImageView view, bool depth) {
  VkRenderingAttachmentInfo a{VK_STRUCTURE_TYPE_RENDERING_ATTACHMENT_INFO};
  a.imageView = view;
  a.imageLayout = depth ? VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL : VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL;
  a.loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
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

Status recordFoliage(LayeredVegetation& lv, VkCommandBuffer cmd) {
  const uint32_t n = lv.settings.layout.count();
  const uint32_t passes = lv.singlePass ? 1 : n;
  for (uint32_t i = 0; i < passes; ++i) {
    const VkRenderingAttachmentInfo colors[2] = {
        clearedAttachment(lv.singlePass ? lv.color.view : lv.colorLayerViews[i], false),
        clearedAttachment(lv.desc.writeIds ? (lv.singlePass ? lv.ids.view : lv.idsLayerViews[i]) : VK_NULL_HANDLE, false)};
    const VkRenderingAttachmentInfo depth = clearedAttachment(lv.singlePass ? lv.depth.view : lv.depthLayerViews[i], true);
    CANOPY_TRY(renderInto(*lv.device, cmd, lv, lv.singlePass ? n : 1, colors, lv.desc.writeIds ? 2 : 1, depth, [&] {
      return lv.singlePass ? drawMaterials(lv, cmd, lv.layered, true, LAYER_PASS_LAYERED, 0)
                           : drawMaterials(lv, cmd, lv.perLayer, true, LAYER_PASS_ONE_LAYER, i);
    }));
  }
  return Status();
}

Status recordBackground(LayeredVegetation& lv, VkCommandBuffer cmd) {
  const VkRenderingAttachmentInfo color = clearedAttachment(lv.backgroundColor.view, false);
  const VkRenderingAttachmentInfo depth = clearedAttachment(lv.backgroundDepth.view, true);
  return renderInto(*lv.device, cmd, lv, 1, &color, 1, depth, [&] {
    return drawMaterials(lv, cmd, lv.background, false, LAYER_PASS_BACKGROUND, 0);
  });
}

}  // namespace

bool operator==(const LayerSettings& a, const LayerSettings& b) {
  return a.layout == b.layout && a.regions == b.regions && a.slice == b.slice && a.draw == b.draw && a.policy == b.policy &&
         a.moveThreshold == b.moveThreshold && a.turnThresholdDegrees == b.turnThresholdDegrees &&
         a.lightDirection == b.lightDirection && a.lightColor == b.lightColor && a.ambient == b.ambient;
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
  if (!(s.ambient >= 0 && s.ambient <= 1))
    return Status::error("layer settings: ambient " + std::to_string(s.ambient) + " is outside [0, 1]");
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(toGlm(s.lightDirection)[i])) return Status::error("layer settings: lightDirection must be finite");
    if (!(toGlm(s.lightColor)[i] >= 0 && toGlm(s.lightColor)[i] <= 1000))
      return Status::error("layer settings: lightColor[" + std::to_string(i) + "] = " + std::to_string(toGlm(s.lightColor)[i]) +
                           " is outside [0, 1000]");
  }
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
        Status w = writeLeafRootCache(cachePath, key, roots);
        lv.stats.rootCacheNote += w.ok() ? "; wrote it" : "; not written: " + w.message();
      }
    }
    lv.stats.rootCacheHit = cached;
    lv.stats.leafCount = roots.leafCount();
    lv.stats.preprocessMs = msSince(t0);
    lv.materials = m.materials;
    lv.boundsMin = m.boundsMin;
    lv.boundsMax = m.boundsMax;
    lv.positions = m.positions;
    lv.leafOfVertex = roots.leafOfVertex;
    lv.leafRootPosition.resize(roots.leafCount());
    for (uint32_t l = 0; l < roots.leafCount(); ++l) lv.leafRootPosition[l] = m.positions[roots.leafRoot[l]];
    CANOPY_TRY(chooseDrawPath(lv, lv.settings, &lv.singlePass));
    CANOPY_TRY(uploadMesh(lv, m, foliage, roots));
    CANOPY_TRY(createTargets(lv));
    CANOPY_TRY(createPipelines(lv));
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
  for (GraphicsPipeline* p : {&lv.layered, &lv.perLayer, &lv.background}) destroyGraphicsPipeline(d, *p);
  for (Image& t : lv.textures) destroyImage(d, t);
  if (lv.sampler) d.vk.DestroySampler(d.device, lv.sampler, d.allocationCallbacks);
  for (Buffer* b : {&lv.vertices, &lv.indexBuffer, &lv.leafRoots, &lv.frameBuffer}) destroyBuffer(d, *b);
  lv = LayeredVegetation{};
}

Status setLayerSettings(LayeredVegetation& lv, const LayerSettings& s) {
  CANOPY_TRY(validateLayerSettings(s));
  bool single = false;
  CANOPY_TRY(chooseDrawPath(lv, s, &single));
  const bool recreate = s.layout.count() != lv.settings.layout.count();
  lv.settings = s;
  lv.singlePass = single;
  lv.stats.singlePass = single;
  lv.settingsChanged = true;
  if (recreate) {
    destroyTargets(lv);
    CANOPY_TRY(createTargets(lv));
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
  return createTargets(lv);
}

Status updateLayerView(LayeredVegetation& lv, const LayerView& view, bool* rebuild) {
  lv.stats.viewUpdates++;
  std::string reason;
  const LayerSettings& s = lv.settings;
  if (!lv.haveView) {
    reason = "first view";
  } else if (!lv.forcedReason.empty()) {
    reason = lv.forcedReason;
  } else if (lv.settingsChanged) {
    reason = "settings changed";
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
  lv.rebuildPending = !reason.empty();
  *rebuild = lv.rebuildPending;
  if (!lv.rebuildPending) return Status();
  CANOPY_TRY(placeForView(lv, view));
  lv.haveView = true;
  lv.settingsChanged = false;
  lv.forcedReason.clear();
  lv.lastRebuildView = view;
  lv.stats.rebuilds++;
  lv.stats.lastRebuildReason = reason;
  return Status();
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
  const rg::State vb = rg::stateOf(rg::Use::VertexBuffer), ib = rg::stateOf(rg::Use::IndexBuffer),
                  roots = rg::stateOf(rg::Use::VertexStorageRead);
  const auto vertices = g.importBuffer("layers: vertices", lv.vertices.size, vb, vb);
  const auto indices = g.importBuffer("layers: indices", lv.indexBuffer.size, ib, ib);
  const auto leafRoots = g.importBuffer("layers: leaf roots", lv.leafRoots.size, roots, roots);
  const auto frame = g.importBuffer("layers: frame", lv.frameBuffer.size, kFrameRead, kFrameRead);
  LayeredVegetation* p = &lv;
  g.addPass("layers: frame constants", [p](rg::PassContext& c) {
     if (p->rebuildPending) c.device->vk.CmdUpdateBuffer(c.cmd, p->frameBuffer.buffer, 0, sizeof(gpu::LayerFrame), &p->frame);
     return Status();
   }).write(frame, rg::Use::TransferDst);
  auto foliage = g.addPass("layers: foliage", [p](rg::PassContext& c) {
                    return p->rebuildPending ? recordFoliage(*p, c.cmd) : Status();
                  });
  foliage.access(frame, kFrameRead)
      .read(vertices, rg::Use::VertexBuffer)
      .read(indices, rg::Use::IndexBuffer)
      .read(leafRoots, rg::Use::VertexStorageRead)
      .write(r.color, rg::Use::ColorAttachmentWrite)
      .write(r.depth, rg::Use::DepthAttachmentWrite);
  if (lv.desc.writeIds) foliage.write(r.ids, rg::Use::ColorAttachmentWrite);
  g.addPass("layers: background", [p](rg::PassContext& c) {
     return p->rebuildPending && !p->rigidDraws.empty() ? recordBackground(*p, c.cmd) : Status();
   })
      .access(frame, kFrameRead)
      .read(vertices, rg::Use::VertexBuffer)
      .read(indices, rg::Use::IndexBuffer)
      .read(leafRoots, rg::Use::VertexStorageRead)
      .write(r.backgroundColor, rg::Use::ColorAttachmentWrite)
      .write(r.backgroundDepth, rg::Use::DepthAttachmentWrite);
  CANOPY_TRY(g.bindImage(r.color, lv.color));
  CANOPY_TRY(g.bindImage(r.depth, lv.depth));
  if (lv.desc.writeIds) CANOPY_TRY(g.bindImage(r.ids, lv.ids));
  CANOPY_TRY(g.bindImage(r.backgroundColor, lv.backgroundColor));
  CANOPY_TRY(g.bindImage(r.backgroundDepth, lv.backgroundDepth));
  CANOPY_TRY(g.bindBuffer(vertices, lv.vertices.buffer));
  CANOPY_TRY(g.bindBuffer(indices, lv.indexBuffer.buffer));
  CANOPY_TRY(g.bindBuffer(leafRoots, lv.leafRoots.buffer));
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
