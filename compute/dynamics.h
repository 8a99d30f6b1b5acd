#pragma once
// Layer dynamics on the GPU (paper 3.4-3.6): for every corner of a uniform grid over every layer,
// the simulation-plane velocity is projected to the view (eq. 1-2, as the general rotation), delayed
// for the layer (eq. 3-4 exact, or eq. 5 approximate; the mode can change every frame) and turned
// into a displacement d_i in pixels (eq. 6-7). The result feeds the inverse warp.
#include <cstdint>
#include <vector>

#include <canopy/canopy_params.h>

#include "engine/memory.h"
#include "engine/pipeline.h"
#include "engine/render_graph.h"
#include "engine/status.h"
#include "engine/camera.h"
#include "shared/anim.h"

namespace canopy {
struct Device;

// DelayMode and SimulationPlane: <canopy/canopy_params.h> (world-space vectors as Float3).
// The default plane: the camera's own right/up, one tile covering the visible region at depth
// `centreDepth` (the larger of its width and height), origin at that region's lower-left corner.
SimulationPlane simulationPlaneFromView(const LayerView& view, float centreDepth);

// DynamicsParams: <canopy/canopy_params.h>.
Status validateDynamicsParams(const DynamicsParams& params);

// One layer as the dynamics see it (from the layer placement).
struct DynamicsLayer {
  float depth = 0;      // representative view depth
  float distance = 0;   // L_i
  float rootLineY = 0;  // pixels, y down
  float height = 1;     // pixels
  std::vector<glm::vec4> plants;  // per-plant roots: rects (x lo, x hi, top, root row), LayerInfo::plants
  // Per rect: its species' flexibility and response speed, and the plant's sway scale (its lever
  // against the per-vertex baseline's, applied with the world wind: heightSway > 0); empty: 1, 1, 1.
  std::vector<glm::vec3> plantResponse;
  std::vector<float> plantHeight;        // per rect: eq. 7's h, pixels (LayerInfo::plantHeight); empty or 0: the rect's rows
  std::vector<float> plantDepth;         // per rect: the plant's centre's view depth (LayerInfo::plantDepth); empty or 0: the layer's
  std::vector<uint8_t> plantWoodOnly;    // per rect: 1 where the plant has no leaves in the layer (LayerInfo::plantWoodOnly); empty: 0
};

struct DynamicsFrameDesc {
  LayerView view;
  SimulationPlane plane;
  std::vector<DynamicsLayer> layers;  // 1..CANOPY_MAX_LAYERS
  uint32_t width = 0, height = 0;     // image, pixels
  uint32_t simSize = 0, ringSize = 0; // N and H of the simulation
  float time = 0;                     // time of the newest simulation field, s
  float waveSpeed = 0.0f;             // the oscillator's c (eq. 5's s unless DynamicsParams.propagationSpeed), domain units/s
  float nominalDt = 1.0f / 30.0f;     // the simulation's nominal step (eq. 6's Delta t unless DynamicsParams.dt), s
  uint32_t newestSlot = ANIM_RING_UNORDERED;  // ring slot of the newest field, when written in step order
  uint32_t halfResolution = 0;        // the layers' LayerFrame.halfResolution, passed to the composite
  bool bend = false;                  // the pushers' bend field may be non-zero: the corners add it
  // World wind (docs/design.md "World wind"): eq. 6 scaled by each plant's on-screen height h and
  // lambda in shares of h per metre of motion: lambda = lambda_i / lambda_x * sway * tileSize /
  // (unitsPerMetre * Delta t) (DynamicsParams.lambda's ratios; sway = WorldWind.sway). 0: off.
  float heightSway = 0.0f;
  float unitsPerMetre = 1.0f;
  glm::vec4 bendOrigin{0.0f, 0.0f, 0.0f, 1.0f}, bendX{1.0f, 0.0f, 0.0f, 0.0f}, bendZ{0.0f, 0.0f, 1.0f, 0.0f};  // AnimFrame's
};
// Corners per row and column of the warp grid: ceil(size / cell) + 1.
uint32_t gridCorners(uint32_t pixels, uint32_t cellSize);
// `plantRects` (null: none) receives the frame block's plant table (two vec4 a rect: shared/anim.h)
// when the layers have plant rects and DynamicsParams.roots is PerPlant or a rect's species responds
// otherwise than the method (at most ANIM_MAX_PLANT_RECTS; more: the layers' roots, no response).
Status makeAnimFrame(const DynamicsParams& params, const DynamicsFrameDesc& desc, gpu::AnimFrame* out,
                     std::vector<glm::vec4>* plantRects = nullptr);

struct LayerDynamics {
  Device* device = nullptr;
  ComputePipeline pipeline;
  ComputePipeline stretchCols, stretchRows;  // the warp's stretch bound (DynamicsParams.maxStretch)
  Buffer frame;         // AnimFrame
  Buffer displacement;  // layers x gridY x gridX vec2, pixels (y down)
  Buffer previous;      // the displacement of the frame before (motion vectors)
  Buffer raw;           // eq. 6-7 before the stretch bound, as displacement
  Buffer envelope;      // the stretch bound's column pass: a float per corner
  Buffer bendShare;     // the pushers' share of the displacement, added after the bound, as displacement
  gpu::AnimFrame current{};
  std::vector<glm::vec4> plantRects;  // uploaded after `current` (per-plant roots)
  uint32_t maxCorners = 0, maxLayers = 0;
};
// Sized for images up to width x height at cells down to minCellSize, up to maxLayers layers.
Status createLayerDynamics(Device& device, uint32_t width, uint32_t height, uint32_t minCellSize, uint32_t maxLayers,
                           LayerDynamics* out);
void destroyLayerDynamics(LayerDynamics& dynamics);

// Adds "dynamics: frame", "dynamics: displacement" and the stretch bound's two passes. `tiled`, `ring` and `ringTimes` are the
// simulation's buffers (SimulationResources); the frame used is dynamics.current at record time.
// Returns the ids of the displacement buffer, of the previous frame's and of the AnimFrame block
// (`previous` and `frame` may be null).
Status addDynamicsPasses(LayerDynamics& dynamics, rg::RenderGraph& graph, rg::ResourceId tiled, rg::ResourceId ring,
                         rg::ResourceId ringTimes, rg::ResourceId* displacement, rg::ResourceId* previous = nullptr,
                         rg::ResourceId* frame = nullptr);

}  // namespace canopy
