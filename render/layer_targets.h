#pragma once
// The layer images (paper 3.2; docs/design.md "Per-frame data flow"): the n-layer colour and depth arrays, the optional id
// array, the background's colour and depth, their per-layer views, and the second set a spread
// re-slice draws into; their first clear, readback for tests and tools.
#include <cstdint>
#include <vector>
#include <glm/glm.hpp>
#include <vulkan/vulkan.h>

#include "engine/memory.h"
#include "engine/render_graph.h"
#include "engine/status.h"
#include "engine/transfer.h"

namespace canopy {
struct Device;
struct LayeredVegetation;

// The second layer set a spread re-slice draws into (LayerSettings.rebuildBudgetMs > 0), rested
// in FragmentSampled for the cross-fade that copies it into the visible set.
struct LayerTargetSet {
  Image color, depth, backgroundColor, backgroundDepth;
  std::vector<VkImageView> colorLayerViews, depthLayerViews;  // per layer (per-layer draw path)
};

struct LayerTargets {
  Image color, depth, ids, backgroundColor, backgroundDepth;
  std::vector<VkImageView> colorLayerViews, depthLayerViews, idsLayerViews;  // per layer (fallback)
  LayerTargetSet next;                      // spread re-slicing only
  PreparedList pendingClear;                // the targets' first clear, not yet recorded (host devices)
};

constexpr VkFormat kLayerDepthFormat = VK_FORMAT_D32_SFLOAT;
constexpr VkFormat kLayerIdsFormat = VK_FORMAT_R32G32_UINT;

// Creates the layer images for lv.settings' layer count (and the next set where spread re-slicing or
// a streamed mesh needs it); destroyLayerTargets frees them once no frame in flight reads them
// (`now`: at once, for images no frame has used). A spread re-slice drawing into them must be
// dropped by the caller (rescheduleAfterChange with targetsRecreated).
Status createLayerTargets(LayeredVegetation& lv);
void destroyLayerTargets(LayeredVegetation& lv, bool now = false);
// Whether re-slices go through the next set: spread re-slicing (not with the id output) or a
// streamed mesh.
bool spreadEnabled(const LayeredVegetation& lv);
bool usesNextSet(const LayeredVegetation& lv);

// A 2D view of one layer of an array image.
Status imageLayerView(Device& device, const Image& image, uint32_t layer, VkImageView* out);

// Reads the layer images back (tests and tools): premultiplied linear RGBA as float, depth, ids.
Status readLayerColor(LayeredVegetation& lv, uint32_t layer, std::vector<glm::vec4>* rgba);
Status readLayerDepth(LayeredVegetation& lv, uint32_t layer, std::vector<float>* depth);
Status readLayerIds(LayeredVegetation& lv, uint32_t layer, std::vector<glm::uvec2>* ids);
Status readBackground(LayeredVegetation& lv, std::vector<glm::vec4>* rgba, std::vector<float>* depth);

}  // namespace canopy
