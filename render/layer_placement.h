#pragma once
// The leaf-to-layer placement for a view (paper 3.2; docs/design.md "Per-frame data flow"): the leaf roots'
// depth range, the layer boundaries, per-layer bounds and the eq. 7 root line, resumable so a
// spread re-slice runs it a few ms a frame; the placement the visible layers show, with the
// impostor cut it draws; the frame block's camera; the layers' screen footprint.
#include <chrono>
#include <cmath>
#include <cstdint>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/camera.h"
#include "engine/memory.h"
#include "engine/status.h"
#include "render/impostors.h"
#include "render/layer_layout.h"
#include "render/layer_instances.h"
#include "render/layer_mesh.h"
#include "render/reprojection.h"
#include "shared/layers.h"

namespace canopy {
struct Device;

// What a placement reads of the vegetation (placementInputs() of layers.cpp fills it): the mesh's
// host copy, chunks, plants and bounds; the placed copies; the impostors' hierarchy; the settings;
// the layer images' size, pixels.
struct PlacementInputs {
  const LayerMesh* mesh = nullptr;
  const LayerInstances* instances = nullptr;
  const Impostors* impostors = nullptr;
  const LayerSettings* settings = nullptr;
  uint32_t width = 0, height = 0;
};

struct LayerInfo {
  LayerSlab slab;             // view-depth range, representative depth, L_i
  float top = 0;              // highest pixel row (y down) of the layer's foliage
  float rootLineY = 0;        // pixel row of the vegetation's root line (bottom of its projected
                              // bounding box; the same for every layer: paper eq. 7)
  float height = 1;           // rootLineY - top, at least 1 pixel (h of eq. 7)
  // View depths of the layer's leaf vertices (leaves reach beyond their roots' slab): where its
  // texels' depths lie, for the reprojection's depth search (render/reprojection.h LayerSearch).
  float drawnNear = INFINITY, drawnFar = -INFINITY;
  uint32_t leaves = 0;        // leaves whose root is in the layer (CPU count)
  uint64_t triangles = 0;
  // Per-plant roots (docs/design.md "Per-plant roots"), for every plant (the dynamics take its own
  // root when there are several, or when a response rides on it): per plant with leaves in this
  // layer (or wood: plantWoodOnly), its projected bounding box's x range, its leaves' top here and
  // its foot's bottom (x lo, x hi, top, root row; pixels, y down), and the plant's key (PlacementJob::plantBase
  // of its copy + its plant within the species).
  std::vector<glm::vec4> plants;
  std::vector<uint32_t> plantKeys;
  // Per plant rect, its species' wind response (docs/design.md "Species: wind response"):
  // flexibility, response speed.
  // and the plant's sway scale (render/plant_sway.h; applied with the world wind).
  std::vector<glm::vec3> plantResponse;
  // Per plant rect, eq. 7's h (pixels): the plant's box's vertical extent projected at its centre
  // (a grass patch's blades, not the depth its rect spans seen from above; docs/design.md "Per-plant roots").
  std::vector<float> plantHeight;
  // Per plant rect, the view depth of the plant's box's centre: where every layer of it reads the
  // wind field with the world wind (docs/design.md "Rigid parts in wind").
  std::vector<float> plantDepth;
  // Per plant rect, 1 where the plant has no leaves in this layer and the rect serves its rigid parts
  // only (a corner inside a plant's leaves' rect takes that one: shared/anim.h plantRectBetter).
  std::vector<uint8_t> plantWoodOnly;
};

// The placement's stages, in order (advancePlacement runs them until a deadline and resumes).
enum class PlacementStage : uint32_t {
  RootDepths,           // every copy's leaf-root depths from the chunks' root tables, and their range
  FoliageVertexDepths,  // per-triangle slicing (SliceMode::Geometry): the range over every foliage vertex
  LayerBoundaries,      // the layers' slabs and boundaries over the range (placeLayers)
  LeafLayers,           // each (copy, leaf)'s layer by its root's depth
  RootLineAndTops,      // over the vertices: the root line, each layer's top and depth span (eq. 7)
  TrianglesPerLayer,    // foliage triangles per layer
  Finish,               // heights from the root line, the plants' rectangles; scratch freed
};

// The placement for one view (paper 3.2: depth range of the leaf roots, layer boundaries, per-layer
// bounds and the eq. 7 root line), resumable so that a spread re-slice can run it a few ms a frame.
struct PlacementJob {
  LayerView view;  // the camera the placement (and the set it draws) is for
  std::vector<InstanceRun> runs;  // the instances that camera sees (render/layer_instances.h)
  // Per visible copy (in runs' order): the frame's view-depth row and clip rows x, y, w composed with
  // its transform (they take model-space points).
  std::vector<glm::vec4> depthRows, rowsX, rowsY, rowsW;
  // Per visible copy its species, and where its leaves' and plants' entries start in leafDepth /
  // leafLayer and plantTop (one past the last copy: the totals); per species, its visible copies
  // (indices into the rows above). A copy visits only its own species' leaves and vertices.
  std::vector<uint32_t> copySpecies;
  std::vector<size_t> leafBase, plantBase;
  std::vector<InstanceRun> speciesVisible;
  glm::vec2 pixelLo{INFINITY}, pixelHi{-INFINITY};  // the vertices' projected extent, pixels (unclipped)
  bool behind = false;                               // a vertex is behind the camera (no extent)
  glm::vec2 rigidDepth{INFINITY, -INFINITY};         // view depths of the rigid vertices (near, far)
  gpu::LayerFrame frame{};
  std::vector<LayerInfo> layers;
  std::vector<float> leafDepth;
  std::vector<uint8_t> leafLayer;
  std::vector<float> plantTop;  // (plantBase[copy] + plant of its species) x layers: the leaves' highest row, per-plant roots
  float zMin = 0, zMax = 0, bottom = 0;
  PlacementStage stage = PlacementStage::RootDepths;
  size_t next = 0;       // the stage's next item (chunk, leaf, or vertex / index of the host mesh)
  uint32_t chunk = 0;    // the chunk holding item `next` (vertex and index stages)
  double ms = 0;  // CPU time spent so far
};

// The impostor cut of one placement (CanopyDesc.impostors; render/impostors.h) as draws: the cut, its
// foliage as chunk parts, its impostor list (the opaque ones first, uploaded with the frame block).
struct ImpostorDraws {
  ImpostorCut cut;
  std::vector<ChunkPart> parts;
  std::vector<InstanceRun> wholeRuns;  // with copies: the cut's whole copies (its parts with copies.count 0 draw them)
  std::vector<gpu::ImpostorInstance> instances;
  uint32_t opaque = 0;
};

// What the visible layers show: the placement's frame block (uploaded to frameBuffer) and layers,
// and the impostor cut it draws.
struct VisibleLayers {
  // The slice camera: the view the visible images were drawn from (docs/design.md "Layers:
  // reprojection"); the composite maps the current camera's pixels into its pixels.
  LayerView view;
  PixelExtent extent;  // where the vegetation's vertices project in that camera (unclipped; reprojection policy)
  glm::vec2 rigidDepth{INFINITY, -INFINITY};  // the rigid vertices' view depths there (the background's depth search)
  std::vector<InstanceRun> runs;  // the instances drawn into the visible set
  gpu::LayerFrame frame{};
  std::vector<LayerInfo> layers;
  Buffer frameBuffer;
  ImpostorDraws impostors;
};

using PlacementClock = std::chrono::steady_clock;
// Starts a placement for `view`; advancePlacement runs it until done or past `deadline` (null: to
// the end); placeForView runs one to the end into `visible`.
void beginPlacement(const PlacementInputs& in, const LayerView& view, PlacementJob& job);
// How many species have a visible copy in the placement.
uint32_t visibleSpecies(const PlacementJob& job);
// What a finished placement measured of its vertices, for the reprojection: their pixel extent
// and the rigid ones' depths.
void takeVertexBounds(VisibleLayers& v, const PlacementJob& job);
Status advancePlacement(const PlacementInputs& in, PlacementJob& job, const PlacementClock::time_point* deadline, bool* done);
Status placeForView(const PlacementInputs& in, const LayerView& view, VisibleLayers& visible, LayerStats& stats);
// The impostor cut of the placement `frame` for `view` and its visible copies `runs` (nothing when
// impostors are off): the visible set's at a re-slice at once, a spread re-slice's when its
// placement is done.
void planImpostorCut(const PlacementInputs& in, const gpu::LayerFrame& frame, const LayerView& view,
                     const std::vector<InstanceRun>& runs, ImpostorDraws* out, LayerStats& stats);

// The pixels of a `width` x `height` target the world box [boundsMin, boundsMax] can cover seen
// through each of `viewProjs` (the visible placement's, and a spread re-slice's next set), 2 pixels
// of margin; the whole target when a corner is behind a camera.
VkRect2D projectedFootprint(const std::vector<glm::mat4>& viewProjs, const glm::vec3& boundsMin, const glm::vec3& boundsMax,
                            uint32_t width, uint32_t height);

// The frame block's camera and lighting for `view` (no placement): the layers' start and the
// per-vertex baseline's every frame.
gpu::LayerFrame cameraFrame(const LayerSettings& settings, const LayerView& view);
// LayerFrame.halfResolution for the settings: the farthest halfResolutionLayers layers' bits.
uint32_t halfResolutionMask(const LayerSettings& settings);

}  // namespace canopy
