#include "render/layer_mesh.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "engine/device.h"
#include "engine/transfer.h"
#include "render/layer_common.h"
#include "render/leaf_attach.h"
#include "render/plant_sway.h"
#include "render/rigid_refine.h"
#include "render/rigid_flex.h"
#include <glm/gtc/packing.hpp>

namespace canopy {

static_assert(offsetof(gpu::LayerVertex, positionXY) == 0 && offsetof(gpu::LayerVertex, normal) == 8 &&
                  offsetof(gpu::LayerVertex, uv) == 12,
              "LayerVertex offsets differ from the attributes the pipelines declare");
static_assert(offsetof(gpu::LayerInstance, model) == 0 && offsetof(gpu::LayerInstance, normalColumn0) == 64 &&
                  offsetof(gpu::LayerInstance, tint) == 112,
              "LayerInstance offsets differ from the instance attributes the pipelines declare");

GraphicsPipelineDesc layerMeshPipelineDesc(VkFormat colorFormat, VkFormat depthFormat) {
  GraphicsPipelineDesc p;
  p.pushConstantSize = sizeof(gpu::LayerDrawPush);
  p.vertexStride = sizeof(gpu::LayerVertex);
  p.attributes = {{0, VK_FORMAT_R16G16B16A16_UINT, 0},  // quantised position, chunk-local leaf
                  {1, VK_FORMAT_R16G16_SNORM, 8},        // octahedral normal
                  {2, VK_FORMAT_R16G16_SFLOAT, 12}};     // texcoord 0
  // The instance table (gpu::LayerInstance) as the per-instance stream: the model matrix's columns,
  // the normal matrix's, the tint (shaders/layers_common.glsl LAYER_INSTANCE_LOCATION).
  p.instanceStride = sizeof(gpu::LayerInstance);
  for (uint32_t i = 0; i < 8; ++i) p.instanceAttributes.push_back({LAYER_INSTANCE_LOCATION + i, VK_FORMAT_R32G32B32A32_SFLOAT, 16 * i});
  p.colorFormats = {colorFormat};
  p.depthFormat = depthFormat;
  p.blend = BlendMode::PremultipliedOver;
  p.fragmentShader = "layers.frag";
  return p;
}


namespace {

// The smallest Beckmann sigma a file's roughness gives the lobe: below it the highlight is a
// point the layers' texels cannot hold (Habel's measured range starts at 0.078).
constexpr float kMinLeafSigma = 0.05f;

// The GPU triangle order and the compact chunked mesh, in host memory.
struct MeshBuild {
  Device& d;
  const LayerMeshDesc& desc;
  LayerMesh& mesh;
  Impostors& impostors;
  LayerStats& stats;
};

Status buildMesh(const MeshBuild& b, const VegetationModel& m, const SpeciesParts& parts, CompactMesh* mesh) {
  const std::vector<uint8_t>& foliage = parts.foliage;
  const LeafRoots& roots = parts.roots;
  Device& d = b.d;
  const size_t nt = m.triangleCount();
  // GPU triangle order: foliage grouped by material, then rigid by material (one draw each): first
  // the rigid triangles whose corners all follow the foliage fully (carried into the layers with
  // it, MeshChunk::carried), then the others (drawn every frame or into the background).
  const size_t nm = m.materials.size();
  const std::vector<gpu::LayerLeafRoot>& anchors = parts.rigidAnchors;
  auto classOf = [&](size_t t) -> size_t {
    if (foliage[t]) return 0;
    if (anchors.size() != m.positions.size()) return 2;
    for (int k = 0; k < 3; ++k)
      if (anchors[m.indices[3 * t + size_t(k)]].leaf != LAYER_RIGID_FULL) return 2;
    return 1;
  };
  std::vector<uint64_t> start(3 * nm + 1, 0);
  for (size_t t = 0; t < nt; ++t) start[classOf(t) * nm + m.triangleMaterial[t] + 1]++;
  for (size_t k = 1; k < start.size(); ++k) start[k] += start[k - 1];
  // The GPU order as a permutation of the model's triangles (4 bytes a face, not a copy of the
  // indices); the id output keeps it, since its triangle ids are in GPU order.
  std::vector<uint32_t> order(nt);
  std::vector<uint64_t> cursor(start.begin(), start.end() - 1);
  for (size_t t = 0; t < nt; ++t) order[cursor[classOf(t) * nm + m.triangleMaterial[t]]++] = uint32_t(t);
  // With impostors the foliage of each material is laid out box by box, depth first
  // (render/impostors.h), so a box's subtree is one run per material.
  if (b.desc.impostors.enable) {
    CANOPY_TRY(buildImpostorOrder(m, parts.boxes, parts.speciesBoxes, roots, start, &b.impostors, &order));
    CANOPY_TRY(planImpostorAtlas(b.desc.impostors, d.properties.limits.maxImageDimension2D,
                                 d.properties.limits.maxImageArrayLayers, &b.impostors));
  }
  // The compact chunked mesh (render/mesh_chunks.h): 16-byte vertices, 16-bit indices and a
  // leaf-root table per chunk, so no buffer is indexed past the device's storage range; one
  // triangle range per (foliage or rigid, material) run of the GPU order.
  std::vector<TriangleRange> ranges;
  for (size_t k = 0; k < 3 * nm; ++k)
    if (start[k + 1] > start[k]) ranges.push_back({uint32_t(k % nm), k < nm, start[k], start[k + 1] - start[k], k >= nm && k < 2 * nm});
  b.mesh.hasRigid = start[3 * nm] > start[nm];
  CompactMeshOptions co;
  co.maxChunkVertices = b.desc.maxChunkVertices;
  co.bend = b.desc.keepBend && !m.bend.empty();
  co.rigidAnchors = &parts.rigidAnchors;
  co.leafRootPositions = &parts.layerRoots;
  const VkDeviceSize align = std::max<VkDeviceSize>(d.properties.limits.minStorageBufferOffsetAlignment, 1);
  co.rootAlignment = uint32_t((align + sizeof(gpu::LayerLeafRoot) - 1) / sizeof(gpu::LayerLeafRoot));
  if (align % sizeof(gpu::LayerLeafRoot) && sizeof(gpu::LayerLeafRoot) % align)
    return Status::error("layers: minStorageBufferOffsetAlignment " + std::to_string(align) + " is not a power of two");
  b.mesh.ring.rootAlignment = co.rootAlignment;
  CANOPY_TRY(buildCompactMesh(m, order, ranges, roots, co, mesh, b.desc.progress));
  if (b.desc.writeIds) b.mesh.gpuToModelTriangle = std::move(order);
  b.stats.meshChunks = uint32_t(mesh->chunks.size());
  b.stats.meshBytes = mesh->bytes();
  b.mesh.chunks = std::move(mesh->chunks);  // the one chunk list (the host mesh keeps none)
  return Status();
}

// The material textures and their sampler.
Status uploadTextures(Device& d, LayerMesh& mesh, const VegetationModel& m) {
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
    mesh.textures.push_back(img);
    CANOPY_TRY(uploadImage(d, &mesh.pendingUploads, img, isWhite ? white : m.images[i].rgba.data(),
                           isWhite ? 4 : m.images[i].rgba.size(), sampled));
  }
  VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  si.magFilter = si.minFilter = VK_FILTER_LINEAR;
  si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_REPEAT;
  si.maxLod = 0.0f;
  CANOPY_VK(d.vk.CreateSampler(d.device, &si, d.allocationCallbacks, &mesh.sampler));
  return Status();
}


}  // namespace


