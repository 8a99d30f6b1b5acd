#pragma once
// CPU reference of the layer dynamics (tests and benchmark only): the same corner loop as
// shaders/anim_displace.comp in plain C++, with the shared eq. 1-7 functions of shared/anim.h.
#include <vector>

#include <glm/glm.hpp>

#include "shared/anim.h"

namespace canopy {

// tiled: n*n vec2; ring: H*n*n vec2; ringTimes: H; plantRects: the frame block's plant table
// (per-plant roots). Returns layers x gridY x gridX displacements.
std::vector<glm::vec2> referenceDisplacement(const gpu::AnimFrame& f, const std::vector<glm::vec2>& tiled,
                                             const std::vector<glm::vec2>& ring, const std::vector<float>& ringTimes,
                                             const std::vector<glm::vec4>& plantRects = {});

// The warp's stretch bound (AnimFrame.maxStretch; anim_stretch_cols/rows.comp): each corner's
// displacement shortened to the largest L-Lipschitz magnitude (L1 grid metric) under |d|.
std::vector<glm::vec2> boundStretchReference(const gpu::AnimFrame& f, const std::vector<glm::vec2>& raw);

// The simulation-plane coordinate (tile units) of warp-grid corner (gx, gy) of a layer.
// `depth` > 0: the view depth the corner reads the field at (a plant rect's), else the layer's.
glm::vec2 cornerSimCoord(const gpu::AnimFrame& f, uint32_t layer, uint32_t gx, uint32_t gy, float depth = 0.0f);

// Bilinear periodic sample of an n*n field at tile coordinates a (cell centres at (i + 0.5) / n).
glm::vec2 sampleTiledReference(const glm::vec2* field, uint32_t n, glm::vec2 a);

}  // namespace canopy
