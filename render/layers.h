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
#include <cstdint>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/graphics_pipeline.h"
#include "engine/memory.h"
#include "engine/render_graph.h"
#include "engine/status.h"
#include "render/camera.h"
#include "render/gltf_loader.h"
#include "render/layer_layout.h"
#include "render/leaf_roots.h"
#include "render/material_split.h"
#include "shared/layers.h"

namespace canopy {
struct Device;

enum class SliceMode {
  LeafRoots,  // a leaf goes whole into the layer of its root (default; needs the preprocessing)
  Geometry,   // the paper's simple segmentation: near/far planes on each fragment's own depth
              // (leaves crossing a boundary are cut; always drawn one layer at a time)
};
enum class LayerDrawMode { Auto, SinglePass, PerLayer };  // Auto: single pass when shaderOutputLayer
enum class ReslicePolicy { OnViewChange, EveryFrame };

struct LayerSettings {
  LayerLayout layout;                    // default 5(3-1-1)
  RegionSplit regions;                   // default thirds of the depth range
  SliceMode slice = SliceMode::LeafRoots;
  LayerDrawMode draw = LayerDrawMode::Auto;
  ReslicePolicy policy = ReslicePolicy::OnViewChange;
  float moveThreshold = 0.01f;           // camera travel that triggers a rebuild, as a fraction of
                                         // the model's bounding radius, [0, 10]
  float turnThresholdDegrees = 0.5f;     // camera turn (forward or up) that triggers one, [0, 180]
  glm::vec3 lightDirection{0.35f, 0.8f, 0.5f};  // towards the light, world space (normalised here)
  glm::vec3 lightColor{1.0f};            // linear RGB, each >= 0
  float ambient = 0.35f;                 // [0, 1]
  bool operator==(const LayerSettings&) const = default;
};
Status validateLayerSettings(const LayerSettings& settings);

struct LayeredVegetationDesc {
  uint32_t width = 1024, height = 768;   // layer resolution, 1..16384 each
  VkFormat colorFormat = VK_FORMAT_R16G16B16A16_SFLOAT;  // or VK_FORMAT_R8G8B8A8_UNORM
  MaterialSplitOptions split;
  LeafRootOptions roots;
  bool useRootCache = true;   // read/write leafRootCachePath(model.path, rootCacheDir) (skipped for an empty path)
  std::string rootCacheDir;   // empty: beside the model
  bool writeIds = false;      // also an R32G32_UINT array per layer: (leaf + 1, triangle + 1), 0 = none
  rg::Use restUse = rg::Use::FragmentSampled;  // how the layer images are left for their readers
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

struct LayerStats {
  double preprocessMs = 0;    // material split + leaf roots (or cache read)
  bool rootCacheHit = false;
  std::string rootCacheNote;  // why the cache was not used, or where it was written
  uint32_t leafCount = 0;
  uint64_t foliageTriangles = 0, rigidTriangles = 0;
  bool singlePass = false;    // the draw mode in use
  uint64_t viewUpdates = 0;   // updateLayerView() calls
  uint64_t rebuilds = 0;      // of which led to a rebuild
  std::string lastRebuildReason;
  double lastPlacementMs = 0; // CPU time of the last placement (depth range, per-layer bounds)
};

struct LayerDraw {
  uint32_t material = 0;
  uint32_t firstIndex = 0, indexCount = 0;
};

struct LayeredVegetation {
  Device* device = nullptr;
  LayeredVegetationDesc desc;
  MaterialSplit split;
  std::vector<ModelMaterial> materials;
  glm::vec3 boundsMin{0}, boundsMax{0};
  // CPU copies for placement: positions, per-vertex leaf, per-leaf root position.
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> leafOfVertex;
  std::vector<glm::vec3> leafRootPosition;
  std::vector<uint32_t> indices;          // GPU order (foliage by material, then rigid)
  std::vector<uint32_t> gpuToModelTriangle;
  std::vector<LayerDraw> foliageDraws, rigidDraws;
  // GPU mesh and materials.
  Buffer vertices, indexBuffer, leafRoots, frameBuffer;
  std::vector<Image> textures;            // per model image (sRGB), plus a white one last
  VkSampler sampler = VK_NULL_HANDLE;
  // Targets: persistent between rebuilds.
  Image color, depth, ids, backgroundColor, backgroundDepth;
  std::vector<VkImageView> colorLayerViews, depthLayerViews, idsLayerViews;  // per-layer (fallback)
  GraphicsPipeline layered, perLayer, background;
  // State.
  LayerSettings settings;
  bool singlePass = false;
  bool rebuildPending = false;
  bool haveView = false;
  bool settingsChanged = false;
  LayerView lastRebuildView;
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
Status setLayerSettings(LayeredVegetation& lv, const LayerSettings& settings);

// Changes the layer images' size (the host's target was resized): recreates the layer and
// background images (a graph holding them must be rebuilt) and marks the layers for a rebuild;
// the mesh, leaf roots and settings are kept.
Status setLayerTargetSize(LayeredVegetation& lv, uint32_t width, uint32_t height);

// Applies the re-slicing policy for the new view: *rebuild tells whether the next recorded layer
// passes will redraw the layers (then the placement has been recomputed for `view`).
Status updateLayerView(LayeredVegetation& lv, const LayerView& view, bool* rebuild);

struct LayerResources {
  rg::ResourceId color = rg::kInvalidResource, depth = rg::kInvalidResource, ids = rg::kInvalidResource;
  rg::ResourceId backgroundColor = rg::kInvalidResource, backgroundDepth = rg::kInvalidResource;
};
// Adds "layers: frame constants", "layers: foliage" and "layers: background" with the layer
// images imported (and bound) in desc.restUse. The passes draw only when a rebuild is pending.
Status addLayerPasses(LayeredVegetation& lv, rg::RenderGraph& graph, LayerResources* out);

// Reads the layer images back (tests and tools): premultiplied linear RGBA as float, depth, ids.
Status readLayerColor(LayeredVegetation& lv, uint32_t layer, std::vector<glm::vec4>* rgba);
Status readLayerDepth(LayeredVegetation& lv, uint32_t layer, std::vector<float>* depth);
Status readLayerIds(LayeredVegetation& lv, uint32_t layer, std::vector<glm::uvec2>* ids);
Status readBackground(LayeredVegetation& lv, std::vector<glm::vec4>* rgba, std::vector<float>* depth);

}  // namespace canopy