// Where the compact mesh lives (docs/design.md "Layers: mesh budget and staging ring"): resident
// when it fits the budget beside everything else this object allocates, with room for the second
// layer set (a spread re-slice needs it, and settings may ask for it later); else in host memory,
// streamed through rings sized from desc.stagingRingBytes, which needs the second set now. Called
// after the textures, frame block and targets, so the bytes are the allocator's, not estimates.
Status chooseLayerMeshResidency(const Device& d, const LayerMeshDesc& desc, LayerMesh& mesh, uint64_t liveAtStart,
                                uint64_t meshBytes, uint64_t nextSet) {
  const uint64_t budget = desc.deviceMemoryBudget;
  mesh.streamed = false;
  if (budget == 0) return Status();
  const uint64_t used = d.allocator->liveBytes - liveAtStart;
  if (used + nextSet + meshBytes + 3 * 256 <= budget) return Status();
  if (desc.keepBend)
    return Status::error("layers: the per-vertex wind baseline (CanopyDesc.allowPerVertex) draws the whole mesh every "
                         "frame and needs it resident: the compact mesh with its branch hierarchy (" + mib(meshBytes) +
                         ") with the layer images and textures (" + mib(used + nextSet) + ") is over deviceMemoryBudget " +
                         mib(budget) + "; raise it (or 0: no limit)");
  if (desc.writeIds)
    return Status::error("layers: the id output draws the mesh at once and needs it resident: the compact mesh (" +
                         mib(meshBytes) + ") with the layer images and textures (" + mib(used + nextSet) +
                         ") is over deviceMemoryBudget " + mib(budget));
  mesh.streamed = true;
  return Status();
}

