#pragma once
// Sway that fits the plant (issue 77; docs/design.md "Rigid parts in wind", sway): with the world
// wind the 2D method leans a plant by its height on screen (eq. 6 x h: "World wind"), the same
// share of its height for every plant, while a real plant's top moves by the levers its wood and
// leaves give the wind. The per-vertex baseline bends a model without a branch hierarchy of its own
// (a glTF file) about a fallback trunk and its leaves about their roots ("Per-vertex wind
// baseline"), so a tall pine with leaves on its trunk is stiffer than a bush of long fronds. Each
// plant's sway scale is those levers over the 2D method's, over the foliage of its top third:
//   trunk   0.045 (h / H)^1.5 h                the fallback trunk's bend at the vertex's height h of H
//   branch  0.079 (radial / R)^1.5 |v - axis|  a branch from the trunk's axis out to the leaf's root
//   leaf    0.3375 |v - root|                  the leaf turning about its root
// (the baseline's default flexibilities, PerVertexParams), scale = (7 trunk + 10 branch + 3.5 leaf)
// / h, the weights the minimax fit of the 2D method's sway to the baseline's on the real plants of
// ../shared/assets (docs/lab/performance-notebook.md "Sway that fits the plant"), held to [0.25, 4]. A model whose
// plants have a hierarchy of their own (generated plants; a host's MeshDesc.branches) is what the
// default sway was calibrated on (issue 66): scale 1.
#include <cstdint>
#include <vector>

#include "engine/status.h"
#include "render/leaf_roots.h"
#include "render/model.h"
#include "render/plants.h"

namespace canopy {

inline constexpr float kMinPlantSway = 0.25f, kMaxPlantSway = 4.0f;
// The fit's weights of the three levers (shares of the 2D method's lever).
inline constexpr double kSwayTrunk = 7.0, kSwayBranch = 10.0, kSwayLeaf = 3.5;

// The baseline's levers of a plant's top third, each over the 2D method's (the vertices' heights).
struct PlantLevers {
  double trunk = 0, branch = 0, leaf = 0;
  bool measured = false;  // false: no foliage in the plant's top third (its scale stays 1)
};

// Per plant of `plants`, its levers (`trianglePlant` the plants' numbering per triangle, findPlants;
// `foliage` per triangle).
Status plantLevers(const VegetationModel& model, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                   const std::vector<uint32_t>& trianglePlant, const Plants& plants, std::vector<PlantLevers>* out);
// A plant's sway scale from its levers, held to [kMinPlantSway, kMaxPlantSway].
float plantSwayScale(const PlantLevers& levers);

// Fills plants->sway (one per plant of `plants`), `trianglePlant` the plants' numbering per triangle
// (findPlants), `foliage` per triangle.
Status plantSwayScales(const VegetationModel& model, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                       const std::vector<uint32_t>& trianglePlant, Plants* plants);

}  // namespace canopy
