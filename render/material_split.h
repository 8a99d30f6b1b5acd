#pragma once
// Rigid vs foliage (paper 3.2): trunks and branches are the background and are not layered; every
// other part is foliage and is sliced into layers. The default rule reads the materials; the user
// can override it with explicit material names or indices.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/status.h"
#include "render/model.h"
#include "render/part_split.h"

namespace canopy {

enum class MaterialRole : uint8_t { Foliage = 0, Rigid = 1 };

// MaterialSplitOptions: <canopy/canopy_params.h>.
struct MaterialSplit {
  std::vector<MaterialRole> role;   // per material of the model (the default material included)
  std::vector<std::string> reason;  // per material: why (for logs and the tools' reports)
  // Per triangle, 1 for foliage: its material's role, or its part's where the material's role came
  // from its alpha mode or an all-opaque model (render/part_split.h); `parts` says why per part.
  std::vector<uint8_t> triangleFoliage;
  std::vector<PartReport> parts;
  uint64_t rigidTriangles = 0, foliageTriangles = 0;
};

// The default rule, in order: (1) a name containing bark, trunk, branch, wood, stem, twig or stalk
// is rigid; (2) a name containing leaf, leaves, foliage, needle, grass, frond,
// flower, petal, blossom, fern, kelp or moss is foliage; (3) MASK or BLEND is foliage (cut-out
// leaves); (4) an OPAQUE material is rigid when the model also has MASK/BLEND materials (then the
// leaves are those), else foliage (an all-opaque model such as a low-poly tree or grass: soft
// parts are treated as leaves, as the paper allows). Rules (3) and (5) are hints: a part of such a
// material that looks like wood is rigid (render/part_split.h).
Status splitMaterials(const VegetationModel& model, const MaterialSplitOptions& options, MaterialSplit* out);

}  // namespace canopy