// Creates the resident buffers and fills them, or the staging rings; the mesh stays in lm.hostMesh.
Status placeLayerMesh(Device& d, const LayerMeshDesc& desc, LayerMesh& lm, LayerStats& stats, CompactMesh&& compact,
                      uint64_t liveAtStart) {
  lm.hostMesh = std::move(compact);
  const CompactMesh& mesh = lm.hostMesh;
  const uint64_t budget = desc.deviceMemoryBudget;
  if (lm.streamed) {
    // Per segment each ring holds at least the largest chunk (its vertices, its root block, and
    // 1024 of its triangles), so every frame's slice makes progress; the rest of the ring's bytes
    // are shared in the proportions of the whole mesh.
    MeshRing& r = lm.ring;
    r.segments = std::max<uint32_t>(d.framesInFlight, 1);
    uint64_t minV = 0, minR = 0, minI = 3;
    for (const MeshChunk& c : lm.chunks) {
      minV = std::max<uint64_t>(minV, c.vertexCount);
      minR = std::max<uint64_t>(minR, roundUp(std::max<uint32_t>(c.tableEntries(), 1), r.rootAlignment));
      minI = std::max<uint64_t>(minI, 3ull * std::min<uint32_t>(c.triangleCount, 1024));
    }
    const uint64_t vb = mesh.vertices.size() * sizeof(gpu::LayerVertex), ib = mesh.indices.size() * 2,
                   rb = mesh.roots.size() * sizeof(gpu::LayerLeafRoot);
    const uint64_t total = std::max<uint64_t>(vb + ib + rb, 1);
    const double share = double(desc.stagingRingBytes) / double(r.segments) / double(total);
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
                           mib(desc.stagingRingBytes) + "); raise the budget");
    CANOPY_TRY(createBuffer(d, r.segments * r.vertexCapacity * sizeof(gpu::LayerVertex), VK_BUFFER_USAGE_VERTEX_BUFFER_BIT,
                            MemoryUsage::Upload, &lm.vertices, "layers: vertex ring"));
    CANOPY_TRY(createBuffer(d, r.segments * roundUp(r.indexCapacity * 2, 4), VK_BUFFER_USAGE_INDEX_BUFFER_BIT,
                            MemoryUsage::Upload, &lm.indexBuffer, "layers: index ring"));
    CANOPY_TRY(createBuffer(d, r.segments * r.rootCapacity * sizeof(gpu::LayerLeafRoot), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                            MemoryUsage::Upload, &lm.leafRoots, "layers: leaf-root ring"));
    for (const Buffer* b : {&lm.vertices, &lm.indexBuffer, &lm.leafRoots})
      if (!hostCoherentPointer(d, b->allocation))
        return Status::error("layers: the staging ring's memory is not host-visible and coherent");
    stats.meshResident = false;
    stats.meshRingBytes = r.bytes;
    return Status();
  }
  stats.meshResident = true;
  stats.meshRingBytes = 0;
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
    return uploadBuffer(d, &lm.pendingUploads, buf, data, bytes, rg::stateOf(use));
  };
  CANOPY_TRY(upload(lm.vertices, mesh.vertices.data(), mesh.vertices.size() * sizeof(gpu::LayerVertex),
                    VK_BUFFER_USAGE_VERTEX_BUFFER_BIT, rg::Use::VertexBuffer, "layers: vertices"));
  CANOPY_TRY(upload(lm.indexBuffer, mesh.indices.data(), mesh.indices.size() * 2, VK_BUFFER_USAGE_INDEX_BUFFER_BIT,
                    rg::Use::IndexBuffer, "layers: indices"));
  if (!mesh.bend.empty())
    CANOPY_TRY(upload(lm.bendVertices, mesh.bend.data(), mesh.bend.size() * sizeof(gpu::BendVertex),
                      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, rg::Use::VertexStorageRead, "per-vertex: branch and w per vertex"));
  return upload(lm.leafRoots, mesh.roots.data(), mesh.roots.size() * sizeof(gpu::LayerLeafRoot),
                VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, rg::Use::VertexStorageRead, "layers: leaf roots");
}


