#pragma once
// The impostors' GPU side (render/impostor_gpu.cpp; docs/design.md "Impostors"): the atlas, its
// pipelines and the bake of each baked box's twelve views (planned by render/impostors.h,
// read from or written to the views' cache file), and the draw of a re-slice's cut.
#include <cstdint>
#include <vulkan/vulkan.h>

#include <canopy/canopy_params.h>

#include "engine/status.h"
#include "render/impostors.h"
#include "render/layer_instances.h"
#include "render/layer_mesh.h"

namespace canopy {

struct Device;
struct ImpostorDraws;

// What the impostors' creation reads of the vegetation: the mesh the bake draws (it must stay where
// it is until the bake is recorded: on a host's device, in its first frame; the bake binds a copies'
// table of its own, one copy at the origin), the placed copies (they size the impostor list), the
// settings the views are shaded with, the layers' colour format.
struct ImpostorSources {
  const LayerMesh* mesh = nullptr;
  const LayerInstances* instances = nullptr;
  const LayerSettings* settings = nullptr;
  VkFormat colorFormat = VK_FORMAT_R16G16B16A16_SFLOAT;
};

// Creates the atlas and pipelines of `imp` (planned by render/impostors.h) and bakes (or reads) the
// views; the bake's figures in `imp`.
Status createImpostors(Device& device, const ImpostorSources& sources, Impostors& imp);
void destroyImpostors(Device& device, Impostors& imp);
// Makes the impostor list hold a cut of `copies` (a box at most once per copy of its species);
// a larger list replaces the old one, released after the frames in flight (graphs must be rebuilt).
Status reserveImpostorList(Device& device, Impostors& imp, const LayerInstances& copies);
// Draws a cut's opaque (fading = false) or fading impostors inside the caller's rendering of the
// layers `target` names (its frame block and size), by the single pass or per layer (`layer`: the
// per-layer path's layer, ignored by the single pass); the list `draws` holds is the one uploaded
// to Impostors.instances for this draw.
Status recordImpostors(const MeshDraw& target, const Impostors& imp, const LayerSettings& settings, bool singlePass,
                       VkCommandBuffer cmd, const ImpostorDraws& draws, bool fading, uint32_t layer);

}  // namespace canopy
