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
  rg::Use restUse = rg::Use::FragmentSampled;  // how the images rest between the frames' passes (LayerTargetsDesc)
};

// The images' shape: size (the guard band included), colour format, layer count, the id array, the
// second set, and how they rest for their readers.
struct LayerTargetsDesc {
  uint32_t width = 1, height = 1, layers = 1;
  VkFormat colorFormat = VK_FORMAT_R16G16B16A16_SFLOAT;
  bool ids = false;      // the id array (LayerMeshDesc.writeIds)
  bool nextSet = false;  // the second set (spread re-slicing or a streamed mesh)
  rg::Use restUse = rg::Use::FragmentSampled;
};

constexpr VkFormat kLayerDepthFormat = VK_FORMAT_D32_SFLOAT;
constexpr VkFormat kLayerIdsFormat = VK_FORMAT_R32G32_UINT;

// Creates the layer images `desc` describes; destroyLayerTargets frees them once no frame in flight
// reads them (`now`: at once, for images no frame has used). A spread re-slice drawing into them
// must be dropped by the caller (rescheduleAfterChange with targetsRecreated).
Status createLayerTargets(Device& device, const LayerTargetsDesc& desc, LayerTargets& targets);
void destroyLayerTargets(Device& device, LayerTargets& targets, bool now = false);

// A 2D view of one layer of an array image.
Status imageLayerView(Device& device, const Image& image, uint32_t layer, VkImageView* out);

// Reads the layer images back (tests and tools): premultiplied linear RGBA as float, depth, ids.
Status readLayerColor(Device& device, const LayerTargets& targets, uint32_t layer, std::vector<glm::vec4>* rgba);
Status readLayerDepth(Device& device, const LayerTargets& targets, uint32_t layer, std::vector<float>* depth);
Status readLayerIds(Device& device, const LayerTargets& targets, uint32_t layer, std::vector<glm::uvec2>* ids);
Status readBackground(Device& device, const LayerTargets& targets, std::vector<glm::vec4>* rgba, std::vector<float>* depth);

}  // namespace canopy
