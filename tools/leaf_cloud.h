#pragma once
// A synthetic leaf cloud for tests and the benchmark until the scene generator exists: `faces / 2`
// quad leaves (two triangles over four shared vertices each, material 0 "leaf", alpha-masked)
// randomly placed in a unit sphere and oriented at random; leaf size shrinks with the count so
// that the leaves' total area stays 8x the crown's cross-section (depth complexity ~8, like a
// dense shrub). With `trunk`, a square trunk (material 1, "bark", opaque) under the crown.
// Deterministic for a seed.
#include <cstdint>

#include "render/model.h"

namespace canopy {

VegetationModel makeLeafCloud(uint64_t faces, uint32_t seed, bool trunk = false);

}  // namespace canopy
