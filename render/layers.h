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
//
// LayeredVegetation is its parts, one concern each, each in its own header (CONTRIBUTING.md):
// the mesh (render/layer_mesh.h), the layer images (render/layer_targets.h), the visible placement
// (render/layer_placement.h), the re-slice scheduler (render/reslice_scheduler.h), the impostors
// (render/impostors.h, render/impostor_gpu.h), the pipelines (below) and the statistics.
#include <cstdint>
#include <string>
#include <vulkan/vulkan.h>

#include "engine/graphics_pipeline.h"
#include "engine/render_graph.h"
#include "engine/status.h"
#include "render/impostors.h"
#include "render/layer_instances.h"
#include "render/layer_mesh.h"
#include "render/layer_passes.h"
#include "render/layer_placement.h"
#include "render/layer_targets.h"
#include "render/leaf_roots.h"
#include "render/model.h"
#include "render/reslice_scheduler.h"

namespace canopy {
struct Device;

// SliceMode, LayerDrawMode, ReslicePolicy, LayerSettings and LayerStats: <canopy/canopy_params.h>.
Status validateLayerSettings(const LayerSettings& settings);

// The vegetation's description: the mesh's (LayerMeshDesc, render/layer_mesh.h: material split,
// leaf roots and their cache, chunks, memory budget, per-vertex hierarchy, impostors) and the rest.
struct LayeredVegetationDesc : LayerMeshDesc {
  uint32_t width = 1024, height = 768;   // layer resolution, 1..16384 each (the guard band included)
  // The guard band (docs/design.md "Layers: guard band"): the layers show the output's view widened
  // by guardX / guardY pixels on each side (output = width - 2 guardX by height - 2 guardY); the
  // slice camera is guardedView(view) of the camera each update asks for.
  uint32_t guardX = 0, guardY = 0;
  VkFormat colorFormat = VK_FORMAT_R16G16B16A16_SFLOAT;  // or VK_FORMAT_R8G8B8A8_UNORM
  // Spread re-slicing: every drawing frame draws this many triangles instead of what the budget and
  // the measured drawing rate give (tests: a deterministic number of slices). 0: measured.
  uint32_t fixedSliceTriangles = 0;
  rg::Use restUse = rg::Use::FragmentSampled;  // how the layer images are left for their readers
  // The placed copies (docs/design.md "Instances"; render/layer_instances.h): transforms, tints,
  // wind phases, species; no models: one copy at the model's origin.
  InstanceInputs copies;
  LayerSettings settings;
};

// The layer and background draws' pipelines (single pass with gl_Layer, or one draw per layer),
// specialised for the shading inputs they may meet (`features`, LAYER_FEATURE_*: the model's
// materials and the settings' translucency model and level colours; docs/design.md "Layers: leaf
// shading", specialised pipelines).
struct LayerShadingPipelines {
  uint32_t features = 0;
  GraphicsPipeline layered, perLayer, background;
  // The single pass with layers at half resolution (layers_half.vert: clip distances keep each
  // such layer's quarter); the one-layer path does it in layers_clip.vert.
  GraphicsPipeline layeredHalf;
  // Shading once (docs/design.md "Layers: shading once"): each path's depth pre-pass and its
  // shading on the depth it left (EQUAL, early fragment tests); absent with the id output.
  struct ShadeOnce {
    GraphicsPipeline depth, shade;
  } layeredOnce, perLayerOnce, backgroundOnce, layeredHalfOnce;
};

// The draws' pipelines for the settings in force, those of other settings met before, and the
// cross-fade's.
struct LayerPipelines {
  LayerShadingPipelines shaded;
  // Kept, not destroyed, when the settings change the features: a frame in flight may still use
  // them, and a setting switched back finds them (at most four: translucency model x level colours).
  std::vector<LayerShadingPipelines> otherShading;
  GraphicsPipeline fade, fadeBackground;  // spread re-slicing only
  GraphicsPipeline fadeOver, fadeOverBackground;  // the cross-fade's first half: the new set laid over
  GraphicsPipeline fadeDepth;             // the cross-fade's depth merge (nearer of the two sets)
  VkSampler nearestSampler = VK_NULL_HANDLE;  // the cross-fade's reads (texel fetches)
  bool singlePass = false;
};

struct LayeredVegetation {
  Device* device = nullptr;
  LayeredVegetationDesc desc;
  LayerSettings settings;     // the settings in force (setLayerSettings)
  LayerMesh mesh;
  LayerInstances instances;   // the copies drawn, their world bounds
  LayerTargets targets;
  LayerPipelines pipelines;
  VisibleLayers visible;
  ResliceScheduler reslice;
  Impostors impostors;        // CanopyDesc.impostors: the hierarchy and the atlas
  LayerStats stats;
};

// drawsBackground(mesh, settings) of the vegetation (render/layer_mesh.h), and its opposite.
inline bool drawsBackground(const LayeredVegetation& lv) { return drawsBackground(lv.mesh, lv.settings); }
inline bool rigidFollows(const LayeredVegetation& lv) { return lv.mesh.hasRigid && !drawsBackground(lv); }

// Which shading inputs the layer draws may meet (LAYER_FEATURE_*, shared/layers.h): the model's
// material textures, the translucency model and the impostors' level colours of `s`. A clear bit
// compiles that input's code out of the fragment shader (layers_shade.glsl): lavapipe runs both
// sides of a branch under a lane mask, so an input no material has still costs every fragment
// (docs/lab/performance-notebook.md "Specialised shading").
uint32_t layerShadingFeatures(const LayeredVegetation& lv, const LayerSettings& s);

// Splits materials, computes (or reads from the cache) the leaf roots, uploads the mesh and the
// textures, creates the targets and pipelines. `model` can be released afterwards.
Status createLayeredVegetation(Device& device, const VegetationModel& model, const LayeredVegetationDesc& desc,
                               LayeredVegetation* out);
// The same for several species in one set of layers (render/species.h; desc.copies.species names
// each copy's): each species' mesh and textures stored once however many copies.
Status createLayeredVegetation(Device& device, const std::vector<SpeciesModel>& species, const LayeredVegetationDesc& desc,
                               LayeredVegetation* out);
void destroyLayeredVegetation(LayeredVegetation& lv);

// Work the parts prepared on a device that defers it (engine/transfer.h, submitOrDefer): the
// mesh's uploads, the impostors' bake and the targets' first clear, each kept in its part's list.
// Whether any waits, and its recording into the host's command buffer ahead of the frame's passes
// (the mesh before the bake that draws it).
bool layerWorkPending(const LayeredVegetation& lv);
Status flushLayerWork(LayeredVegetation& lv, VkCommandBuffer cmd);

// Applies the re-slicing policy for the new camera `view` and advances a spread re-slice
// (render/reslice_scheduler.h advanceReslice over the vegetation's parts): *changed tells whether
// the next recorded layer passes change the visible layers; lv.visible is then the placement they show.
Status updateLayerView(LayeredVegetation& lv, const LayerView& view, bool* changed);

// Changes settings at run time; a different layer count recreates the layer images (a graph
// holding them must be rebuilt), anything else only marks the layers for a rebuild.
// *targetsRecreated (optional) tells whether the layer images were recreated.
Status setLayerSettings(LayeredVegetation& lv, const LayerSettings& settings, bool* targetsRecreated = nullptr);

// Replaces the placed copies and re-slices at once (with impostors the list grows for them:
// record graphs must then be rebuilt).
Status setLayerInstances(LayeredVegetation& lv, const InstanceInputs& copies);

// Changes the layer images' size (the host's target was resized): recreates the layer and
// background images (a graph holding them must be rebuilt) and marks the layers for a rebuild;
// the mesh, leaf roots and settings are kept.
Status setLayerTargetSize(LayeredVegetation& lv, uint32_t width, uint32_t height, uint32_t guardX = 0, uint32_t guardY = 0);

// The output the layers are for (their size less the guard band) and the guard band, pixels.
inline glm::uvec2 layerOutputSize(const LayeredVegetation& lv) {
  return {lv.desc.width - 2 * lv.desc.guardX, lv.desc.height - 2 * lv.desc.guardY};
}
inline glm::uvec2 layerGuard(const LayeredVegetation& lv) { return {lv.desc.guardX, lv.desc.guardY}; }
// The slice camera for the camera `view` (the guard band's widened projection).
LayerView sliceCameraFor(const LayeredVegetation& lv, const LayerView& view);

// The parts' inputs as the vegetation holds them: what a mesh draw binds (the visible frame block),
// what a placement reads.
MeshDraw meshDraw(const LayeredVegetation& lv);
PlacementInputs placementInputs(const LayeredVegetation& lv);

// The pixels the visible layers (and, during a spread re-slice, the next set) can cover: the
// placed copies' bounding box projected by the placements' views (projectedFootprint).
VkRect2D layerFootprint(const LayeredVegetation& lv);

// Whether re-slices go through the next layer set: spread re-slicing or a streamed mesh.
bool usesNextSet(const LayeredVegetation& lv);

// The layer images read back (tests and tools; render/layer_targets.h): premultiplied linear RGBA
// as float, depth, ids.
inline Status readLayerColor(LayeredVegetation& lv, uint32_t layer, std::vector<glm::vec4>* rgba) {
  return readLayerColor(*lv.device, lv.targets, layer, rgba);
}
inline Status readLayerDepth(LayeredVegetation& lv, uint32_t layer, std::vector<float>* depth) {
  return readLayerDepth(*lv.device, lv.targets, layer, depth);
}
inline Status readLayerIds(LayeredVegetation& lv, uint32_t layer, std::vector<glm::uvec2>* ids) {
  return readLayerIds(*lv.device, lv.targets, layer, ids);
}
inline Status readBackground(LayeredVegetation& lv, std::vector<glm::vec4>* rgba, std::vector<float>* depth) {
  return readBackground(*lv.device, lv.targets, rgba, depth);
}

}  // namespace canopy
