#include "render/layer_placement.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "engine/device.h"
#include "engine/transfer.h"
#include "render/layer_common.h"

namespace canopy {

// Starts the placement for `view`: the frame constants the layer draws read.
void beginPlacement(const PlacementInputs& in, const LayerView& view, PlacementJob& job) {
  job = PlacementJob{};
  job.view = view;
  const LayerSettings& s = *in.settings;
  gpu::LayerFrame& f = job.frame;
  f = cameraFrame(s, view);
  f.layerCount = s.layout.count();
  f.sliceMode = s.slice == SliceMode::Geometry ? LAYER_SLICE_GEOMETRY : LAYER_SLICE_LEAF_ROOT;
  job.zMin = INFINITY;
  job.zMax = -INFINITY;
  job.bottom = -INFINITY;
  // The copies this camera sees (docs/design.md "Instances"); per copy, the frame's rows composed
  // with its transform, so the stages below read model-space vertices.
  job.runs = visibleInstanceRuns(*in.instances, in.mesh->species, f.viewProj);
  const std::vector<MeshSpecies>& species = in.mesh->species;
  job.speciesVisible.assign(species.size(), InstanceRun{});
  job.leafBase.assign(1, 0);
  job.plantBase.assign(1, 0);
  for (const InstanceRun& r : job.runs)
    for (uint32_t i = r.first; i < r.first + r.count; ++i) {
      const uint32_t s = i < in.instances->species.size() ? in.instances->species[i] : 0u;
      InstanceRun& visible = job.speciesVisible[s];
      if (visible.count == 0) visible.first = uint32_t(job.copySpecies.size());
      visible.count++;
      job.copySpecies.push_back(s);
      job.leafBase.push_back(job.leafBase.back() + species[s].leafCount);
      job.plantBase.push_back(job.plantBase.back() + species[s].plantCount);
      const glm::mat4 m = in.instances->models[i], vp = f.viewProj * m;
      job.depthRows.push_back(glm::vec4(f.depthRow) * m);
      job.rowsX.push_back(glm::vec4(vp[0][0], vp[1][0], vp[2][0], vp[3][0]));
      job.rowsY.push_back(glm::vec4(vp[0][1], vp[1][1], vp[2][1], vp[3][1]));
      job.rowsW.push_back(glm::vec4(vp[0][3], vp[1][3], vp[2][3], vp[3][3]));
    }
  job.leafDepth.resize(job.leafBase.back());
}

namespace {
// Per-plant roots: each (visible copy, plant)'s bounding box projected (its x range and its lowest
// row: eq. 7's "bottom of the bounding box", per plant) and, per layer it has leaves in, its rect.
// A plant with a box corner behind the camera has no rect (its layers' corners take the nearest
// other plant's root).
void placePlants(PlacementJob& job, const Plants& plants, const std::vector<MeshSpecies>& species, float h, float w) {
  const uint32_t layers = job.frame.layerCount;
  for (size_t k = 0; k < job.rowsW.size(); ++k) {
    const MeshSpecies& sp = species[job.copySpecies[k]];
    for (uint32_t p = sp.firstPlant; p < sp.firstPlant + sp.plantCount; ++p) {
      const size_t slot = job.plantBase[k] + (p - sp.firstPlant);
      float xlo = INFINITY, xhi = -INFINITY, bottom = -INFINITY;
      bool behind = false;
      // The x range from the whole box; the root line from the foot's box: seen from above, a wide
      // crown's box corner in front of the trunk projects rows below the trunk's foot, and the
      // plant then leaned about a line under it, its foot sliding (issue 77).
      const bool hasFoot = p < plants.footMin.size();
      for (int c = 0; c < 16 && !behind; ++c) {
        const bool box = c < 8;
        const glm::vec3 lo = box || !hasFoot ? plants.boundsMin[p] : plants.footMin[p];
        const glm::vec3 hi = box || !hasFoot ? plants.boundsMax[p] : plants.footMax[p];
        const glm::vec4 q((c & 1) ? hi.x : lo.x, (c & 2) ? hi.y : lo.y, (c & 4) ? hi.z : lo.z, 1.0f);
        const float cw = glm::dot(job.rowsW[k], q);
        if (cw <= 1e-6f) {
          behind = true;
          break;
        }
        const float x = (glm::dot(job.rowsX[k], q) / cw * 0.5f + 0.5f) * w, y = (glm::dot(job.rowsY[k], q) / cw * 0.5f + 0.5f) * h;
        if (box) {
          xlo = std::min(xlo, x);
          xhi = std::max(xhi, x);
        }
        if (!box || !hasFoot) bottom = std::max(bottom, y);
      }
      if (behind) continue;
      bottom = std::min(bottom, 2.0f * h);  // as the layers' root line (finish)
      // Eq. 7's h: the box's vertical extent at its centre on screen (model y is up). A grass patch
      // seen from above spans its depth in rows, its blades a few: with the rect's rows the patch
      // leaned as a whole about its nearest row, a sawtooth from patch to patch that compressed
      // the layer (docs/lab/performance-notebook.md "The picture in wind").
      const glm::vec3 mid = 0.5f * (plants.boundsMin[p] + plants.boundsMax[p]);
      const glm::vec4 foot(mid.x, plants.boundsMin[p].y, mid.z, 1.0f), head(mid.x, plants.boundsMax[p].y, mid.z, 1.0f);
      const float fw = glm::dot(job.rowsW[k], foot), hw = glm::dot(job.rowsW[k], head);
      float upright = fw > 1e-6f && hw > 1e-6f
                          ? std::clamp((glm::dot(job.rowsY[k], foot) / fw - glm::dot(job.rowsY[k], head) / hw) * 0.5f * h, 0.0f, 2.0f * h)
                          : 0.0f;
      // Its top over every layer: a layer it has no leaves in still gets its rect when it has rigid
      // parts, which follow the layer of their own depth (docs/design.md "Rigid parts in wind").
      float topAll = INFINITY;
      for (uint32_t i = 0; i < layers; ++i) topAll = std::min(topAll, job.plantTop[slot * layers + i]);
      // Never taller than the plant stands above its root line on screen, so its top leaves reach
      // R = 1 (eq. 7): seen from above, the box's top at its centre lies above the crown's top as
      // seen, and the root line (its foot) below the box's centre's foot.
      if (std::isfinite(topAll) && upright > 0.0f) upright = std::max(std::min(upright, bottom - std::max(topAll, -h)), 1.0f);
      const bool wood = p < plants.rigid.size() && plants.rigid[p];
      for (uint32_t i = 0; i < layers; ++i) {
        float top = std::max(job.plantTop[slot * layers + i], -h);
        const bool woodOnly = !std::isfinite(top) && wood;
        if (woodOnly) top = std::max(topAll, -h);
        if (!std::isfinite(top)) continue;
        job.layers[i].plants.push_back(glm::vec4(xlo, xhi, std::min(top, bottom - 1.0f), bottom));
        job.layers[i].plantKeys.push_back(uint32_t(slot));
        job.layers[i].plantResponse.push_back(glm::vec3(sp.flexibility, sp.responseSpeed, p < plants.sway.size() ? plants.sway[p] : 1.0f));
        job.layers[i].plantHeight.push_back(upright);
        job.layers[i].plantDepth.push_back(std::max(glm::dot(job.depthRows[k], glm::vec4(mid, 1.0f)), 0.0f));
        job.layers[i].plantWoodOnly.push_back(woodOnly ? 1 : 0);
      }
    }
  }
}

// What every stage of one advancePlacement call reads: the mesh, the copies, the batch size, and
// the helpers that walk the compact host mesh as the vertex shader decodes it.
struct PlacementPass {
  const LayerMesh& mesh;
  PlacementJob& job;
  const LayerSettings& settings;
  gpu::LayerFrame& frame;
  const CompactMesh& hm;  // read chunk by chunk: foliage chunks first, vertices and indices contiguous
  const Plants& plants;
  const std::vector<MeshSpecies>& species;
  size_t copies, batch, nVertices, nChunks, foliageIndices = 0;
  bool geometric, perPlant;
  float height, width;

