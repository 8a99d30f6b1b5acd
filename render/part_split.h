#pragma once
// Trunk and foliage found by geometry where the materials do not tell (issue 77; docs/design.md
// "Rigid parts in wind"): a material whose role comes from its alpha mode or from an all-opaque
// model (not from its name, nor the user's) may hold both a trunk and a crown (one colour-atlas
// material for a whole tree; bark named by its colour; needle cards and their trunk in one
// alpha-tested texture). Its triangles are split into connected parts (welded by position) and a
// part is rigid when it looks like wood:
//   - no cut-out texels: its texture's alpha at its corners and centres stays at or above the
//     material's cutoff (a leaf card has transparent texels);
//   - not green: its mean colour (factor x texture at its corners) is grey, white, black or brown,
//     not a hue between yellow-green and cyan;
//   - round: its second and third principal extents are alike (a trunk, a branch), not a flat card
//     or blade (third below 0.3 of the second);
//   - long and thin (its first principal extent at least 2.5 times the second) or standing on the
//     plant's foot (its lowest point within 2 % of its plant's height of the plant's lowest;
//     render/plants.h groupPlants).
// The material rule stays the hint: every other part keeps its material's role; --rigid / --foliage
// (MaterialSplitOptions) decide whole materials; each classified part is reported with its reasons.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/status.h"
#include "render/model.h"

namespace canopy {

// A classified part of a material (for canopy-layers' report and logs).
struct PartReport {
  uint32_t material = 0;
  uint32_t triangles = 0;
  bool rigid = false;
  std::string reason;  // the features that decided
};

// Fills `triangleFoliage` (per triangle, 1 for foliage) from the material roles (`materialFoliage`,
// per material) and, for the materials with `byParts` set, from each part's features.
Status splitParts(const VegetationModel& model, const std::vector<uint8_t>& materialFoliage, const std::vector<uint8_t>& byParts,
                  std::vector<uint8_t>* triangleFoliage, std::vector<PartReport>* reports);

}  // namespace canopy
