#pragma once
// Layer dynamics on the GPU (paper 3.4-3.6): for every corner of a uniform grid over every layer,
// the simulation-plane velocity is projected to the view (eq. 1-2, as the general rotation), delayed
// for the layer (eq. 3-4 exact, or eq. 5 approximate; the mode can change every frame) and turned
// into a displacement d_i in pixels (eq. 6-7). The result feeds the inverse warp.
#include <cstdint>
#include <vector>

#include "engine/memory.h"
#include "engine/pipeline.h"
#include "engine/render_graph.h"
#include "engine/status.h"
#include "render/camera.h"
#include "shared/anim.h"

namespace canopy {
struct Device;

enum class DelayMode { Exact, Approximate };

// The simulation plane in world space (design.md): the 2D field is the same on every parallel
// plane; a world point maps to tile coordinates by orthogonal projection, / tileSize, fract().
struct SimulationPlane {
  glm::vec3 origin{0.0f};          // world point at simulation coordinate (0, 0)
  glm::vec3 right{1.0f, 0, 0};     // unit x axis
  glm::vec3 up{0, 1.0f, 0};        // unit y axis, orthogonal to right
  float tileSize = 1.0f;           // world units covered by one tile (one simulation domain), > 0
};
// The default plane: the camera's own right/up, one tile covering the visible region at depth
// `centreDepth` (the larger of its width and height), origin at that region's lower-left corner.
SimulationPlane simulationPlaneFromView(const LayerView& view, float centreDepth);

struct DynamicsParams {
  DelayMode delay = DelayMode::Exact;
  float vd = 2.0f;                  // V_D of eq. 4, domain units/s, [-1000, 1000]
  float propagationSpeed = 1.0f;    // s of eq. 5, [0, 1000]
  glm::vec3 lambda{300.0f, 300.0f, 150.0f};  // lambda_x,y,z: pixels per domain unit, [0, 1e6] each
  float rigidity = 1.0f;            // r of eq. 7, [0, 10]
  bool everyPartMoves = false;      // eq. 7: R = 1 everywhere
  float depthAttenuation = 0.3f;    // m of eq. 6, [0, 1]
  float dt = 1.0f / 30.0f;          // Delta t of eq. 6, s, (0, 10]
  uint32_t cellSize = 16;           // warp-grid cell, pixels, [2, 256]
  float maxDelay = 10.0f;           // |gamma| bound for a vanishing eq. 4 denominator, s, (0, 3600]
};
Status validateDynamicsParams(const DynamicsParams& params);

// One layer as the dynamics see it (from the layer placement).
struct DynamicsLayer {
  float depth = 0;      // representative view depth
  float distance = 0;   // L_i
  float rootLineY = 0;  // pixels, y down
  float height = 1;     // pixels
};

struct DynamicsFrameDesc {
  LayerView view;
  SimulationPlane plane;
  std::vector<DynamicsLayer> layers;  // 1..CANOPY_MAX_LAYERS
  uint32_t width = 0, height = 0;     // image, pixels
  uint32_t simSize = 0, ringSize = 0; // N and H of the simulation
  float time = 0;                     // time of the newest simulation field, s
};
// Corners per row and column of the warp grid: ceil(size / cell) + 1.
uint32_t gridCorners(uint32_t pixels, uint32_t cellSize);
Status makeAnimFrame(const DynamicsParams& params, const DynamicsFrameDesc& desc, gpu::AnimFrame* out);

struct LayerDynamics {
  Device* device = nullptr;
  ComputePipeline pipeline;
  Buffer frame;         // AnimFrame
  Buffer displacement;  // layers x gridY x gridX vec2, pixels (y down)
  Buffer previous;      // the displacement of the frame before (motion vectors)
  gpu::AnimFrame current{};
  uint32_t maxCorners = 0, maxLayers = 0;
};
// Sized for images up to width x height at cells down to minCellSize, up to maxLayers layers.
Status createLayerDynamics(Device& device, uint32_t width, uint32_t height, uint32_t minCellSize, uint32_t maxLayers,
                           LayerDynamics* out);
void destroyLayerDynamics(LayerDynamics& dynamics);

// Adds "dynamics: frame" and "dynamics: displacement". `tiled`, `ring` and `ringTimes` are the
// simulation's buffers (SimulationResources); the frame used is dynamics.current at record time.
// Returns the ids of the displacement buffer, of the previous frame's and of the AnimFrame block
// (`previous` and `frame` may be null).
Status addDynamicsPasses(LayerDynamics& dynamics, rg::RenderGraph& graph, rg::ResourceId tiled, rg::ResourceId ring,
                         rg::ResourceId ringTimes, rg::ResourceId* displacement, rg::ResourceId* previous = nullptr,
                         rg::ResourceId* frame = nullptr);

}  // namespace canopy
