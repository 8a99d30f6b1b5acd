#pragma once
// A bounding-box hierarchy over the foliage (seed 002, Lluch et al., section 3; issue 18): the
// structure the image-based levels of detail are built on. From the scene generator's L-system
// (each PUSH opens a box, its POP closes it: VegetationModel::boxParent / triangleBox), or, for
// models without a branch structure (glTF), from a k-d split of the leaf roots. Boxes come
// parents first; each bounds its own leaves' triangles and all its descendants' (so boxes nest);
// every foliage triangle belongs to exactly one box, and a leaf is never split between boxes.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "engine/status.h"
#include "render/model.h"
#include "render/leaf_roots.h"

namespace canopy {

constexpr uint32_t kNoBox = 0xffffffffu;

struct FoliageBox {
  glm::vec3 boundsMin{INFINITY}, boundsMax{-INFINITY};  // empty (min > max) for a box without foliage
  uint32_t parent = kNoBox;  // an earlier box, kNoBox for the root
  uint32_t level = 0;        // the parent's + 1
  uint64_t firstTriangle = 0, triangleCount = 0;  // its own foliage triangles in BoxHierarchy::triangles
};

struct BoxHierarchy {
  std::vector<FoliageBox> boxes;
  std::vector<uint32_t> triangles;  // foliage triangle ids, grouped by the box that owns them
};

// From the model's own boxes (boxParent, and triangleBox for every foliage triangle);
// `foliage[t]` != 0 marks foliage triangles. Errors name the model and the offending box or triangle.
Status boxesFromModel(const VegetationModel& model, const std::vector<uint8_t>& foliage, BoxHierarchy* out);

// A k-d split of the leaf roots (`roots` from computeLeafRoots on the same mask): a box is split at
// the median root along the longest axis of its roots' bounds until it holds at most
// `maxLeavesPerBox` leaves (1..2^30); the leaves' triangles go to the box that holds their root.
Status boxesFromLeafRoots(const VegetationModel& model, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                          uint32_t maxLeavesPerBox, BoxHierarchy* out);

// Splits the own leaves of every box holding more than `maxOwnLeaves` (a grass patch of thousands
// of blades) into k-d pieces by their roots, the largest piece first, until each holds at most
// maxOwnLeaves or there are `maxPieces`; the pieces become the box's children (one level down), so
// the impostors can switch a large box region by region. Boxes stay parents first and nested.
Status refineBoxes(const VegetationModel& model, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                   uint32_t maxOwnLeaves, uint32_t maxPieces, BoxHierarchy* hierarchy);

}  // namespace canopy