namespace {
// One species' material split, leaf roots (read from or written to its cache file) and plants;
// *rootKey: its cache key (0: no cache); `note`: what the cache did.
Status prepareSpecies(const LayerMeshDesc& desc, const VegetationModel& m, SpeciesParts& p, uint64_t* rootKey, bool* cached,
                      std::string* note) {
  *rootKey = 0;
  *cached = false;
  CANOPY_TRY(splitMaterials(m, desc.split, &p.split));
  p.foliage = std::move(p.split.triangleFoliage);  // the materials' roles, and the parts' (render/part_split.h)
  const bool cacheOn = !desc.rootCacheDir.empty() && !m.path.empty();
  const std::string cachePath = cacheOn ? leafRootCachePath(m.path, desc.rootCacheDir) : std::string();
  if (cacheOn) {
    *rootKey = leafRootKey(m, p.foliage, desc.roots);
    std::string why;
    *cached = readLeafRootCache(cachePath, *rootKey, m.positions.size(), &p.roots, &why);
    *note = *cached ? "read " + cachePath : cachePath + ": " + why;
  } else {
    *note = "cache off";
  }
  if (!*cached) {
    CANOPY_TRY(computeLeafRoots(m, p.foliage, desc.roots, &p.roots, desc.progress));
    if (cacheOn) {
      std::string evicted;
      Status w = writeLeafRootCache(cachePath, *rootKey, p.roots, desc.cacheMaxBytes, &evicted);
      *note += w.ok() ? "; wrote it" : "; not written: " + w.message();
      if (!evicted.empty()) *note += "; " + evicted;
    }
  }
  // Only the per-vertex leaf and the per-leaf root are used from here on, by the compaction; the
  // per-vertex root goes now and the rest after it (the placement reads the compact mesh).
  std::vector<uint32_t>().swap(p.roots.rootOfVertex);
  if (desc.impostors.enable) CANOPY_TRY(buildFoliageBoxes(m, p.foliage, p.roots, desc.impostors, &p.boxes));
  std::vector<uint32_t> trianglePlant;
  CANOPY_TRY(findPlants(m, p.roots, &p.plants, &trianglePlant, p.foliage));
  // Each plant's sway scale from its levers (render/plant_sway.h).
  CANOPY_TRY(plantSwayScales(m, p.foliage, p.roots, trianglePlant, &p.plants));
  // How far each rigid vertex follows the foliage (docs/design.md "Rigid parts in wind").
  if (!p.split.rigidTriangles) return Status();
  CANOPY_TRY(rigidAnchors(m, p.foliage, p.roots, trianglePlant, &p.rigidAnchors));
  // Each leaf layered where it grows from its branch (render/leaf_attach.h), as that branch is.
  return leafLayerRoots(m, p.foliage, p.roots, &p.layerRoots, &p.rigidAnchors);
}
}  // namespace

Status prepareLayerMesh(Device& d, const LayerMeshDesc& desc, const VegetationModel& m, LayerMesh& mesh, Impostors& impostors,
                        LayerStats& stats, CompactMesh* out, uint64_t* rootKey) {
  return prepareLayerMesh(d, desc, std::vector<SpeciesModel>{SpeciesModel{&m}}, mesh, impostors, stats, out, rootKey);
}

