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

inline constexpr float kFootShare = 0.05f;

struct Plants {
  std::vector<uint32_t> leafPlant;              // per leaf (LeafRoots numbering): its plant
  std::vector<glm::vec3> boundsMin, boundsMax;  // per plant, model space: every triangle of it, rigid parts too
  // Per plant, its foot: the box of its vertices within kFootShare of its height above its lowest
  // point (eq. 7's root line; a wide crown's box reaches far lower on screen than its trunk's foot).
  std::vector<glm::vec3> footMin, footMax;
  std::vector<float> sway;  // per plant, its sway scale with the world wind (render/plant_sway.h); empty: 1
  std::vector<uint8_t> rigid;  // per plant, 1 where it has rigid parts (findPlants)
  uint32_t count() const { return uint32_t(boundsMin.size()); }
};

// The plants' groups before any leaf is known: per triangle its group (VegetationModel::trianglePlant,
// merged where the model asks for it, kNoPlant for a triangle of none; one group for a model without
// plants) and per group its box (model space; a group merged into another keeps an unused box).
struct PlantGroups {
  std::vector<uint32_t> triangle;
  std::vector<glm::vec3> lo, hi;
};
Status groupPlants(const VegetationModel& model, PlantGroups* out);
// Per triangle, the size (box max - min) of the plant it belongs to, the whole model's for a triangle
// of no plant: lengths that scale with a plant (the leaves' attachment reach, the rigid refinement's
// edge, the anchors' radius, a part's foot) are shares of its own plant, so a file holding a field
// treats each plant as a file of that plant alone would.
std::vector<glm::vec3> plantSizeOfTriangles(const VegetationModel& model);

// Groups the triangles by VegetationModel::trianglePlant (empty, or of another size: one plant, the
// whole model), merging plants whose bounds overlap in x and z when the model asks for it; a leaf
// takes the plant of its root vertex's first triangle. Plants without leaves are dropped.
// `trianglePlant` (optional): per triangle its plant in that numbering, kNoPlant for a triangle of no
// plant or of a group without leaves (a rock, the ground).
// `foliage` (per triangle; optional): Plants::rigid is set for the plants with other triangles.
Status findPlants(const VegetationModel& model, const LeafRoots& roots, Plants* out,
                  std::vector<uint32_t>* trianglePlant = nullptr, const std::vector<uint8_t>& foliage = {});

}  // namespace canopy
