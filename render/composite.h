#pragma once
// Inverse warp + compositing into the host's targets (paper 3.2, 3.6; docs/design.md "Conventions where the paper is silent", compositing):
// one fused full-screen pass samples every layer at p - d_i(p), composites the layers front to
// back with the rigid background and the host's scene inserted by depth, blends the premultiplied
// result over the host's colour, writes the depth of the nearest layer where its alpha >= 0.5 (else
// the trunk's, else leaves the scene's) and, optionally, motion vectors.
//
// Host targets: colour in any blendable colour-attachment format; depth D32_SFLOAT or D16_UNORM
// with SAMPLED usage (a small compute pass copies it first, so layers behind the host's geometry
// are hidden per layer); motion, when wanted, an R16G16_SFLOAT or R32G32_SFLOAT attachment that is
// written only where the vegetation is frontmost (current minus previous position, pixels, y down:
// the displacement's change and, between re-slices, the camera's motion; docs/design.md "Layers:
// reprojection") and left alone elsewhere.
#include <cstdint>
#include <vulkan/vulkan.h>

#include <canopy/canopy_params.h>

#include "engine/graphics_pipeline.h"
#include "engine/memory.h"
#include "engine/pipeline.h"
#include "engine/render_graph.h"
#include "engine/status.h"
#include "render/layer_passes.h"
#include "shared/anim.h"
#include "shared/composite.h"