Status prepareLayerMesh(Device& d, const LayerMeshDesc& desc, const std::vector<SpeciesModel>& given, LayerMesh& mesh,
                        Impostors& impostors, LayerStats& stats, CompactMesh* out, uint64_t* rootKey) {
  *rootKey = 0;
  CANOPY_TRY(checkSpecies(given));
  const auto t0 = std::chrono::steady_clock::now();
  // A species whose rigid parts have edges too long to follow the displacement between their
  // vertices is refined first (render/rigid_refine.h); the others are used as given.
  std::vector<SpeciesModel> species = given;
  std::vector<VegetationModel> refined(given.size());
  for (size_t s = 0; s < given.size(); ++s) {
    MaterialSplit split;
    CANOPY_TRY(splitMaterials(*given[s].model, desc.split, &split));
    if (!needsRigidRefinement(*given[s].model, split.triangleFoliage)) continue;
    CANOPY_TRY(refineRigidParts(*given[s].model, &split.triangleFoliage, &refined[s]));
    species[s].model = &refined[s];
  }
  // Each species on its own (its split rule reads its own materials, its leaf roots have its own
  // cache file), then laid end to end (render/species.h).
  std::vector<SpeciesParts> parts(species.size());
  stats.rootCacheHit = true;
  stats.rootCacheNote.clear();
  for (size_t s = 0; s < species.size(); ++s) {
    uint64_t key = 0;
    bool cached = false;
    std::string note;
    CANOPY_TRY(prepareSpecies(desc, *species[s].model, parts[s], &key, &cached, &note));
    if (s == 0) *rootKey = key;  // the impostor views' cache key (cached for one species only)
    stats.rootCacheHit = stats.rootCacheHit && cached;
    stats.rootCacheNote += (s ? "; " : "") + note;
  }
  VegetationModel merged;
  SpeciesParts all;
  CANOPY_TRY(mergeSpecies(species, parts, &merged, &all, &mesh.species));
  // The per-vertex baseline's hierarchy: each species' own, or its own fallback trunk.
  if (desc.keepBend && species.size() > 1) CANOPY_TRY(mergeBendHierarchies(species, &merged));
  const VegetationModel& m = species.size() == 1 ? *species[0].model : merged;
  if (desc.keepBend) mesh.branches = m.branches;
  mesh.split = std::move(all.split);
  mesh.plants = std::move(all.plants);
  LeafRoots& roots = all.roots;
  stats.foliageTriangles = mesh.split.foliageTriangles;
  stats.rigidTriangles = mesh.split.rigidTriangles;
  stats.leafCount = roots.leafCount();
  stats.plants = mesh.plants.count();
  stats.species = uint32_t(species.size());
  stats.preprocessMs = msSince(t0);
  mesh.materials = m.materials;
  mesh.boundsMin = m.boundsMin;
  mesh.boundsMax = m.boundsMax;
  mesh.leafCount = roots.leafCount();
  if (desc.keepBend) {
    mesh.leafRootPositions.resize(roots.leafCount());
    for (uint32_t l = 0; l < roots.leafCount(); ++l) mesh.leafRootPositions[l] = glm::vec4(m.positions[roots.leafRoot[l]], 1.0f);
  }
  CANOPY_TRY(buildMesh(MeshBuild{d, desc, mesh, impostors, stats}, m, all, out));
  all.boxes = BoxHierarchy{};
  // A chunk holds one material, and materials are numbered species after species.
  const std::vector<uint32_t> speciesOf = materialSpecies(mesh.species);
  for (MeshChunk& c : mesh.chunks) c.species = speciesOf[c.material];
  roots = LeafRoots{};
  CANOPY_TRY(uploadTextures(d, mesh, m));
  return Status();
}

void releaseLeafRootPositions(LayerMesh& mesh) {
  std::vector<glm::vec4>().swap(mesh.leafRootPositions);
  std::vector<gpu::BendBranch>().swap(mesh.branches);
}

