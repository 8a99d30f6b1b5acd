#pragma once
// Depth-sliced vegetation layers (paper 3.2): the foliage is drawn once per view change into an
// n-layer 2D-array colour image (premultiplied RGBA, linear) plus a depth array, each leaf whole
// into the layer of its root's depth; the rigid parts (trunk, branches) are drawn into their own
// colour + depth, the background. Single pass with gl_Layer from the vertex shader where the
// device has shaderOutputLayer, else one draw per layer clipped to the layer's near/far planes.
//
// Usage: createLayeredVegetation() once per model; every frame updateLayerView() (applies the
// re-slicing policy and, when a rebuild is due, places the layers); addLayerPasses() adds the
// draws to a render graph (they record only when a rebuild is due). The layer images stay in
// desc.restUse between rebuilds.
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/graphics_pipeline.h"
#include "engine/memory.h"
#include "engine/render_graph.h"
#include "engine/status.h"
#include "engine/transfer.h"
#include "engine/camera.h"
#include "render/gltf_loader.h"
#include "render/impostors.h"
#include "render/layer_layout.h"
#include "render/leaf_roots.h"
#include "render/material_split.h"
#include "render/mesh_chunks.h"
#include "shared/layers.h"

namespace canopy {
struct Device;

// SliceMode, LayerDrawMode, ReslicePolicy, LayerSettings and LayerStats: <canopy/canopy.h>.
Status validateLayerSettings(const LayerSettings& settings);

struct LayeredVegetationDesc {
  uint32_t width = 1024, height = 768;   // layer resolution, 1..16384 each
  VkFormat colorFormat = VK_FORMAT_R16G16B16A16_SFLOAT;  // or VK_FORMAT_R8G8B8A8_UNORM
  MaterialSplitOptions split;
  LeafRootOptions roots;
  // The leaf-root cache folder: leafRootCachePath(model.path, rootCacheDir) is read and written
  // there. Empty (the default), or a model without a path: no file is touched.
  std::string rootCacheDir;
  uint64_t cacheMaxBytes = 0;  // CanopyDesc.cacheMaxBytes (0: no cap)
  bool writeIds = false;      // also an R32G32_UINT array per layer: (leaf + 1, triangle + 1), 0 = none
  uint32_t maxChunkVertices = kMaxChunkVertices;  // distinct vertices per mesh chunk, 3..65535 (tests cut small chunks)
  // Spread re-slicing: every drawing frame draws this many triangles instead of what the budget and
  // the measured drawing rate give (tests: a deterministic number of slices). 0: measured.
  uint32_t fixedSliceTriangles = 0;
  // Device memory (issue 16; docs/design.md "Layers: mesh budget and staging ring"): the bytes of
  // buffers and images this object may allocate; 0: no limit (the mesh is resident). When the
  // compact mesh does not fit beside the textures and both layer sets, it stays in host memory and
  // every re-slice streams it through a host-visible ring of about `stagingRingBytes` (one segment
  // per frame in flight), a slice per frame.
  uint64_t deviceMemoryBudget = 0;
  uint64_t stagingRingBytes = 64ull << 20;
  rg::Use restUse = rg::Use::FragmentSampled;  // how the layer images are left for their readers
  // Keep the model's branch hierarchy with the compact mesh (CompactMesh::bend) for the per-vertex
  // wind baseline; the mesh must then be resident (refused, naming the budget, otherwise).
  bool keepBend = false;
  // The foliage's box hierarchy and its baked views (render/impostors.h; needs a resident mesh).
  ImpostorDesc impostors;
  LayerSettings settings;
  Progress progress;          // optional: "leaf roots" and "vertices" while creating (big meshes)
};

struct LayerInfo {
  LayerSlab slab;             // view-depth range, representative depth, L_i
  float top = 0;              // highest pixel row (y down) of the layer's foliage
  float rootLineY = 0;        // pixel row of the vegetation's root line (bottom of its projected
                              // bounding box; the same for every layer: paper eq. 7)
  float height = 1;           // rootLineY - top, at least 1 pixel (h of eq. 7)
  uint32_t leaves = 0;        // leaves whose root is in the layer (CPU count)
  uint64_t triangles = 0;
};

// The second layer set a spread re-slice draws into (LayerSettings.rebuildBudgetMs > 0), rested
// in FragmentSampled for the cross-fade that copies it into the visible set.
struct LayerTargetSet {
  Image color, depth, backgroundColor, backgroundDepth;
  std::vector<VkImageView> colorLayerViews, depthLayerViews;  // per layer (per-layer draw path)
};

// The placement for one view (paper 3.2: depth range of the leaf roots, layer boundaries, per-layer
// bounds and the eq. 7 root line), resumable so that a spread re-slice can run it a few ms a frame.
struct PlacementJob {
  gpu::LayerFrame frame{};
  std::vector<LayerInfo> layers;
  std::vector<float> leafDepth;
  std::vector<uint8_t> leafLayer;
  float zMin = 0, zMax = 0, bottom = 0;
  uint32_t stage = 0;
  size_t next = 0;       // the stage's next item (chunk, leaf, or vertex / index of the host mesh)
  uint32_t chunk = 0;    // the chunk holding item `next` (vertex and index stages)
  double ms = 0;  // CPU time spent so far
};

// A part of a mesh chunk drawn by one spread slice; a streamed mesh has the chunk's vertices,
// the part's indices and the chunk's roots copied into this frame's ring segment at these element
// offsets (vertexOffset, firstIndex, root-table binding).
struct ChunkPart {
  uint32_t chunk = 0, firstTriangle = 0, triangleCount = 0;
  uint64_t ringVertex = 0, ringIndex = 0, ringRoot = 0;
  float weight = 1.0f;  // LayerDrawPush.lod.x: below 1 for a box fading towards its impostor
  uint32_t level = 0;   // the part's foliage box level (the debug view)
};

// How drawMaterials differs from a layer draw (the impostor bake, the debug view).
struct MeshDrawOptions {
  VkBuffer frame = VK_NULL_HANDLE;  // another frame block (binding 0) at frameOffset; null: the layers'
  VkDeviceSize frameOffset = 0;
  bool keepViewport = false;        // the caller has set viewport and scissor
  bool debugLevels = false;         // colour each part by its level (LayerDrawPush.lod.y)
};

// The staging ring of a streamed mesh (docs/design.md "Layers: mesh budget and staging ring"):
// lv.vertices, lv.indexBuffer and lv.leafRoots are host-visible rings of `segments` segments of
// these capacities (elements); frame F writes segment F mod segments, which the embedding contract
// (frames <= F - framesInFlight completed) leaves free.
struct MeshRing {
  uint32_t segments = 0;
  uint64_t vertexCapacity = 0, indexCapacity = 0, rootCapacity = 0;  // per segment
  uint32_t rootAlignment = 1;            // root blocks start at multiples of this many entries
  uint64_t counter = 0;                  // segment choice when no host frame numbers are seen (tools)
  uint64_t bytes = 0;                    // the three rings together
};

enum class SpreadPhase : uint32_t { Idle = 0, Placing = 1, Drawing = 2, CrossFading = 3 };  // = LayerStats.spreadPhase

// docs/design.md "Layers: spread re-slicing".
struct SpreadRebuild {
  SpreadPhase phase = SpreadPhase::Idle;
  PlacementJob job;
  uint32_t frames = 0;                 // frames since it started
  uint32_t cursorChunk = 0, cursorTriangle = 0;  // the next triangle to draw
  std::vector<ChunkPart> slice;        // this frame's draws into the next set
  bool sliceClears = false;            // this frame's slice is the first: clear the next set
  bool united = false;                 // the frame after the last slice unites the occupancy (no fade)
  uint32_t fadeStep = 0;               // 1..crossFadeFrames during the cross-fade (the last copies)
  bool fadeCopy = false;               // this frame's step is the last: copy the next set
  // Asked at once but the mesh is streamed: placement in one frame, slices as large as the ring
  // segment allows, and the copy without a fade in the frame of the last slice.
  bool immediate = false;
  std::vector<float> fadeWeights;      // this frame's LayerFadePush.weight per layer, then the
                                       // background; 0: not blended this frame
  std::vector<LayerInfo> fadeFrom;     // the visible placement when the fade started
};

// Sizes the spread slices: frame intervals (between updateLayerView calls) of frames without layer
// work give the still baseline; a drawing frame's interval above it is what its triangles cost.
struct SliceRateControl {
  std::chrono::steady_clock::time_point lastUpdate{};
  bool haveLast = false;
  enum class Work { None, Placement, Slice, Other } lastWork = Work::Other;
  uint64_t lastTriangles = 0;
  double lastPlacementMs = 0;          // CPU placement time of a Placement frame (taken off its interval)
  std::vector<double> stillMs;         // the last few still intervals (ring)
  uint32_t stillNext = 0;
  std::vector<double> rateSamples;     // the last few slices' triangles / cost (ring)
  uint32_t rateNext = 0;
  double trianglesPerMs = 2000.0;      // start: a slow CPU device's rate (lavapipe draws ~2000-4000/ms)
};

struct LayeredVegetation {
  Device* device = nullptr;
  LayeredVegetationDesc desc;
  MaterialSplit split;
  std::vector<ModelMaterial> materials;
  glm::vec3 boundsMin{0}, boundsMax{0};
  // The compact mesh in host memory (its chunks: `chunks`): the placement reads its decoded
  // positions and leaves (so the CPU places what the GPU draws, and no per-vertex copy of the
  // model is kept), and a streamed mesh's re-slices copy from it into the ring.
  CompactMesh hostMesh;
  uint32_t leafCount = 0;                 // model leaves (LayerLeafRoot.leaf < leafCount)
  std::vector<uint32_t> gpuToModelTriangle;  // with desc.writeIds only
  bool hasRigid = false;                  // the model has rigid triangles (a background to draw)
  std::vector<MeshChunk> chunks;          // the compact mesh's chunks, one draw each
  // GPU mesh and materials.
  Buffer vertices, indexBuffer, leafRoots, frameBuffer;
  Buffer bendVertices;                    // hostMesh.bend on the device (desc.keepBend and a hierarchy)
  std::vector<Image> textures;            // per model image (sRGB), plus a white one last
  VkSampler sampler = VK_NULL_HANDLE;
  // Targets: persistent between rebuilds.
  Image color, depth, ids, backgroundColor, backgroundDepth;
  std::vector<VkImageView> colorLayerViews, depthLayerViews, idsLayerViews;  // per-layer (fallback)
  GraphicsPipeline layered, perLayer, background;
  LayerTargetSet next;                    // spread re-slicing only
  GraphicsPipeline fade, fadeBackground;  // spread re-slicing only
  VkSampler nearestSampler = VK_NULL_HANDLE;
  // State.
  LayerSettings settings;
  bool singlePass = false;
  bool rebuildPending = false;
  bool haveView = false;
  bool settingsChanged = false;
  std::string forcedReason;  // re-slice at the next view update for this reason (a camera cut)
  bool forceImmediate = false;  // ... and at once
  bool streamed = false;        // the mesh is not resident: re-slices stream it through `ring`
  MeshRing ring;
  bool slicePending = false;    // this frame draws spread.slice into the next set
  bool fadePending = false;     // this frame runs a cross-fade step
  // Which tiles hold foliage may have changed this frame (the composite's occupancy): a re-slice at
  // once and the frame after a cross-fade recompute it; the frame after a spread re-slice's last
  // slice has the next set's tiles united in (occupancyUniteNext), which covers the cross-fade.
  bool occupancyDirty = false;
  bool occupancyUniteNext = false;
  bool occupancyRecomputeNext = false;  // the last fade step asks the frame after it
  bool occupancyRecomputeNow = false;   // a streamed re-slice asked at once copied its set in this frame
  SpreadRebuild spread;
  SliceRateControl rate;
  std::vector<PreparedWork> pendingClear;  // the targets' first clear, not yet recorded (host devices)
  LayerView lastRebuildView;
  // Impostors (CanopyDesc.impostors; render/impostors.h): the hierarchy and atlas, and what the
  // visible placement draws: its cut, the cut's foliage as chunk parts, its impostor list (the
  // opaque ones first, uploaded with the frame block).
  Impostors imp;
  ImpostorCut cut;
  std::vector<ChunkPart> cutParts;
  std::vector<gpu::ImpostorInstance> cutInstances;
  uint32_t cutOpaque = 0;
  gpu::LayerFrame frame{};
  std::vector<LayerInfo> layers;
  LayerStats stats;
};

// Splits materials, computes (or reads from the cache) the leaf roots, uploads the mesh and the
// textures, creates the targets and pipelines. `model` can be released afterwards.
Status createLayeredVegetation(Device& device, const VegetationModel& model, const LayeredVegetationDesc& desc,
                               LayeredVegetation* out);
void destroyLayeredVegetation(LayeredVegetation& lv);

// Changes settings at run time; a different layer count recreates the layer images (a graph
// holding them must be rebuilt), anything else only marks the layers for a rebuild.
// *targetsRecreated (optional) tells whether the layer images were recreated.
Status setLayerSettings(LayeredVegetation& lv, const LayerSettings& settings, bool* targetsRecreated = nullptr);

// Changes the layer images' size (the host's target was resized): recreates the layer and
// background images (a graph holding them must be rebuilt) and marks the layers for a rebuild;
// the mesh, leaf roots and settings are kept.
Status setLayerTargetSize(LayeredVegetation& lv, uint32_t width, uint32_t height);

// Applies the re-slicing policy for the new view and advances a spread re-slice: *changed tells
// whether the next recorded layer passes change the visible layers (a re-slice at once, whose
// placement has been recomputed for `view`, or a cross-fade step); lv.layers is then the placement
// they show.
Status updateLayerView(LayeredVegetation& lv, const LayerView& view, bool* changed);

// The pixels the visible layers (and, during a spread re-slice, the next set) can cover: the
// model's bounding box projected by the placements' views, 2 pixels of margin; the whole target
// when a corner is behind a camera.
VkRect2D layerFootprint(const LayeredVegetation& lv);

// The frame block's camera and lighting for `view` (no placement): the layers' start and the
// per-vertex baseline's every frame.
gpu::LayerFrame cameraFrame(const LayerSettings& settings, const LayerView& view);

// What the per-vertex baseline binds besides the layers' mesh and textures (render/per_vertex.cpp).
struct PerVertexBindings {
  VkBuffer frame = VK_NULL_HANDLE;         // its gpu::LayerFrame (binding 0, in place of the layers')
  VkBuffer bendFrame = VK_NULL_HANDLE;     // gpu::BendFrame (binding 6)
  VkBuffer branches = VK_NULL_HANDLE;      // gpu::BendBranch table (binding 7)
  VkBuffer bendVertices = VK_NULL_HANDLE;  // gpu::BendVertex per compact-mesh vertex (binding 8)
  VkBuffer tips = VK_NULL_HANDLE;          // the motion table (binding 9)
};
// Draws every chunk of the (resident) mesh, foliage then rigid, with `pipe` inside the caller's
// rendering: the per-vertex baseline's frame.
Status drawWholeMesh(LayeredVegetation& lv, VkCommandBuffer cmd, const GraphicsPipeline& pipe,
                     const PerVertexBindings& bindings);

// The pipeline description every draw of the compact mesh starts from (the layers, the background,
// the impostor bake, the per-vertex baseline): shaders/layers_common.glsl's six bindings, the
// LayerDrawPush constants, the LayerVertex attributes, premultiplied "over", layers.frag.
GraphicsPipelineDesc layerMeshPipelineDesc(VkFormat colorFormat, VkFormat depthFormat);

// For render/impostor_gpu.cpp: a 2D view of one layer of an array image; the mesh draw with chunk
// parts (drawMaterials); a GPU-order foliage triangle run cut at chunk borders into parts.
Status imageLayerView(Device& device, const Image& image, uint32_t layer, VkImageView* out);
Status drawMeshParts(LayeredVegetation& lv, VkCommandBuffer cmd, const GraphicsPipeline& pipe, uint32_t passKind,
                     uint32_t target, const std::vector<ChunkPart>& parts, const MeshDrawOptions& options);
void appendRunParts(const LayeredVegetation& lv, uint64_t first, uint64_t count, float weight, uint32_t level,
                    std::vector<ChunkPart>* out);

// The compact mesh in a render graph (issue 16's buffers, read-only after their upload): imported in
// its rest states and bound; readsMesh() declares a draw's reads. One place for the layer passes,
// the per-vertex baseline and the impostor bake.
struct MeshResources {
  rg::ResourceId vertices = rg::kInvalidResource, indices = rg::kInvalidResource, roots = rg::kInvalidResource;
};
Status importMesh(const LayeredVegetation& lv, rg::RenderGraph& graph, MeshResources* out);
rg::RenderGraph::PassBuilder& readsMesh(rg::RenderGraph::PassBuilder& pass, const MeshResources& mesh);

struct LayerResources {
  rg::ResourceId color = rg::kInvalidResource, depth = rg::kInvalidResource, ids = rg::kInvalidResource;
  rg::ResourceId backgroundColor = rg::kInvalidResource, backgroundDepth = rg::kInvalidResource;
  // The next set's colour (spread re-slicing only): the composite's occupancy unites it in.
  rg::ResourceId nextColor = rg::kInvalidResource, nextBackgroundColor = rg::kInvalidResource;
};
// Adds "layers: frame constants", "layers: foliage" and "layers: background" with the layer
// images imported (and bound) in desc.restUse, and with spread re-slicing "layers: spread slice"
// and "layers: cross-fade" (the next set imported in FragmentSampled). The passes draw only when
// updateLayerView planned that work for this frame.
Status addLayerPasses(LayeredVegetation& lv, rg::RenderGraph& graph, LayerResources* out);

// Reads the layer images back (tests and tools): premultiplied linear RGBA as float, depth, ids.
Status readLayerColor(LayeredVegetation& lv, uint32_t layer, std::vector<glm::vec4>* rgba);
Status readLayerDepth(LayeredVegetation& lv, uint32_t layer, std::vector<float>* depth);
Status readLayerIds(LayeredVegetation& lv, uint32_t layer, std::vector<glm::uvec2>* ids);
Status readBackground(LayeredVegetation& lv, std::vector<glm::vec4>* rgba, std::vector<float>* depth);

}  // namespace canopy
