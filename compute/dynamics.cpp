#include "compute/dynamics.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "engine/device.h"
#include "engine/pass_slots.h"
#include "shared/sim.h"

namespace canopy {
namespace {
const rg::State kComputeRead = rg::stateOf(rg::Use::ComputeStorageRead);

bool finite3(const glm::vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

// A deterministic uniform number in [-1, 1] for layer i under `seed` (the simulation's integer
// hash: the same seed gives the same V_D per layer on every machine and every frame).
float layerJitter(uint32_t seed, uint32_t i) { return gpu::hashToSigned(seed * 0x9E3779B9u ^ (i + 1u) * 0x85EBCA6Bu); }
}  // namespace

SimulationPlane simulationPlaneFromView(const LayerView& view, float centreDepth) {
  SimulationPlane p;
  const glm::mat4 inv = glm::inverse(view.view);
  const glm::vec3 right = glm::normalize(glm::vec3(inv[0])), up = glm::normalize(glm::vec3(inv[1]));
  const glm::vec3 eye = glm::vec3(inv[3]), forward = -glm::normalize(glm::vec3(inv[2]));
  // Half extents of the visible region at that depth, from the projection's scale terms.
  const float halfW = centreDepth / std::max(std::abs(view.proj[0][0]), 1e-6f);
  const float halfH = centreDepth / std::max(std::abs(view.proj[1][1]), 1e-6f);
  p.tileSize = 2.0f * std::max(halfW, halfH);
  p.right = toFloat3(right);
  p.up = toFloat3(up);
  p.origin = toFloat3(eye + forward * centreDepth - right * (0.5f * p.tileSize) - up * (0.5f * p.tileSize));
  return p;
}

Status validateDynamicsParams(const DynamicsParams& p) { return checkParams(p, "DynamicsParams."); }

uint32_t gridCorners(uint32_t pixels, uint32_t cellSize) { return (pixels + cellSize - 1) / cellSize + 1; }

Status makeAnimFrame(const DynamicsParams& p, const DynamicsFrameDesc& d, gpu::AnimFrame* out, std::vector<glm::vec4>* plantRects) {
  // `p` was checked when it was given (validateDynamicsParams; setCanopyParams), not every frame.
  const uint32_t n = uint32_t(d.layers.size());
  if (n < 1 || n > CANOPY_MAX_LAYERS)
    return Status::error("dynamics: " + std::to_string(n) + " layers, expected 1.." + std::to_string(CANOPY_MAX_LAYERS));
  if (d.width < 1 || d.height < 1) return Status::error("dynamics: empty image");
  if (d.simSize < 4 || d.ringSize < 1) return Status::error("dynamics: no simulation field (N < 4 or no history)");
  const glm::vec3 origin = toGlm(d.plane.origin), right = toGlm(d.plane.right), up = toGlm(d.plane.up);
  const float tileSize = d.plane.tileSize;
  if (!finite3(origin) || !(tileSize > 0 && std::isfinite(tileSize)) ||
      std::abs(glm::length(right) - 1.0f) > 1e-3f || std::abs(glm::length(up) - 1.0f) > 1e-3f ||
      std::abs(glm::dot(right, up)) > 1e-3f)
    return Status::error("dynamics: the simulation plane needs unit, orthogonal right/up axes and tileSize > 0");
  gpu::AnimFrame f{};
  f.invViewProj = glm::inverse(d.view.proj * d.view.view);
  f.viewRotation = glm::mat4(glm::mat3(d.view.view));
  f.depthRow = -glm::vec4(d.view.view[0][2], d.view.view[1][2], d.view.view[2][2], d.view.view[3][2]);
  f.simOrigin = glm::vec4(origin, tileSize);
  f.simRight = glm::vec4(right, 0.0f);
  f.simUp = glm::vec4(up, 0.0f);
  // Eq. 6: lambda in pixels per domain unit (from cells by the warp grid's cell), Delta t the
  // simulation's nominal step unless the parameter overrides it.
  const float lambdaScale = p.lambdaUnits == LambdaUnits::Cells ? float(p.cellSize) : 1.0f;
  const float dt = p.dt > 0.0f ? p.dt : d.nominalDt;
  if (!(dt > 0.0f && std::isfinite(dt)))
    return Status::error("dynamics: DynamicsParams.dt = 0 asks for the simulation's nominal step, and none was given");
  f.lambda = glm::vec4(toGlm(p.lambda) * lambdaScale, dt);
  if (d.heightSway > 0.0f) {
    const float lx = std::max(p.lambda.x, 1e-12f);
    f.lambda = glm::vec4(toGlm(p.lambda) / lx * (d.heightSway * tileSize / (std::max(d.unitsPerMetre, 1e-12f) * dt)), dt);
    f.heightRelative = 1u;
  }
  f.time = d.time;
  // Eq. 5's s: the wave's propagation speed (the paper's meaning) unless the host gives one.
  f.propagation = p.propagationSpeed > 0.0f ? p.propagationSpeed : d.waveSpeed;
  f.bend = d.bend ? 1u : 0u;
  f.bendOrigin = d.bendOrigin;
  f.bendX = d.bendX;
  f.bendZ = d.bendZ;
  f.offsetMode = p.approximateOffset == ApproximateOffset::Direction ? ANIM_OFFSET_DIRECTION : ANIM_OFFSET_VELOCITY;
  f.rigidity = p.rigidity;
  f.everyPartMoves = p.everyPartMoves ? 1u : 0u;
  f.delayMode = p.delay == DelayMode::Exact ? ANIM_DELAY_EXACT : ANIM_DELAY_APPROXIMATE;
  f.n = d.simSize;
  f.ringSize = d.ringSize;
  f.layerCount = n;
  f.gridX = gridCorners(d.width, p.cellSize);
  f.gridY = gridCorners(d.height, p.cellSize);
  f.cellSize = float(p.cellSize);
  f.width = float(d.width);
  f.height = float(d.height);
  f.maxDelay = p.maxDelay;
  f.maxShrink = p.maxShrink;
  f.maxStretch = p.maxStretch;
  if (d.newestSlot != ANIM_RING_UNORDERED && d.newestSlot >= d.ringSize)
    return Status::error("dynamics: newestSlot = " + std::to_string(d.newestSlot) + " is outside the ring of " +
                         std::to_string(d.ringSize) + " slots");
  f.newestSlot = d.newestSlot;
  f.halfResolution = d.halfResolution;
  const float last = d.layers.back().distance;
  // With the world wind, eq. 7's h is the vegetation's height for every layer (the tallest layer's
  // from the shared root line): eq. 6 is then l x sway x V below it whatever the layer (r = 1), and a
  // trunk reaching above the highest leaf of its own layer bends on, not flattened at that leaf's
  // row (docs/design.md "Rigid parts in wind"). Per-plant rects carry the plant's own height.
  float tallest = 1.0f;
  for (const DynamicsLayer& dl : d.layers) tallest = std::max(tallest, dl.height);
  // Eq. 4's L_i in the simulation's domain units: one domain unit is one tile of the plane.
  const float distanceScale = p.delayUnits == DelayDistanceUnits::Domain ? 1.0f / tileSize : 1.0f;
  for (uint32_t i = 0; i < n; ++i) {
    gpu::AnimLayer& l = f.layers[i];
    l.depth = d.layers[i].depth;
    l.distance = d.layers[i].distance * distanceScale;
    l.vd = p.vd + p.vdJitter * layerJitter(p.vdSeed, i);
    // docs/design.md: A_i = 1 - m (L_i / L_{n-1})^2; A_0 = 1, and 1 with a single layer. With the
    // world wind eq. 6 is scaled by each plant's height on screen, which already makes a farther
    // plant move fewer pixels: m, the paper's stand-in for that perspective, is not applied twice
    // (it would move the back of one crown 30 % less than its front, and tear a branch spanning
    // both from its leaves: docs/design.md "Rigid parts in wind").
    const float ratio = (n > 1 && last > 0) ? d.layers[i].distance / last : 0.0f;
    const float m = d.heightSway > 0.0f ? 0.0f : p.depthAttenuation;
    l.attenuation = 1.0f - m * ratio * ratio;
    l.rootLineY = d.layers[i].rootLineY;
    l.height = d.heightSway > 0.0f ? tallest : std::max(d.layers[i].height, 1.0f);
  }
  // Per-plant roots: the layers' plant rects in one table after the frame block.
  if (plantRects) {
    plantRects->clear();
    size_t total = 0;
    for (const DynamicsLayer& dl : d.layers) total += dl.plants.size();
    // The rects carry the species' wind response too: kept without per-plant roots when a
    // response differs from the method's, the layer's root line then standing.
    bool response = false;
    for (const DynamicsLayer& dl : d.layers)
      for (const glm::vec3& r : dl.plantResponse) response = response || glm::vec2(r) != glm::vec2(1.0f) || (d.heightSway > 0.0f && r.z != 1.0f);
    // One plant (at most a rect a layer, each the same plant's: the same x range and root row) takes
    // its own root only to carry a response (the placement gives every plant its rects); else the
    // layer's root line stands, as for any single plant.
    bool several = false;
    const glm::vec4* first = nullptr;
    for (const DynamicsLayer& dl : d.layers) {
      several = several || dl.plants.size() > 1;
      if (dl.plants.empty()) continue;
      const glm::vec4& r = dl.plants[0];
      if (!first) first = &r;
      else several = several || r.x != first->x || r.y != first->y || r.w != first->w;
    }
    const bool rooted = p.roots == RootMode::PerPlant && (several || response);
    const float ownRoot = rooted ? 1.0f : 0.0f;
    // With the world wind the rects also carry each plant's sample depth (one gust a plant).
    if ((rooted || response || d.heightSway > 0.0f) && total <= ANIM_MAX_PLANT_RECTS)
      for (uint32_t i = 0; i < n; ++i) {
        const DynamicsLayer& dl = d.layers[i];
        f.layers[i].firstPlant = uint32_t(plantRects->size() / ANIM_RECT_VEC4S);
        f.layers[i].plantCount = uint32_t(dl.plants.size());
        for (size_t j = 0; j < dl.plants.size(); ++j) {
          const glm::vec3 pr = j < dl.plantResponse.size() ? dl.plantResponse[j] : glm::vec3(1.0f);
          // With the world wind a plant's flexibility carries its sway scale (render/plant_sway.h).
          const glm::vec2 r(pr.x * (d.heightSway > 0.0f ? pr.z : 1.0f), pr.y);
          plantRects->push_back(dl.plants[j]);
          const float h = j < dl.plantHeight.size() ? dl.plantHeight[j] : 0.0f;
          plantRects->push_back(glm::vec4(r, ownRoot, h));
          // The field's sample depth: the plant's centre with the world wind (one gust for all its
          // layers), the layer's otherwise (the paper's: each layer where it lies).
          const float depth = j < dl.plantDepth.size() && d.heightSway > 0.0f ? dl.plantDepth[j] : 0.0f;
          const float woodOnly = j < dl.plantWoodOnly.size() ? float(dl.plantWoodOnly[j]) : 0.0f;
          plantRects->push_back(glm::vec4(depth, woodOnly, 0.0f, 0.0f));
        }
      }
  }
  *out = f;
  return Status();
}

Status createLayerDynamics(Device& d, uint32_t width, uint32_t height, uint32_t minCell, uint32_t maxLayers,
                           LayerDynamics* out) {
  *out = LayerDynamics{};
  out->device = &d;
  if (minCell < 2 || maxLayers < 1 || maxLayers > CANOPY_MAX_LAYERS || width < 1 || height < 1)
    return Status::error("createLayerDynamics: bad size, cell or layer count");
  out->maxCorners = gridCorners(width, minCell) * gridCorners(height, minCell);
  out->maxLayers = maxLayers;
  Status s = [&]() -> Status {
    ComputePipelineDesc pd;
    pd.shader = "anim_displace.comp";
    CANOPY_TRY(createComputePipeline(d, pd, &out->pipeline));
    pd.shader = "anim_stretch_cols.comp";
    CANOPY_TRY(createComputePipeline(d, pd, &out->stretchCols));
    pd.shader = "anim_stretch_rows.comp";
    CANOPY_TRY(createComputePipeline(d, pd, &out->stretchRows));
    static_assert(sizeof(gpu::AnimFrame) % 4 == 0 && sizeof(gpu::AnimFrame) <= 65536,
                  "the frame block is written with one vkCmdUpdateBuffer");
    CANOPY_TRY(createBuffer(d, sizeof(gpu::AnimFrame) + ANIM_RECT_VEC4S * ANIM_MAX_PLANT_RECTS * sizeof(glm::vec4),
                            VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                            MemoryUsage::DeviceLocal, &out->frame, "dynamics: frame"));
    CANOPY_TRY(createBuffer(d, VkDeviceSize(out->maxCorners) * maxLayers * sizeof(glm::vec2),
                            VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUsage::DeviceLocal,
                            &out->displacement, "dynamics: displacement"));
    CANOPY_TRY(createBuffer(d, out->displacement.size, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                            MemoryUsage::DeviceLocal, &out->previous, "dynamics: previous displacement"));
    CANOPY_TRY(createBuffer(d, out->displacement.size, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT,
                            MemoryUsage::DeviceLocal, &out->raw, "dynamics: displacement before the stretch bound"));
    CANOPY_TRY(createBuffer(d, out->displacement.size, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUsage::DeviceLocal,
                            &out->bendShare, "dynamics: the pushers' share"));
    CANOPY_TRY(createBuffer(d, VkDeviceSize(out->maxCorners) * maxLayers * sizeof(float), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT,
                            MemoryUsage::DeviceLocal, &out->envelope, "dynamics: stretch envelope"));
    return Status();
  }();
  if (!s.ok()) destroyLayerDynamics(*out);
  return s;
}

void destroyLayerDynamics(LayerDynamics& x) {
  if (!x.device) return;
  destroyComputePipeline(*x.device, x.pipeline);
  destroyComputePipeline(*x.device, x.stretchCols);
  destroyComputePipeline(*x.device, x.stretchRows);
  destroyBuffer(*x.device, x.raw);
  destroyBuffer(*x.device, x.envelope);
  destroyBuffer(*x.device, x.bendShare);
  destroyBuffer(*x.device, x.frame);
  destroyBuffer(*x.device, x.displacement);
  destroyBuffer(*x.device, x.previous);
  x = LayerDynamics{};
}

Status addDynamicsPasses(LayerDynamics& x, rg::RenderGraph& g, rg::ResourceId tiled, rg::ResourceId ring,
                         rg::ResourceId ringTimes, rg::ResourceId* displacement, rg::ResourceId* previous,
                         rg::ResourceId* frameOut) {
  if (!x.device) return Status::error("addDynamicsPasses: dynamics not created");
  const auto frame = g.importBuffer("dynamics: frame", x.frame.size, kComputeRead, kComputeRead);
  const auto disp = g.importBuffer("dynamics: displacement", x.displacement.size, kComputeRead, kComputeRead);
  const auto prev = g.importBuffer("dynamics: previous displacement", x.previous.size, kComputeRead, kComputeRead);
  const auto raw = g.importBuffer("dynamics: displacement before the stretch bound", x.raw.size, kComputeRead, kComputeRead);
  const auto env = g.importBuffer("dynamics: stretch envelope", x.envelope.size, kComputeRead, kComputeRead);
  const auto share = g.importBuffer("dynamics: the pushers' share", x.bendShare.size, kComputeRead, kComputeRead);
  LayerDynamics* p = &x;
  g.addPass("dynamics: frame", [p](rg::PassContext& c) {
     c.device->vk.CmdUpdateBuffer(c.cmd, p->frame.buffer, 0, sizeof(gpu::AnimFrame), &p->current);
     // vkCmdUpdateBuffer takes at most 65536 bytes a call.
     const size_t bytes = p->plantRects.size() * sizeof(glm::vec4);
     for (size_t at = 0; at < bytes; at += 65536)
       c.device->vk.CmdUpdateBuffer(c.cmd, p->frame.buffer, sizeof(gpu::AnimFrame) + at, std::min<size_t>(bytes - at, 65536),
                                    reinterpret_cast<const uint8_t*>(p->plantRects.data()) + at);
     return Status();
   }).write(frame, rg::Use::TransferDst);
  using rg::Use;
  const rg::Slots slots = {rg::slot(frame, Use::ComputeStorageRead),     rg::slot(tiled, Use::ComputeStorageRead),
                           rg::slot(ring, Use::ComputeStorageRead),      rg::slot(ringTimes, Use::ComputeStorageRead),
                           rg::slot(disp, Use::ComputeStorageRead),      rg::slot(prev, Use::ComputeStorageWrite),
                           rg::slot(raw, Use::ComputeStorageWrite),      rg::slot(share, Use::ComputeStorageWrite)};
  rg::addSlotPass(g, "dynamics: displacement", slots, [p](rg::PassContext& c, const rg::Slots& s) {
    const gpu::AnimFrame& f = p->current;
    const uint32_t corners = f.gridX * f.gridY;
    if (corners > p->maxCorners || f.layerCount > p->maxLayers)
      return Status::error("dynamics: the warp grid (" + std::to_string(f.gridX) + "x" + std::to_string(f.gridY) +
                           ", " + std::to_string(f.layerCount) + " layers) exceeds what the dynamics were created for");
    return rg::dispatchSlots(c, p->pipeline, s, corners, f.layerCount, 1, nullptr, 0);
  });
  // The warp's stretch bound (docs/design.md "Layers: the warp's stretch"): along the columns, then the rows.
  const rg::Slots cols = {rg::slot(frame, Use::ComputeStorageRead), rg::slot(raw, Use::ComputeStorageRead),
                          rg::slot(env, Use::ComputeStorageWrite)};
  rg::addSlotPass(g, "dynamics: stretch columns", cols, [p](rg::PassContext& c, const rg::Slots& s) {
    return rg::dispatchSlots(c, p->stretchCols, s, p->current.gridX, p->current.layerCount, 1, nullptr, 0);  // a column each
  });
  const rg::Slots rows = {rg::slot(frame, Use::ComputeStorageRead), rg::slot(raw, Use::ComputeStorageRead),
                          rg::slot(env, Use::ComputeStorageReadWrite), rg::slot(disp, Use::ComputeStorageWrite),
                          rg::slot(share, Use::ComputeStorageRead)};
  rg::addSlotPass(g, "dynamics: stretch rows", rows, [p](rg::PassContext& c, const rg::Slots& s) {
    return rg::dispatchSlots(c, p->stretchRows, s, p->current.gridY, p->current.layerCount, 1, nullptr, 0);  // a row each
  });
  CANOPY_TRY(g.bindBuffer(frame, x.frame.buffer));
  CANOPY_TRY(g.bindBuffer(disp, x.displacement.buffer));
  CANOPY_TRY(g.bindBuffer(prev, x.previous.buffer));
  CANOPY_TRY(g.bindBuffer(raw, x.raw.buffer));
  CANOPY_TRY(g.bindBuffer(env, x.envelope.buffer));
  CANOPY_TRY(g.bindBuffer(share, x.bendShare.buffer));
  if (displacement) *displacement = disp;
  if (previous) *previous = prev;
  if (frameOut) *frameOut = frame;
  return Status();
}

}  // namespace canopy