void destroyLayerMesh(Device& d, LayerMesh& mesh) {
  dropPreparedWork(d, mesh.pendingUploads);  // uploads never recorded: nothing waits for them
  for (Image& t : mesh.textures) destroyImage(d, t);
  if (mesh.sampler) d.vk.DestroySampler(d.device, mesh.sampler, d.allocationCallbacks);
  for (Buffer* b : {&mesh.vertices, &mesh.indexBuffer, &mesh.leafRoots, &mesh.bendVertices}) destroyBuffer(d, *b);
  mesh = LayerMesh{};
}

// Binds the mesh and draws its foliage or rigid chunks with `pipe` (`parts`: only those parts of
// chunks; null: every chunk whole); the push constants say how the vertex shader routes triangles
// (passKind, targetLayer). `perVertex`: the per-vertex baseline's own frame block in place of the
// layers' and its bend buffers after the layers' own (shaders/per_vertex_common.glsl).
Status drawMaterials(const MeshDraw& md, VkCommandBuffer cmd, const GraphicsPipeline& pipe, bool foliage,
                     uint32_t passKind, uint32_t target, const std::vector<ChunkPart>* parts,
                     const PerVertexBindings* perVertex, const MeshDrawOptions* options) {
  const Device& d = *md.device;
  const LayerMesh& mesh = *md.mesh;
  const MeshDrawOptions plain;
  const MeshDrawOptions& o = options ? *options : plain;
  const VkBuffer streams[2] = {mesh.vertices.buffer, md.instances};
  const VkDeviceSize offsets[2] = {0, 0};
  d.vk.CmdBindVertexBuffers(cmd, 0, 2, streams, offsets);
  d.vk.CmdBindIndexBuffer(cmd, mesh.indexBuffer.buffer, 0, VK_INDEX_TYPE_UINT16);
  std::vector<InstanceRun> speciesRuns;
  if (!o.keepViewport) setViewportScissor(d, cmd, md.width, md.height);
  // One draw per mesh chunk: its bounds decode the quantised positions, its block of the root table
  // is bound at its own offset (render/mesh_chunks.h).
  auto draw = [&](const MeshChunk& c, const ChunkPart* part, uint32_t first, uint32_t count) -> Status {
    // A chunk belongs to one species: only the runs of that species' copies (render/species.h).
    static const std::vector<InstanceRun> firstCopy = {{0, 1}};
    const std::vector<InstanceRun>* runs = o.runs ? o.runs : &firstCopy;
    if (part && part->copies.count) {
      speciesRuns.assign(1, part->copies);  // one copy's own cut (render/impostors.h)
      runs = &speciesRuns;
    } else if (md.speciesCopies && md.speciesCopies->size() > 1) {
      const InstanceRun own = (*md.speciesCopies)[c.species];
      if (o.runs) clipRuns(*o.runs, own, &speciesRuns);
      else speciesRuns.assign(own.count ? 1 : 0, InstanceRun{own.first, 1});
      runs = &speciesRuns;
    }
    if (runs->empty()) return Status();
    const ModelMaterial& mat = mesh.materials[c.material];
    if (o.subset != MeshDrawOptions::Subset::All) {
      const bool prepassed = mat.alphaMode != AlphaMode::Blend && (!part || part->weight >= 1.0f);
      if (prepassed != (o.subset == MeshDrawOptions::Subset::DepthPrepassed)) return Status();
    }
    auto textureOf = [&](int32_t image) -> const Image& { return image >= 0 ? mesh.textures[size_t(image)] : mesh.textures.back(); };
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
    push.specular = c.foliage ? std::clamp(mat.specularFactor, 0.0f, 1.0f) : 0.0f;
    const bool fileTransmission = mat.transmissionFactor >= 0.0f;
    push.transmission = !c.foliage ? glm::vec4(0.0f)
                        : fileTransmission ? glm::vec4(mat.transmissionColor, mat.transmissionFactor)
                                           : glm::vec4(1.0f, 1.0f, 1.0f, md.leafTransmission);
    push.shadingFlags = (c.foliage && !fileTransmission ? LAYER_SHADE_TINT_FROM_BASE : 0u) |
                        (mat.transmissionImage >= 0 ? LAYER_SHADE_TRANSMISSION_TEXTURE : 0u) |
                        (mat.transmissionColorImage >= 0 ? LAYER_SHADE_TRANSMISSION_COLOR_TEXTURE : 0u);
    push.normalScale = mat.normalImage >= 0 ? mat.normalScale : 0.0f;
    // Habel's translucency: optical depth through the leaf (KHR_materials_volume, else the setting).
    glm::vec3 tau(md.leafOpticalDepth);
    if (mat.thicknessFactor >= 0.0f) {
      tau = glm::vec3(0.0f);
      if (std::isfinite(mat.attenuationDistance) && mat.attenuationDistance > 0.0f)
        for (int k = 0; k < 3; ++k)
          tau[k] = mat.thicknessFactor * -std::log(std::max(mat.attenuationColor[k], 1e-6f)) / mat.attenuationDistance;
    }
    // The lobe's Beckmann sigma from the file's roughness (GGX's alpha = roughness^2, which a Beckmann
    // sigma matches closely), at least kMinLeafSigma; 0: the frame's (LayerSettings.leafRoughness).
    const float sigma = mat.roughness >= 0.0f && !md.overrideLeafRoughness ? std::max(mat.roughness * mat.roughness, kMinLeafSigma) : 0.0f;
    push.volume = glm::vec4(glm::min(tau, glm::vec3(100.0f)), sigma);
    push.passKind = passKind;
    push.lod = glm::vec4(part ? part->weight : 1.0f, o.debugLevels ? float((part ? part->level : 0u) + 1u) : 0.0f, 0.0f, 0.0f);
    push.triangleBase = uint32_t(c.firstTriangle);
    const VkDeviceSize rootBytes = std::max<VkDeviceSize>(c.tableEntries(), 1) * sizeof(gpu::LayerLeafRoot);
    // A streamed mesh's part sits in this frame's ring segment (planSlice copied it there).
    const bool ring = mesh.streamed;
    const uint64_t rootAt = ring ? part->ringRoot : c.firstRoot;
    const uint64_t indexAt = ring ? part->ringIndex : c.firstIndex + 3ull * first;
    const uint64_t vertexAt = ring ? part->ringVertex : c.firstVertex;
    const VkImageLayout ro = VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL;
    const Binding frame = o.frame ? bindBuffer(o.frame, o.frameOffset, sizeof(gpu::LayerFrame))
                                  : bindBuffer(perVertex ? perVertex->frame : md.frame);
    const Binding roots = bindBuffer(mesh.leafRoots.buffer, rootAt * sizeof(gpu::LayerLeafRoot), rootBytes);
    const Binding base = bindImage(tex.view, ro, mesh.sampler), normal = bindImage(textureOf(mat.normalImage).view, ro, mesh.sampler),
                  trans = bindImage(textureOf(mat.transmissionImage).view, ro, mesh.sampler),
                  transColor = bindImage(textureOf(mat.transmissionColorImage).view, ro, mesh.sampler);
    if (perVertex)
      CANOPY_TRY(bindGraphics(*md.device, cmd, pipe,
                              {frame, roots, base, normal, trans, transColor, bindBuffer(perVertex->bendFrame),
                               bindBuffer(perVertex->branches), bindBuffer(perVertex->bendVertices),
                               bindBuffer(perVertex->tips), bindBuffer(perVertex->trunks)},
                              push));
    else if (!o.extra.empty()) {
      std::vector<Binding> all = {frame, roots, base, normal, trans, transColor};
      all.insert(all.end(), o.extra.begin(), o.extra.end());
      CANOPY_TRY(bindGraphics(*md.device, cmd, pipe, all, &push, uint32_t(sizeof push)));
    } else
      CANOPY_TRY(bindGraphics(*md.device, cmd, pipe, {frame, roots, base, normal, trans, transColor}, push));
    // gl_PrimitiveID restarts at each draw: a part's ids would start at its first triangle, so the
    // id output (re-sliced at once) never draws parts. One instanced draw per run of visible copies
    // (gl_InstanceIndex, firstInstance included, indexes the instance table).
    for (const InstanceRun& r : *runs)
      d.vk.CmdDrawIndexed(cmd, count * 3, r.count, uint32_t(indexAt), int32_t(vertexAt), r.first);
    return Status();
  };
  if (parts) {
    for (const ChunkPart& p : *parts)
      if (drawnWithFoliage(mesh.chunks[p.chunk], o.carryWood) == foliage) CANOPY_TRY(draw(mesh.chunks[p.chunk], &p, p.firstTriangle, p.triangleCount));
    return Status();
  }
  if (mesh.streamed) return Status::error("layers: a streamed mesh is drawn in slices only");  // updateLayerView never asks
  for (const MeshChunk& c : mesh.chunks)
    if (drawnWithFoliage(c, o.carryWood) == foliage) CANOPY_TRY(draw(c, nullptr, 0, c.triangleCount));
  return Status();
}