namespace canopy {
struct Device;
struct LayerDynamics;

// CompositeDebugView and CompositeParams: <canopy/canopy_params.h> (values = the shader's constants).
static_assert(uint32_t(CompositeDebugView::None) == COMPOSITE_DEBUG_NONE && uint32_t(CompositeDebugView::Layers) == COMPOSITE_DEBUG_LAYERS &&
              uint32_t(CompositeDebugView::Velocity) == COMPOSITE_DEBUG_VELOCITY && uint32_t(CompositeDebugView::Grid) == COMPOSITE_DEBUG_GRID);
Status validateCompositeParams(const CompositeParams& params);

struct CompositorDesc {
  uint32_t width = 0, height = 0;                  // the host's targets, pixels
  // The guard band (docs/design.md "Layers: guard band"): the layer images are the output plus
  // guardX / guardY pixels on each side (multiples of COMPOSITE_TILE); the warp grid and the
  // occupancy are over the layer images.
  uint32_t guardX = 0, guardY = 0;
  VkFormat colorFormat = VK_FORMAT_R8G8B8A8_UNORM; // host colour target
  VkFormat depthFormat = VK_FORMAT_D32_SFLOAT;     // host depth target (sampled usage required)
  VkFormat motionFormat = VK_FORMAT_UNDEFINED;     // UNDEFINED: no motion output
  bool reverseZ = false;                           // the host's depth is reverse-Z (1 = near)
  uint32_t maxLayers = CANOPY_MAX_LAYERS;
  uint32_t minCellSize = 8;                        // smallest warp-grid cell (sizes the displacement image)
  // Compute path: listed 8x8 tiles per workgroup of the tile kernel, 1..64; 0 = by device class
  // (16 on CPU devices, where a workgroup launch costs more than an 8x8 tile's pixels; 1 on GPUs).
  uint32_t tilesPerGroup = 0;
};
// Checks formats against the device (blendable colour attachment, sampleable depth attachment).
Status validateCompositorDesc(Device& device, const CompositorDesc& desc);
// The layer images' size: the output plus the guard band on each side.
inline uint32_t compositorLayerWidth(const CompositorDesc& d) { return d.width + 2 * d.guardX; }
inline uint32_t compositorLayerHeight(const CompositorDesc& d) { return d.height + 2 * d.guardY; }

struct Compositor {
  Device* device = nullptr;
  CompositorDesc desc;
  GraphicsPipeline composite;
  ComputePipeline occupancyPipeline, occupancySumsPipeline, sceneDepthPipeline;
  // Compute path (CompositePath::Compute): displacement image, classification, tile kernel, resolve.
  bool computeAvailable = false;  // RGBA32F storage + linear filtering on this device
  bool computeThisFrame = false;  // prepareComposite's choice (debug views use the fragment path)
  ComputePipeline displacementPipeline, classifyPipeline;
  // The tile kernel per variant (COMPOSITE_VARIANT_*: still or reprojected, bilinear or nearest),
  // created when prepareComposite first needs it: the two of the bilinear setting in use.
  ComputePipeline tilesPipelines[COMPOSITE_TILE_VARIANTS];
  GraphicsPipeline resolve;
  Image displacementImage;        // RGBA32F array: (d_i, previous d_i) per warp-grid corner
  Image composed;  // the tile kernel's result per pixel, RGBA32UI (compositePackPixel, shared/composite.h)
  Buffer tileList;                // CompositeTileHeader + one uvec2 per screen tile
  VkSampler displacementSampler = VK_NULL_HANDLE;  // linear, clamp to edge
  Buffer occupancy;   // (maxLayers + 1) x layer tiles uint: 1 where the tile (+1 px) holds foliage;
                      // slot layerCount: the rigid background
  Buffer occupancySums;  // its summed-area table per slot (compositeSumsEntries), read by the classification
  Buffer sceneDepth;  // width x height float: the host's depth before the composite
  Buffer viewBuffer;    // gpu::CompositeView (reprojection), rewritten by the frames that reproject
  gpu::CompositeView view{};
  Buffer debugStandIn;  // bound for the debug views' inputs when the graph has none
  bool hasDebugSources = false;
  VkSampler linear = VK_NULL_HANDLE, nearest = VK_NULL_HANDLE, depthSampler = VK_NULL_HANDLE;
  CompositeParams params;
  gpu::CompositePush push{};     // the next recorded frame's constants (prepareComposite)
  bool occupancyPending = true;  // recompute occupancy (after a layer rebuild)
  bool occupancyUnitePending = false;  // OR the next set's occupancy in (after any recompute)
};
Status createCompositor(Device& device, const CompositorDesc& desc, Compositor* out);
void destroyCompositor(Compositor& compositor);

// Fixes the next recorded composite: layer count and warp grid from the dynamics frame, the levers
// from `params`, whether the layers were rebuilt (occupancy) and whether the previous displacement
// is last frame's (motion vectors).
// `foliageRect` (layer pixels; null: the whole layer image) bounds where the layers can hold foliage: the
// occupancy pass reads only those tiles.
// `uniteNext`: OR the next layer set's occupancy (LayerResources.nextColor; a spread re-slice whose
// last slice is drawn this frame) into the current one, so it holds for the whole cross-fade.
Status prepareComposite(Compositor& compositor, const CompositeParams& params, const gpu::AnimFrame& anim,
                        bool hasBackground, bool layersRebuilt, bool motionValid, const VkRect2D* foliageRect = nullptr,
                        bool uniteNext = false);

// Shows the layers from another camera than the slice camera they were drawn with (docs/design.md
// "Layers: reprojection"): `view` for the next recorded composite, or null (the current camera is
// the slice camera: layer pixel = output pixel plus the guard band). Call after prepareComposite.
void setCompositeReprojection(Compositor& compositor, const gpu::CompositeView* view);

struct CompositeTargets {
  rg::ResourceId color = rg::kInvalidResource;   // host colour (blended over)
  rg::ResourceId depth = rg::kInvalidResource;   // host depth (read, then written)
  rg::ResourceId motion = rg::kInvalidResource;  // optional
  // The host's viewport as whole pixels (CanopyCamera.viewport), read when the pass records: drawn
  // inside it only. Null: the whole targets.
  const VkRect2D* scissor = nullptr;
};
// What the velocity debug view reads: the dynamics frame and the simulation's tiled field.
struct CompositeDebugSources {
  rg::ResourceId animFrame = rg::kInvalidResource;
  rg::ResourceId tiled = rg::kInvalidResource;
};
// Begins dynamic rendering into the host's targets with their contents kept (colour and motion
// blended over, depth tested and written), a full viewport and the host's scissor: the composite's resolve and
// fragment path, and the per-vertex baseline's draw.
void beginHostRendering(rg::PassContext& pass, const CompositeTargets& targets, uint32_t width, uint32_t height,
                        bool motion);

// Adds "composite: occupancy" and "composite: occupancy sums", then the fragment path ("composite: scene depth", "composite: warp +
// composite") and the compute path ("composite: displacement image", "composite: tile list reset",
// "composite: classify", "composite: warp + composite (tiles)", "composite: resolve"); each frame
// records one of the two (prepareComposite).
// `layers` are the layer images (addLayerPasses), `displacement` and `previous` the dynamics'
// buffers (addDynamicsPasses); `debug` is needed only for CompositeDebugView::Velocity.
Status addCompositePasses(Compositor& compositor, rg::RenderGraph& graph, const LayerResources& layers,
                          rg::ResourceId displacement, rg::ResourceId previous, const CompositeTargets& targets,
                          const CompositeDebugSources& debug = {});

}  // namespace canopy
