#pragma once
// Image-based multiresolution foliage (seed 002, Lluch et al.; issue 18; docs/design.md
// "Impostors"). At creation (CanopyDesc.impostors.enable):
//   1. the foliage's box hierarchy (render/foliage_boxes.h: the generator's L-system boxes, else a
//      k-d split of the leaf roots), and the foliage's GPU triangle order laid out box by box in
//      depth-first order, so that every box's own leaves and every box's subtree are one contiguous
//      triangle run per material (a cut through the hierarchy is a short list of draw ranges);
//   2. the bake: per box of the top levels, orthographic views of its subtree's leaves
//      (shared/impostor.h: the six diagonal planes, or those and the six faces: ImpostorDesc.views),
//      colour and depth, drawn once on the GPU with the layers' own shading into a tiled atlas
//      within a memory budget.
// At a re-slice (LayerSettings.impostors): the cut for the view (impostorCut), its impostors drawn
// into the layers (each in the layer of its box's root depth), then the leaves of the boxes left.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <vulkan/vulkan.h>

#include <canopy/canopy_params.h>

#include "engine/graphics_pipeline.h"
#include "engine/memory.h"
#include "engine/status.h"
#include "engine/transfer.h"
#include "render/model.h"
#include "render/foliage_boxes.h"
#include "render/leaf_roots.h"
#include "shared/impostor.h"

