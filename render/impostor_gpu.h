#pragma once
// The impostors' GPU side (render/impostor_gpu.cpp; docs/design.md "Impostors"): the atlas, its
// pipelines and the bake of each baked box's twelve views (lv.imp planned by render/impostors.h,
// read from or written to the views' cache file), and the draw of a re-slice's cut.
#include <cstdint>
#include <vulkan/vulkan.h>

#include "engine/status.h"

namespace canopy {

struct LayeredVegetation;
struct ImpostorDraws;

// Creates the atlas and pipelines and bakes (or reads) the views; stats in lv.imp.
Status createImpostors(LayeredVegetation& lv);
void destroyImpostors(LayeredVegetation& lv);
// Draws a cut's opaque (fading = false) or fading impostors inside the caller's rendering of the
// layers (`layer`: the per-layer path's layer, ignored by the single pass); the list `draws` holds
// is the one uploaded to Impostors.instances for this draw.
Status recordImpostors(LayeredVegetation& lv, VkCommandBuffer cmd, const ImpostorDraws& draws, bool fading, uint32_t layer);

}  // namespace canopy
