#pragma once
// Canopy's public API: animated vegetation in a host engine's own colour and depth targets.
//
// One context (CanopyContext) is created per vegetation model from a CanopyDesc; plain parameter
// structs (CanopyParams) can change every frame. Each frame Canopy steps the 2D wind + wave
// simulation (paper 3.3), re-slices the foliage into depth layers when the view moved (3.2),
// computes every layer's delayed displacement on a warp grid (3.4-3.6) and warps + composites the
// layers over the host's colour, writing the vegetation's depth (and optionally motion vectors).
//
// Two ways to embed it (design.md, "The embedding surface"):
//  1. Canopy's render graph: beginCanopyFrame() every frame, and addCanopyPasses() once into the
//     host's rg::RenderGraph holding the host's targets as imported images (rebuild that graph
//     when canopyResourceGeneration() changes).
//  2. Any other engine: recordCanopy() records one frame, barriers included, into the host's
//     command buffer and leaves the host's images in the state the host asks for.
// Nothing is global: every call takes the context. Errors are returned (Status), never thrown.
//
// Conventions: the camera is the host's (view + Vulkan projection: clip y down, depth 0..1 with
// near at 0, the depth the host's depth target holds, compared LESS). Times in seconds, sizes in
// pixels; simulation units in compute/simulation.h.
#include <cstdint>
#include <vulkan/vulkan.h>

#include "compute/dynamics.h"
#include "compute/simulation.h"
#include "engine/device.h"
#include "engine/render_graph.h"
#include "engine/status.h"
#include "render/camera.h"
#include "render/composite.h"
#include "render/gltf_loader.h"
#include "render/layers.h"

namespace canopy {

struct CanopyDesc {
  uint32_t width = 1024, height = 768;               // host targets, 1..16384 each
  VkFormat colorFormat = VK_FORMAT_R8G8B8A8_UNORM;   // host colour target: any blendable format
  VkFormat depthFormat = VK_FORMAT_D32_SFLOAT;       // host depth: D32_SFLOAT or D16_UNORM, SAMPLED usage
  VkFormat motionFormat = VK_FORMAT_UNDEFINED;       // R16G16_SFLOAT / R32G32_SFLOAT; UNDEFINED: none
  VkFormat layerFormat = VK_FORMAT_R16G16B16A16_SFLOAT;  // layer images (or R8G8B8A8_UNORM)
  uint32_t maxLayers = 8;    // the most layers CanopyParams may ask for, 1..32 (sizes the warp grid)
  uint32_t minCellSize = 4;  // the smallest warp-grid cell CanopyParams may ask for, pixels, 2..256
  SimulationDesc simulation; // grid N, history length
  MaterialSplitOptions split;       // which materials are rigid (background) and which are foliage
  LeafRootOptions roots;
  bool useRootCache = true;         // leaf-root cache file beside the model (or in rootCacheDir)
  std::string rootCacheDir;
  Progress progress;                // optional: called during createCanopy ("leaf roots", "vertices")
};

struct CanopyParams {
  LayerSettings layers;        // layout "5(3-1-1)", region split, re-slicing thresholds, light
  SimulationParams simulation; // wind sources, strength, frequency, fluid, oscillator, motors
  DynamicsParams dynamics;     // delay mode, V_D, s, lambda, rigidity, m, warp-grid cell
  CompositeParams composite;   // compositing levers
  // The simulation plane (design.md). Unset: fixed from the first frame's camera, one tile over the
  // visible region at the vegetation's centre depth.
  bool customPlane = false;
  SimulationPlane plane;
};

// What changes every frame.
struct CanopyFrame {
  LayerView camera;          // the host's view and projection for this frame
  float dt = 1.0f / 30.0f;   // simulation step, s, [0, 10]; 0 holds the simulation (pause)
};

struct CanopyStats {
  uint64_t frames = 0;
  bool layersRebuilt = false;        // the last frame re-sliced the layers
  uint64_t resourceGeneration = 0;   // see canopyResourceGeneration()
  uint64_t internalGraphBuilds = 0;  // recordCanopy() graph (re)compilations
  LayerStats layers;
  SimulationStats simulation;
};

struct CanopyContext;

// Loads nothing itself: `model` comes from loadGltf() (or any generator) and may be released after.
Status createCanopy(Device& device, const VegetationModel& model, const CanopyDesc& desc, CanopyContext** out);
void destroyCanopy(CanopyContext* context);

// Validates and applies parameters from the next frame on. A new layer count recreates the layer
// images only (and bumps canopyResourceGeneration); a new warp-grid cell only changes constants.
Status setCanopyParams(CanopyContext* context, const CanopyParams& params);
const CanopyParams& canopyParams(const CanopyContext* context);

// The host's targets changed size (a window resize): recreates the layer images, the compositor
// and the warp-grid dynamics (small objects, pipelines included) and keeps the mesh, leaf roots,
// simulation state and parameters, so a resize costs no reload. Waits for the device to be idle. Bumps
// canopyResourceGeneration() (rebuild a graph holding Canopy's passes); recordCanopy() rebuilds
// its own. Width and height in [1, 16384]; on any other failure (out of memory) destroy the context.
Status resizeCanopy(CanopyContext* context, uint32_t width, uint32_t height);

// Path 1 (Canopy's graph): prepares the next recorded frame (CPU work only).
Status beginCanopyFrame(CanopyContext* context, const CanopyFrame& frame);
// Adds Canopy's passes (simulation, layers, dynamics, composite) to `graph`, drawing into the
// host's imported images. The graph must be rebuilt when canopyResourceGeneration() changes.
Status addCanopyPasses(CanopyContext* context, rg::RenderGraph& graph, const CompositeTargets& targets);
uint64_t canopyResourceGeneration(const CanopyContext* context);

// Path 2 (the host's own graph): one of the host's images, how it arrives and how to leave it.
struct CanopyImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;  // 2D view; for depth, the depth aspect
  rg::State current;                  // last stage/access/layout the host used it with
  rg::State final;                    // the state Canopy must leave it in
};
struct CanopyFrameInputs {
  CanopyFrame frame;
  CanopyImage color, depth;
  CanopyImage motion;                 // only with CanopyDesc.motionFormat
};
// Records one whole frame into `cmd` (which the host submits). Equivalent to beginCanopyFrame()
// plus a graph holding the host's images; that graph is kept and rebuilt only when the images,
// their states or Canopy's resources change.
Status recordCanopy(CanopyContext* context, VkCommandBuffer cmd, const CanopyFrameInputs& inputs);

CanopyStats canopyStats(const CanopyContext* context);

// Read access to the parts (tools, tests, the benchmark).
LayeredVegetation& canopyLayers(CanopyContext* context);
LayerDynamics& canopyDynamics(CanopyContext* context);
Simulation& canopySimulation(CanopyContext* context);
Compositor& canopyCompositor(CanopyContext* context);

}  // namespace canopy
