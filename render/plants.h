#pragma once
// Per-plant roots (beyond paper eq. 7; docs/design.md "Per-plant roots"): which plant each leaf
// belongs to and each plant's bounds, from VegetationModel::trianglePlant, found once per model.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "engine/status.h"
#include "render/leaf_roots.h"
#include "render/model.h"

namespace canopy {

struct Plants {
  std::vector<uint32_t> leafPlant;              // per leaf (LeafRoots numbering): its plant
  std::vector<glm::vec3> boundsMin, boundsMax;  // per plant, model space: every triangle of it, rigid parts too
  std::vector<float> sway;  // per plant, its sway scale with the world wind (render/plant_sway.h); empty: 1
  std::vector<uint8_t> rigid;  // per plant, 1 where it has rigid parts (findPlants)
  uint32_t count() const { return uint32_t(boundsMin.size()); }
};

// Groups the triangles by VegetationModel::trianglePlant (empty, or of another size: one plant, the
// whole model), merging plants whose bounds overlap in x and z when the model asks for it; a leaf
// takes the plant of its root vertex's first triangle. Plants without leaves are dropped.
// `trianglePlant` (optional): per triangle its plant in that numbering, kNoPlant for a triangle of no
// plant or of a group without leaves (a rock, the ground).
// `foliage` (per triangle; optional): Plants::rigid is set for the plants with other triangles.
Status findPlants(const VegetationModel& model, const LeafRoots& roots, Plants* out,
                  std::vector<uint32_t>* trianglePlant = nullptr, const std::vector<uint8_t>& foliage = {});

}  // namespace canopy