  PlacementPass(const PlacementInputs& in, PlacementJob& j)
      : mesh(*in.mesh), job(j), settings(*in.settings), frame(j.frame), hm(in.mesh->hostMesh), plants(in.mesh->plants),
        species(in.mesh->species) {
    copies = job.depthRows.size();
    // Items per clock reading, each item visited once per visible copy.
    batch = std::max<size_t>((size_t(1) << 14) / std::max<size_t>(copies, 1), 1);
    nVertices = hm.vertices.size();
    nChunks = mesh.chunks.size();
    geometric = settings.slice == SliceMode::Geometry;
    // Plant rects for every plant, a single one too: they carry per-plant roots (more than one
    // plant), a species' wind response, the plant's sway scale and, with the world wind, the depth
    // its layers read the field at (one gust a plant); the dynamics take what applies
    // (compute/dynamics.cpp makeAnimFrame).
    perPlant = plants.leafPlant.size() == mesh.leafCount;
    for (const MeshChunk& c : mesh.chunks)
      if (c.foliage) foliageIndices = std::max<size_t>(foliageIndices, c.firstIndex + 3ull * c.triangleCount);
    height = float(in.height);
    width = float(in.width);
  }
  // View depth of model-space point p in copy k.
  float depthOf(size_t k, const glm::vec3& p) const { return glm::dot(job.depthRows[k], glm::vec4(p, 1.0f)); }
  // The visible copies of chunk c's species ([first, first + count) of the rows).
  const InstanceRun& copiesOf(const MeshChunk& c) const { return job.speciesVisible[c.species]; }
  // Copy k's entry for (model-wide) leaf `leaf` of chunk c's species in leafDepth and leafLayer.
  size_t leafSlot(size_t k, const MeshChunk& c, uint32_t leaf) const { return job.leafBase[k] + (leaf - species[c.species].firstLeaf); }
  // The chunk holding vertex (or index) `item`, items visited in order.
  const MeshChunk& chunkOf(size_t item, bool index) {
    for (;; ++job.chunk) {
      const MeshChunk& c = mesh.chunks[job.chunk];
      if (job.chunk + 1 == mesh.chunks.size() || item < (index ? c.firstIndex + 3ull * c.triangleCount : c.firstVertex + c.vertexCount))
        return c;
    }
  }
  uint32_t leafOf(const MeshChunk& c, const gpu::LayerVertex& v) const {
    const uint32_t l = chunkLeaf(v);
    return l == LAYER_CHUNK_NO_LEAF ? kNoLeaf : hm.roots[c.firstRoot + l].leaf;
  }
  // Each stage handles items [job.next, its return value) and moves job.stage on when it reaches
  // its last item (returning 0, so the next stage starts at its first).
  size_t rootDepths();
  size_t foliageVertexDepths();
  Status layerBoundaries();
  size_t leafLayers();
  size_t rootLineAndTops();
  size_t trianglesPerLayer();
  void finish();
};

// The keys the layers are assigned by: leaf roots (or, with per-triangle slicing, every foliage
// vertex), read from the chunks' root tables (a leaf in two chunks is written twice, alike).
size_t PlacementPass::rootDepths() {
  size_t roots = 0, end = job.next;
  for (; end < nChunks && roots < batch; ++end) {
    const MeshChunk& c = mesh.chunks[end];
    const InstanceRun own = copiesOf(c);
    for (uint64_t i = c.firstRoot; i < c.firstRoot + c.rootCount; ++i)
      for (size_t k = own.first; k < own.first + own.count; ++k) {
        const float z = depthOf(k, hm.roots[i].position);
        job.leafDepth[leafSlot(k, c, hm.roots[i].leaf)] = z;
        if (!geometric) {
          job.zMin = std::min(job.zMin, z);
          job.zMax = std::max(job.zMax, z);
        }
      }
    roots += size_t(c.rootCount) * std::max<size_t>(own.count, 1) / std::max<size_t>(copies, 1) + 1;
  }
  if (end < nChunks) return end;
  job.stage = geometric ? PlacementStage::FoliageVertexDepths : PlacementStage::LayerBoundaries;
  return 0;
}

size_t PlacementPass::foliageVertexDepths() {
  const size_t end = std::min(job.next + batch, nVertices);
  for (size_t v = job.next; v < end; ++v)
    if (chunkLeaf(hm.vertices[v]) != LAYER_CHUNK_NO_LEAF) {
      const MeshChunk& c = chunkOf(v, false);
      const glm::vec3 p = decodePosition(c, hm.vertices[v]);
      const InstanceRun own = copiesOf(c);
      for (size_t k = own.first; k < own.first + own.count; ++k) {
        const float z = depthOf(k, p);
        job.zMin = std::min(job.zMin, z);
        job.zMax = std::max(job.zMax, z);
      }
    }
  if (end < nVertices) return end;
  job.stage = PlacementStage::LayerBoundaries;
  return 0;
}

Status PlacementPass::layerBoundaries() {
  if (!(job.zMin <= job.zMax)) job.zMin = job.zMax = 0.0f;  // no foliage: empty layers
  // Every root at one depth (a plant whose foliage is one welded part, a single leaf): the slabs
  // would all be that depth, and the vertex shader's root depth, rounded otherwise than this
  // one, could put the leaf in the last layer while the CPU counts it in the first, whose top and
  // height it then does not get (issue 77: a palm that never moved). The range is opened behind
  // the roots by a thousandth of their depth, far beyond any rounding, so they lie in layer 0.
  const float minRange = 1e-3f * std::max(std::abs(job.zMin), 1e-3f);
  if (job.zMax - job.zMin < minRange) job.zMax = job.zMin + minRange;
  std::vector<LayerSlab> slabs;
  std::vector<float> bounds;
  CANOPY_TRY(placeLayers(settings.layout, settings.regions, job.zMin, job.zMax, &slabs, &bounds));
  for (uint32_t i = 0; i <= CANOPY_MAX_LAYERS; ++i) frame.boundaries[i] = bounds[std::min<size_t>(i, bounds.size() - 1)];
  job.layers.assign(frame.layerCount, LayerInfo{});
  for (uint32_t i = 0; i < frame.layerCount; ++i) {
    job.layers[i].slab = slabs[i];
    job.layers[i].top = INFINITY;
  }
  job.leafLayer.resize(job.leafDepth.size());
  if (perPlant) job.plantTop.assign(job.plantBase.back() * frame.layerCount, INFINITY);
  job.stage = PlacementStage::LeafLayers;
  return Status();
}

// Every copy's leaves: (copy, leaf) items.
size_t PlacementPass::leafLayers() {
  const size_t total = job.leafDepth.size(), end = std::min(job.next + batch * std::max<size_t>(copies, 1), total);
  for (size_t i = job.next; i < end; ++i) {
    job.leafLayer[i] = uint8_t(gpu::layerOfDepth(frame, job.leafDepth[i]));
    job.layers[job.leafLayer[i]].leaves++;
  }
  if (end < total) return end;
  job.stage = PlacementStage::RootLineAndTops;
  return 0;
}

// The screen-space root line and per-layer tops (eq. 7), the layers' and the rigid part's depths.
size_t PlacementPass::rootLineAndTops() {
  const size_t end = std::min(job.next + batch, nVertices);
  for (size_t v = job.next; v < end; ++v) {
    const MeshChunk& c = chunkOf(v, false);
    const glm::vec4 p(decodePosition(c, hm.vertices[v]), 1.0f);
    const uint32_t leaf = leafOf(c, hm.vertices[v]);
    const InstanceRun own = copiesOf(c);
    for (size_t k = own.first; k < own.first + own.count; ++k) {
      const float w = glm::dot(job.rowsW[k], p);
      if (w <= 1e-6f) {
        job.behind = true;
        continue;
      }
      const float y = (glm::dot(job.rowsY[k], p) / w * 0.5f + 0.5f) * height;
      job.bottom = std::max(job.bottom, y);
      const glm::vec2 px((glm::dot(job.rowsX[k], p) / w * 0.5f + 0.5f) * width, y);
      job.pixelLo = glm::min(job.pixelLo, px);
      job.pixelHi = glm::max(job.pixelHi, px);
      const float z = glm::dot(job.depthRows[k], p);
      if (leaf == kNoLeaf) {
        job.rigidDepth = glm::vec2(std::min(job.rigidDepth.x, z), std::max(job.rigidDepth.y, z));
        continue;
      }
      const uint32_t layer = geometric ? gpu::layerOfDepth(frame, z) : job.leafLayer[leafSlot(k, c, leaf)];
      LayerInfo& li = job.layers[layer];
      li.top = std::min(li.top, y);
      li.drawnNear = std::min(li.drawnNear, z);
      li.drawnFar = std::max(li.drawnFar, z);
      if (perPlant) {
        const size_t slot = job.plantBase[k] + (plants.leafPlant[leaf] - species[c.species].firstPlant);
        float& top = job.plantTop[slot * frame.layerCount + layer];
        top = std::min(top, y);
      }
    }
  }
  if (end < nVertices) return end;
  job.stage = PlacementStage::TrianglesPerLayer;
  return 0;
}

// Foliage triangles come first in GPU order: indices [0, foliageIndices).
size_t PlacementPass::trianglesPerLayer() {
  const size_t end = std::min(job.next + 3 * batch, foliageIndices);
  for (size_t k = job.next; k < end; k += 3) {
    const MeshChunk& c = chunkOf(k, true);
    const gpu::LayerVertex& v = hm.vertices[c.firstVertex + hm.indices[k]];
    const InstanceRun own = copiesOf(c);
    for (size_t j = own.first; j < own.first + own.count; ++j) {
      const uint32_t layer = geometric ? gpu::layerOfDepth(frame, depthOf(j, decodePosition(c, v))) : job.leafLayer[leafSlot(j, c, leafOf(c, v))];
      job.layers[layer].triangles++;
    }
  }
  if (end < foliageIndices) return end;
  job.stage = PlacementStage::Finish;
  return 0;
}

void PlacementPass::finish() {
  // A vertex just in front of the camera's plane (a first-person camera inside the vegetation)
  // projects hundreds of image heights away: eq. 7's root line and h are held within an image
  // height of the image, or eq. 6 (h times the sway) moved every corner by thousands of pixels.
  float bottom = std::min(job.bottom, 2.0f * height);
  if (!std::isfinite(bottom)) bottom = height;
  // A layer without leaves takes the top of the nearest layer with some: the vertex shader, not this
  // count, decides where a leaf at a slab boundary is drawn, and a leaf drawn in a layer of height
  // 1 px would stand still (eq. 6 is scaled by h with the world wind).
  const size_t n = job.layers.size();
  std::vector<float> tops(n, INFINITY);
  for (size_t i = 0; i < n; ++i) tops[i] = job.layers[i].top;
  for (size_t i = 0; i < n; ++i)
    for (size_t k = 1; !std::isfinite(tops[i]) && k < n; ++k) {
      if (i >= k && std::isfinite(job.layers[i - k].top)) tops[i] = job.layers[i - k].top;
      else if (i + k < n && std::isfinite(job.layers[i + k].top)) tops[i] = job.layers[i + k].top;
    }
  for (size_t i = 0; i < n; ++i) {
    LayerInfo& li = job.layers[i];
    li.rootLineY = bottom;
    li.top = std::isfinite(tops[i]) ? std::max(tops[i], -height) : bottom;
    li.height = std::max(bottom - li.top, 1.0f);
  }
  if (perPlant) placePlants(job, plants, species, height, width);
  job.plantTop = {};
  job.leafDepth = {};
  job.leafLayer = {};
}

}  // namespace

// Runs the placement's stages (PlacementStage) until it is done or `deadline` (null: none) has
// passed; the clock is read every batch of items.
Status advancePlacement(const PlacementInputs& in, PlacementJob& job, const PlacementClock::time_point* deadline, bool* done) {
  const auto t0 = PlacementClock::now();
  PlacementPass pass(in, job);
  *done = false;
  while (!*done) {
    size_t end = 0;
    switch (job.stage) {
      case PlacementStage::RootDepths: end = pass.rootDepths(); break;
      case PlacementStage::FoliageVertexDepths: end = pass.foliageVertexDepths(); break;
      case PlacementStage::LayerBoundaries: CANOPY_TRY(pass.layerBoundaries()); break;
      case PlacementStage::LeafLayers: end = pass.leafLayers(); break;
      case PlacementStage::RootLineAndTops: end = pass.rootLineAndTops(); break;
      case PlacementStage::TrianglesPerLayer: end = pass.trianglesPerLayer(); break;
      case PlacementStage::Finish:
        pass.finish();
        *done = true;
        break;
    }
    job.next = end;
    if (end == 0) job.chunk = 0;  // a new stage starts at the first chunk
    if (!*done && deadline && PlacementClock::now() >= *deadline) break;
  }
  job.ms += msSince(t0);
  return Status();
}

// The impostor cut of the visible placement (LayerSettings.impostors; render/impostors.h): which
// boxes are drawn as impostors, with which weight, and the remaining foliage as chunk parts.
void planImpostorCut(const PlacementInputs& pin, const gpu::LayerFrame& frame, const LayerView& view,
                     const std::vector<InstanceRun>& runs, ImpostorDraws* out, LayerStats& stats) {
  const auto t0 = PlacementClock::now();
  *out = ImpostorDraws{};
  const LayerSettings& s = *pin.settings;
  if ((s.impostors.mode == ImpostorMode::Off && !s.impostors.debugView) || !pin.impostors->enabled) return;
  ImpostorCutInput in;
  in.settings = s.impostors;
  in.depthRow = frame.depthRow;
  in.perspective = view.proj[2][3] != 0.0f;
  in.pixelScale = std::abs(view.proj[1][1]) * 0.5f * float(pin.height);
  // The far region begins at the first far layer's near boundary (none: no far region); boxes ramp
  // in over band x the mean layer thickness before it.
  const LayerLayout& l = s.layout;
  const uint32_t n = l.count();
  in.farStart = l.region[2] ? frame.boundaries[l.region[0] + l.region[1]] : INFINITY;
  in.farBand = s.impostors.band * (frame.boundaries[n] - frame.boundaries[0]) / float(n);
  // Copies (not the model alone at its origin): each visible one cut through its species' boxes.
  const LayerInstances& copies = *pin.instances;
  if (!copies.identity)
    for (const InstanceRun& r : runs)
      for (uint32_t i = r.first; i < r.first + r.count && i < copies.models.size(); ++i)
        in.copies.push_back({i, i < copies.species.size() ? copies.species[i] : 0u, copies.models[i]});
  impostorCut(*pin.impostors, in, &out->cut);
  for (const ImpostorCut::Run& r : out->cut.geometry)
    appendRunParts(pin.mesh->chunks, r.first, r.count, r.weight, r.level, &out->parts,
                   r.copy == kEveryCopy ? InstanceRun{} : InstanceRun{r.copy, 1});
  for (uint32_t c : out->cut.wholeCopies) {
    if (!out->wholeRuns.empty() && out->wholeRuns.back().first + out->wholeRuns.back().count == c) out->wholeRuns.back().count++;
    else out->wholeRuns.push_back({c, 1});
  }
  out->instances = out->cut.opaque;
  out->opaque = uint32_t(out->cut.opaque.size());
  out->instances.insert(out->instances.end(), out->cut.fading.begin(), out->cut.fading.end());
  stats.lastImpostors = uint32_t(out->instances.size());
  stats.lastFadingBoxes = uint32_t(out->cut.fading.size());
  stats.lastDrawnTriangles = out->cut.triangles;
  stats.lastImpostorCopies = out->cut.perCopy ? uint32_t(in.copies.size() - out->cut.wholeCopies.size()) : out->instances.empty() ? 0u : 1u;
  stats.lastPlacementMs += msSince(t0);
}

uint32_t visibleSpecies(const PlacementJob& job) {
  uint32_t n = 0;
  for (const InstanceRun& r : job.speciesVisible) n += r.count > 0;
  return n;
}

void takeVertexBounds(VisibleLayers& v, const PlacementJob& job) {
  v.extent = job.behind ? PixelExtent{} : PixelExtent{job.pixelLo, job.pixelHi, true};
  v.rigidDepth = job.rigidDepth;
}

// The whole placement for `view` at once, made the visible one.
Status placeForView(const PlacementInputs& in, const LayerView& view, VisibleLayers& visible, LayerStats& stats) {
  PlacementJob job;
  beginPlacement(in, view, job);
  bool done = false;
  CANOPY_TRY(advancePlacement(in, job, nullptr, &done));
  visible.view = job.view;
  visible.runs = job.runs;
  stats.lastVisibleInstances = uint32_t(job.depthRows.size());
  stats.lastVisibleSpecies = visibleSpecies(job);
  takeVertexBounds(visible, job);
  visible.frame = job.frame;
  visible.layers = std::move(job.layers);
  stats.lastPlacementMs = job.ms;
  planImpostorCut(in, visible.frame, view, visible.runs, &visible.impostors, stats);
  return Status();
}


uint32_t halfResolutionMask(const LayerSettings& s) {
  const uint32_t n = s.layout.count(), k = std::min(s.halfResolutionLayers, n);
  if (k == 0) return 0;
  const uint32_t bits = k >= 32 ? ~0u : (1u << k) - 1u;
  return bits << (n - k);  // the farthest k layers
}

gpu::LayerFrame cameraFrame(const LayerSettings& s, const LayerView& view) {
  gpu::LayerFrame f{};
  f.halfResolution = halfResolutionMask(s);
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
  f.leafShading = glm::vec4(s.leafRefractiveIndex, s.leafRoughness, s.translucency ? 1.0f : 0.0f,
                           s.translucencyModel == TranslucencyModel::Habel ? LAYER_TRANSLUCENCY_HABEL : LAYER_TRANSLUCENCY_DIFFUSE);
  return f;
}


VkRect2D projectedFootprint(const std::vector<glm::mat4>& viewProjs, const glm::vec3& bmin, const glm::vec3& bmax,
                            uint32_t width, uint32_t height) {
  const float w = float(width), h = float(height);
  const VkRect2D all{{0, 0}, {width, height}};
  glm::vec2 lo(INFINITY), hi(-INFINITY);
  for (const glm::mat4& vp : viewProjs)
    for (int c = 0; c < 8; ++c) {
      const glm::vec3 p((c & 1) ? bmax.x : bmin.x, (c & 2) ? bmax.y : bmin.y, (c & 4) ? bmax.z : bmin.z);
      const glm::vec4 q = vp * glm::vec4(p, 1.0f);
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

}  // namespace canopy