Status drawMeshParts(const MeshDraw& draw, VkCommandBuffer cmd, const GraphicsPipeline& pipe, uint32_t passKind,
                     uint32_t target, const std::vector<ChunkPart>& parts, const MeshDrawOptions& options) {
  return drawMaterials(draw, cmd, pipe, true, passKind, target, &parts, nullptr, &options);
}

void appendRunParts(const std::vector<MeshChunk>& chunks, uint64_t first, uint64_t count, float weight, uint32_t level,
                    std::vector<ChunkPart>* out, InstanceRun copies) {
  // Chunks are in GPU triangle order and never span materials: find the one holding `first`.
  auto it = std::upper_bound(chunks.begin(), chunks.end(), first,
                             [](uint64_t t, const MeshChunk& c) { return t < c.firstTriangle; });
  if (it == chunks.begin()) return;
  for (size_t c = size_t(it - chunks.begin()) - 1; count > 0 && c < chunks.size(); ++c) {
    const MeshChunk& ch = chunks[c];
    const uint64_t local = first - ch.firstTriangle;
    if (local >= ch.triangleCount) continue;
    const uint64_t take = std::min<uint64_t>(count, ch.triangleCount - local);
    ChunkPart p;
    p.chunk = uint32_t(c);
    p.firstTriangle = uint32_t(local);
    p.triangleCount = uint32_t(take);
    p.weight = weight;
    p.level = level;
    p.copies = copies;
    out->push_back(p);
    first += take;
    count -= take;
  }
}