namespace canopy {

constexpr uint32_t kNoTile = 0xffffffffu;

struct ImpostorNode {
  uint32_t parent = 0xffffffffu;  // an earlier node (depth-first preorder); none for the root
  uint32_t level = 0;
  uint32_t subtreeEnd = 0;        // the first node after its subtree (preorder)
  glm::vec3 center{0}, half{0};   // bounds of its subtree's foliage
  glm::vec3 root{0};              // mean of its subtree's leaf roots (its layer)
  float radius = 0;               // half the bounds' diagonal
  uint32_t firstTile = kNoTile;   // baked views, or kNoTile
  uint32_t gpuIndex = kNoTile;    // its ImpostorBox entry (baked nodes only)
};

struct Impostors {
  bool enabled = false;
  std::vector<ImpostorNode> nodes;       // depth-first preorder
  // Per species its nodes [speciesNodes[s], speciesNodes[s + 1]) (a forest of its own boxes, in
  // its model's space; docs/design.md "Impostors: copies and species").
  std::vector<uint32_t> speciesNodes;
  std::vector<uint32_t> speciesBaked;    // per species, its nodes with views
  uint32_t materials = 0;                // model materials (runs are per material)
  // Per node and material: own leaves' run [ownFirst, ownFirst + ownCount) and the subtree's run
  // [ownFirst, subtreeEnd) in GPU triangle numbers (3 values per node and material).
  std::vector<uint64_t> runs;
  uint64_t ownFirst(uint32_t node, uint32_t m) const { return runs[(size_t(node) * materials + m) * 3 + 0]; }
  uint64_t ownCount(uint32_t node, uint32_t m) const { return runs[(size_t(node) * materials + m) * 3 + 1]; }
  uint64_t subtreeEnd(uint32_t node, uint32_t m) const { return runs[(size_t(node) * materials + m) * 3 + 2]; }
  uint32_t firstView = IMPOSTOR_FIRST_VIEW_DIAGONAL;  // the stored views [firstView, IMPOSTOR_VIEWS)
  uint32_t viewCount() const { return IMPOSTOR_VIEWS - firstView; }
  uint32_t baked = 0, tileSize = 0, tilesPerRow = 0, rowsPerLayer = 0, atlasLayers = 0, tiles = 0;
  uint32_t tilesPerLayer() const { return tilesPerRow * rowsPerLayer; }
  Image color, depth;                                   // the atlas (2D arrays)
  std::vector<VkImageView> colorLayerViews, depthLayerViews;
  Buffer boxTable, instances;                            // gpu::ImpostorBox per baked node; this re-slice's list
  Buffer identityCopy;                                   // the bake's copies' table: one copy at the model's origin
  PreparedList pendingUploads;  // the bake (or the cached views' upload) and the box table, not yet recorded (host devices)
  uint32_t instanceCapacity = 0;
  GraphicsPipeline bake, layered, layeredFade, perLayer, perLayerFade;
  GraphicsPipeline layeredHalf, layeredHalfFade;  // single pass with layers at half resolution (clip distances)
  VkSampler linearSampler = VK_NULL_HANDLE, nearestSampler = VK_NULL_HANDLE;
  double bakeMs = 0;
  uint64_t bytes = 0;
  // The bake's file cache (beside the leaf-root cache; empty path: off): the key of everything the
  // views are drawn from but the bake frames (added by the bake), and what became of it.
  std::string cachePath;
  uint64_t cacheKey = 0;
  uint64_t cacheMaxBytes = 0;  // the folder's cap (CanopyDesc.cacheMaxBytes; 0: none)
  bool cacheHit = false;
  std::string cacheNote = "cache off";
};

// Where a model's baked views are cached (the leaf-root cache's folder and naming, ".impostors").
std::string impostorCachePath(const std::string& modelPath, const std::string& cacheDir);
// The part of the cache key that comes from the model and the layout: mesh, materials, images,
// hierarchy runs, node bounds and the atlas plan.
uint64_t impostorModelKey(const Impostors& imp, const VegetationModel& model, const std::vector<uint64_t>& meshHashes);

constexpr uint32_t kEveryCopy = 0xffffffffu;

// What a re-slice draws with impostors on (computed by impostorCut with the placement).
struct ImpostorCut {
  bool active = false;
  std::vector<gpu::ImpostorInstance> opaque, fading;  // weight 1 / inside the band
  // A foliage run (GPU triangle numbers) of one copy, or (copy = kEveryCopy) of the copies the
  // draw names: all the visible ones without copies, `wholeCopies` with them.
  struct Run { uint32_t material; uint64_t first, count; float weight; uint32_t level; uint32_t copy = kEveryCopy; };
  std::vector<Run> geometry;                          // foliage runs to draw
  // With copies: those whose cut is their whole foliage at full weight (no impostor), ascending,
  // drawn instanced by their species' whole runs; every other copy by runs of its own.
  bool perCopy = false;
  std::vector<uint32_t> wholeCopies;
  uint64_t triangles = 0;
};

// Step 1: the hierarchy and the foliage's GPU order. `materialStart[m]` is where material m's
// foliage triangles start in GPU order; `order` (GPU -> model triangle) gets its foliage part
// rewritten box by box. Errors name the model and what is wrong.
// `hierarchy`: the boxes (render/foliage_boxes.h), each species' a forest of its own, species after
// species; `speciesBoxes[s]` is where species s's boxes start (with the end appended).
Status buildImpostorOrder(const VegetationModel& m, const BoxHierarchy& hierarchy, const std::vector<uint32_t>& speciesBoxes,
                          const LeafRoots& roots, const std::vector<uint64_t>& materialStart, Impostors* imp,
                          std::vector<uint32_t>* order);
// One model's box hierarchy: its own (the generator's L-system boxes, refined where a box holds
// more than desc.maxLeavesPerBox leaves of its own), else a k-d split of its leaf roots.
Status buildFoliageBoxes(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                         const ImpostorDesc& desc, BoxHierarchy* out);

// Which nodes get views within desc's budget and tile size: fills firstTile, gpuIndex, baked,
// tiles, tileSize, tilesPerRow, rowsPerLayer, atlasLayers, bytes (the atlas as allocated, within
// the budget). Errors name the budget.
Status planImpostorAtlas(const ImpostorDesc& desc, uint32_t maxImageSide, uint32_t maxArrayLayers, Impostors* imp);
// The volume of n's box over its parent's (ImpostorDesc.minVolumeRatio).
float volumeRatio(const ImpostorNode& parent, const ImpostorNode& n);

// The orthographic view-projection of node `box`'s view k (Vulkan clip space, depth 0 at the
// side the view looks from): the bake's camera, and what the tests render directly.
glm::mat4 impostorViewProj(const ImpostorNode& box, uint32_t k);

// A visible copy the cut is made for: its index in the copies' table, species and transform.
struct ImpostorCopy {
  uint32_t index = 0, species = 0;
  glm::mat4 model{1.0f};
};

struct ImpostorCutInput {
  ImpostorSettings settings;
  std::vector<ImpostorCopy> copies;  // empty: the model itself at the origin (no copies)
  glm::vec4 depthRow{0};    // view depth of a world point
  float pixelScale = 1;     // pixels per world unit at view depth 1 (perspective) or everywhere (orthographic)
  bool perspective = true;
  float farStart = 0, farBand = 0;  // FarRegion: depth ramp
};
// The cut through the hierarchy for one view: per node its impostor share a (size and, for
// FarRegion, depth ramps; 0 for nodes without views), W = a x (what its ancestors left), its own
// leaves drawn with what is left after it; subtrees left with nothing are skipped. With copies,
// per copy through its species' nodes, seen through its transform.
void impostorCut(const Impostors& imp, const ImpostorCutInput& in, ImpostorCut* out);

}  // namespace canopy
