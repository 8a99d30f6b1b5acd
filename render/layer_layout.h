#pragma once
// Layer placement (paper 3.2, docs/design.md "Conventions where the paper is silent", layers): the foliage's view-space depth range is split
// into near, mid and far regions at user-given distances, each with its own layer count (written
// like the paper: "5(3-1-1)"); inside a region the layers are equally spaced.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <canopy/canopy_params.h>

#include "engine/status.h"
#include "shared/layers.h"

namespace canopy {

static_assert(kMaxLayers == CANOPY_MAX_LAYERS);  // kMaxLayers, LayerLayout, RegionSplit: <canopy/canopy_params.h>

// Parses "N(a-b-c)" (N must equal a+b+c) or a plain "N" (= N(N-0-0): N equal layers over the
// whole range). 1 <= N <= kMaxLayers. Errors quote the text and say what is expected.
Status parseLayerLayout(std::string_view text, LayerLayout* out);
std::string toString(const LayerLayout& layout);  // "5(3-1-1)"

Status validateRegionSplit(const RegionSplit& split);

struct LayerSlab {
  float zNear = 0, zFar = 0;  // view depths bounding the layer's leaf roots
  float depth = 0;            // representative depth (slab centre)
  float distance = 0;         // L_i: depth - depth of layer 0 (eq. 4 and eq. 6)
};

// Splits [zMin, zMax] (view depths of the leaf roots). An empty region hands its interval to its
// non-empty neighbours (split at its middle when both exist), so the layers always cover the whole
// range. `boundaries` gets count()+1 increasing depths (the LayerFrame convention).
Status placeLayers(const LayerLayout& layout, const RegionSplit& split, float zMin, float zMax,
                   std::vector<LayerSlab>* slabs, std::vector<float>* boundaries);

}  // namespace canopy