Status drawWholeMesh(const MeshDraw& draw, VkCommandBuffer cmd, const GraphicsPipeline& pipe,
                     const PerVertexBindings& bindings, const std::vector<InstanceRun>& runs) {
  // The host's targets, whose viewport beginHostRendering set (the layers' images are larger by
  // the guard band).
  MeshDrawOptions options;
  options.keepViewport = true;
  options.runs = &runs;
  CANOPY_TRY(drawMaterials(draw, cmd, pipe, true, LAYER_PASS_BACKGROUND, 0, nullptr, &bindings, &options));
  return draw.mesh->hasRigid ? drawMaterials(draw, cmd, pipe, false, LAYER_PASS_BACKGROUND, 0, nullptr, &bindings, &options) : Status();
}


Status importMesh(const LayerMesh& mesh, rg::RenderGraph& g, MeshResources* out) {
  const rg::State vb = rg::stateOf(rg::Use::VertexBuffer), ib = rg::stateOf(rg::Use::IndexBuffer),
                  roots = rg::stateOf(rg::Use::VertexStorageRead);
  out->vertices = g.importBuffer("layers: vertices", mesh.vertices.size, vb, vb);
  out->indices = g.importBuffer("layers: indices", mesh.indexBuffer.size, ib, ib);
  out->roots = g.importBuffer("layers: leaf roots", mesh.leafRoots.size, roots, roots);
  CANOPY_TRY(g.bindBuffer(out->vertices, mesh.vertices.buffer));
  CANOPY_TRY(g.bindBuffer(out->indices, mesh.indexBuffer.buffer));
  return g.bindBuffer(out->roots, mesh.leafRoots.buffer);
}

rg::RenderGraph::PassBuilder& readsMesh(rg::RenderGraph::PassBuilder& pass, const MeshResources& mesh) {
  return pass.read(mesh.vertices, rg::Use::VertexBuffer)
      .read(mesh.indices, rg::Use::IndexBuffer)
      .read(mesh.roots, rg::Use::VertexStorageRead);
}

}  // namespace canopy
