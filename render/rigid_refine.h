#pragma once
// The rigid parts refined for the displacement they follow (docs/design.md "Rigid parts in wind"):
// the rigid draw moves each vertex and the rasterizer interpolates between them, so a low-poly
// trunk drawn as a few triangles from its foot to its crown follows a displacement that is not
// linear along it (the stretch bound, a gust's shape) only at its ends, and a leaf growing from its
// middle floats off it. Rigid edges longer than kRigidEdgeShare of their plant's height
// (render/plants.h) are split at their midpoints (conforming: a split edge is split in both
// triangles that share it; a triangle with one, two or three split edges becomes two, three or
// four), pass after pass until none is longer. Positions, normals and texture coordinates are interpolated; materials and plants kept.
#include <cstdint>

#include "engine/status.h"
#include "render/model.h"

namespace canopy {

inline constexpr float kRigidEdgeShare = 0.05f;
inline constexpr uint32_t kRigidRefinePasses = 6;

// Whether `model` has a rigid edge to split (`foliage` per triangle). A model with a branch hierarchy
// (VegetationModel::bend) is never refined: its per-vertex records would not interpolate.
bool needsRigidRefinement(const VegetationModel& model, const std::vector<uint8_t>& foliage);
// `out` = `model` with its long rigid edges split; `foliage` follows (per triangle).
Status refineRigidParts(const VegetationModel& model, std::vector<uint8_t>* foliage, VegetationModel* out);

}  // namespace canopy
