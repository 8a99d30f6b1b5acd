#include "render/foliage_boxes.h"

#include <algorithm>
#include <string>

namespace canopy {
namespace {

std::string modelName(const VegetationModel& m) { return m.path.empty() ? std::string("the model") : m.path; }

// Groups the foliage triangles by box (boxOf[t] for foliage triangles), then bounds every box by
// its own triangles and, children before parents, by its children: boxes nest by construction.
Status finish(const VegetationModel& m, const std::vector<uint8_t>& foliage, const std::vector<uint32_t>& boxOf,
              BoxHierarchy* out) {
  std::vector<FoliageBox>& boxes = out->boxes;
  const size_t nt = m.triangleCount();
  for (size_t t = 0; t < nt; ++t)
    if (foliage[t]) boxes[boxOf[t]].triangleCount++;
  uint64_t first = 0;
  for (FoliageBox& b : boxes) {
    b.firstTriangle = first;
    first += b.triangleCount;
    b.triangleCount = 0;
  }
  out->triangles.assign(first, 0);
  for (size_t t = 0; t < nt; ++t) {
    if (!foliage[t]) continue;
    FoliageBox& b = boxes[boxOf[t]];
    out->triangles[b.firstTriangle + b.triangleCount++] = uint32_t(t);
    for (int k = 0; k < 3; ++k) {
      const glm::vec3& p = m.positions[m.indices[3 * t + k]];
      b.boundsMin = glm::min(b.boundsMin, p);
      b.boundsMax = glm::max(b.boundsMax, p);
    }
  }
  for (size_t i = boxes.size(); i-- > 1;) {
    const FoliageBox& b = boxes[i];
    if (b.parent == kNoBox) continue;
    boxes[b.parent].boundsMin = glm::min(boxes[b.parent].boundsMin, b.boundsMin);
    boxes[b.parent].boundsMax = glm::max(boxes[b.parent].boundsMax, b.boundsMax);
  }
  return Status();
}

Status checkMask(const VegetationModel& m, const std::vector<uint8_t>& foliage) {
  if (foliage.size() != m.triangleCount())
    return Status::error("foliage boxes: the foliage mask has " + std::to_string(foliage.size()) + " entries for " +
                         std::to_string(m.triangleCount()) + " triangles of " + modelName(m));
  return Status();
}

}  // namespace

Status boxesFromModel(const VegetationModel& m, const std::vector<uint8_t>& foliage, BoxHierarchy* out) {
  *out = BoxHierarchy{};
  CANOPY_TRY(checkMask(m, foliage));
  if (m.boxParent.empty()) return Status::error("foliage boxes: " + modelName(m) + " has no box hierarchy");
  if (m.triangleBox.size() != m.triangleCount())
    return Status::error("foliage boxes: " + modelName(m) + " has " + std::to_string(m.triangleBox.size()) +
                         " triangle boxes for " + std::to_string(m.triangleCount()) + " triangles");
  out->boxes.resize(m.boxParent.size());
  for (size_t i = 0; i < m.boxParent.size(); ++i) {
    const uint32_t p = m.boxParent[i];
    if (p != kNoBox && p >= i)
      return Status::error("foliage boxes: " + modelName(m) + ": box " + std::to_string(i) + " has parent " +
                           std::to_string(p) + " (parents come first)");
    out->boxes[i].parent = p;
    out->boxes[i].level = p == kNoBox ? 0 : out->boxes[p].level + 1;
  }
  for (size_t t = 0; t < foliage.size(); ++t)
    if (foliage[t] && m.triangleBox[t] >= m.boxParent.size())
      return Status::error("foliage boxes: " + modelName(m) + ": foliage triangle " + std::to_string(t) +
                           " names box " + std::to_string(m.triangleBox[t]) + " of " + std::to_string(m.boxParent.size()));
  return finish(m, foliage, m.triangleBox, out);
}

Status boxesFromLeafRoots(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                          uint32_t maxLeavesPerBox, BoxHierarchy* out) {
  *out = BoxHierarchy{};
  CANOPY_TRY(checkMask(m, foliage));
  if (maxLeavesPerBox < 1 || maxLeavesPerBox > (1u << 30))
    return Status::error("foliage boxes: maxLeavesPerBox " + std::to_string(maxLeavesPerBox) + " is outside 1..2^30");
  if (roots.leafOfVertex.size() != m.positions.size())
    return Status::error("foliage boxes: the leaf roots are not those of " + modelName(m));
  // Breadth-first: a node's leaves are a contiguous range of `order`; the split sorts its range
  // around the median root along the longest axis (by count, so equal positions still split).
  std::vector<uint32_t> order(roots.leafCount());
  for (uint32_t i = 0; i < order.size(); ++i) order[i] = i;
  struct Range {
    uint32_t box;
    size_t begin, end;
  };
  std::vector<Range> work{{0, 0, order.size()}};
  out->boxes.push_back(FoliageBox{});
  std::vector<uint32_t> boxOfLeaf(roots.leafCount(), 0);
  auto rootOf = [&](uint32_t leaf) { return m.positions[roots.leafRoot[leaf]]; };
  for (size_t w = 0; w < work.size(); ++w) {
    const Range r = work[w];
    if (r.end - r.begin <= maxLeavesPerBox) {
      for (size_t i = r.begin; i < r.end; ++i) boxOfLeaf[order[i]] = r.box;
      continue;
    }
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (size_t i = r.begin; i < r.end; ++i) {
      lo = glm::min(lo, rootOf(order[i]));
      hi = glm::max(hi, rootOf(order[i]));
    }
    const glm::vec3 ext = hi - lo;
    const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
    const size_t mid = r.begin + (r.end - r.begin) / 2;
    std::nth_element(order.begin() + long(r.begin), order.begin() + long(mid), order.begin() + long(r.end),
                     [&](uint32_t a, uint32_t b) { return rootOf(a)[axis] < rootOf(b)[axis] || (rootOf(a)[axis] == rootOf(b)[axis] && a < b); });
    for (const auto& [b, e] : {std::pair<size_t, size_t>{r.begin, mid}, {mid, r.end}}) {
      FoliageBox child;
      child.parent = r.box;
      child.level = out->boxes[r.box].level + 1;
      out->boxes.push_back(child);
      work.push_back({uint32_t(out->boxes.size() - 1), b, e});
    }
  }
  // A triangle's leaf is its first vertex's (a leaf's triangles share their vertices' leaf).
  std::vector<uint32_t> boxOf(m.triangleCount(), 0);
  for (size_t t = 0; t < boxOf.size(); ++t) {
    if (!foliage[t]) continue;
    const uint32_t leaf = roots.leafOfVertex[m.indices[3 * t]];
    if (leaf == kNoLeaf || leaf >= boxOfLeaf.size())
      return Status::error("foliage boxes: foliage triangle " + std::to_string(t) + " of " + modelName(m) + " has no leaf");
    boxOf[t] = boxOfLeaf[leaf];
  }
  return finish(m, foliage, boxOf, out);
}

Status refineBoxes(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                   uint32_t maxOwnLeaves, uint32_t maxPieces, BoxHierarchy* h) {
  CANOPY_TRY(checkMask(m, foliage));
  if (maxOwnLeaves < 1 || maxPieces < 2)
    return Status::error("foliage boxes: refinement needs maxOwnLeaves >= 1 and maxPieces >= 2");
  if (roots.leafOfVertex.size() != m.positions.size())
    return Status::error("foliage boxes: the leaf roots are not those of " + modelName(m));
  const size_t nb = h->boxes.size();
  std::vector<uint32_t> boxOf(m.triangleCount(), 0), boxOfLeaf(roots.leafCount(), kNoBox);
  for (size_t b = 0; b < nb; ++b)
    for (uint64_t j = h->boxes[b].firstTriangle; j < h->boxes[b].firstTriangle + h->boxes[b].triangleCount; ++j)
      boxOf[h->triangles[j]] = uint32_t(b);
  auto leafOf = [&](uint32_t t) { return roots.leafOfVertex[m.indices[3 * size_t(t)]]; };
  auto rootOf = [&](uint32_t leaf) { return m.positions[roots.leafRoot[leaf]]; };
  bool changed = false;
  for (size_t b = 0; b < nb; ++b) {
    const FoliageBox box = h->boxes[b];
    std::vector<uint32_t> leaves;
    for (uint64_t j = box.firstTriangle; j < box.firstTriangle + box.triangleCount; ++j) {
      const uint32_t leaf = leafOf(h->triangles[j]);
      if (leaf != kNoLeaf && leaf < boxOfLeaf.size() && boxOfLeaf[leaf] != uint32_t(b)) {
        boxOfLeaf[leaf] = uint32_t(b);
        leaves.push_back(leaf);
      }
    }
    if (leaves.size() <= maxOwnLeaves) continue;
    // Median splits along the longest axis of the pieces' roots, the largest piece first, until
    // every piece is small enough or there are maxPieces of them; the pieces become children.
    std::vector<std::pair<size_t, size_t>> pieces{{0, leaves.size()}};
    while (pieces.size() < maxPieces) {
      size_t largest = 0;
      for (size_t i = 1; i < pieces.size(); ++i)
        if (pieces[i].second - pieces[i].first > pieces[largest].second - pieces[largest].first) largest = i;
      const auto [begin, end] = pieces[largest];
      if (end - begin <= maxOwnLeaves) break;
      glm::vec3 lo(INFINITY), hi(-INFINITY);
      for (size_t i = begin; i < end; ++i) {
        lo = glm::min(lo, rootOf(leaves[i]));
        hi = glm::max(hi, rootOf(leaves[i]));
      }
      const glm::vec3 ext = hi - lo;
      const int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : ext.y >= ext.z ? 1 : 2;
      const size_t mid = begin + (end - begin) / 2;
      std::nth_element(leaves.begin() + long(begin), leaves.begin() + long(mid), leaves.begin() + long(end),
                       [&](uint32_t a, uint32_t c) {
                         return rootOf(a)[axis] < rootOf(c)[axis] || (rootOf(a)[axis] == rootOf(c)[axis] && a < c);
                       });
      pieces[largest] = {begin, mid};
      pieces.push_back({mid, end});
    }
    for (const auto& [begin, end] : pieces) {
      FoliageBox child;
      child.parent = uint32_t(b);
      child.level = box.level + 1;
      h->boxes.push_back(child);
      for (size_t i = begin; i < end; ++i) boxOfLeaf[leaves[i]] = uint32_t(h->boxes.size() - 1);
    }
    for (uint64_t j = box.firstTriangle; j < box.firstTriangle + box.triangleCount; ++j) {
      const uint32_t t = h->triangles[j], leaf = leafOf(t);
      if (leaf != kNoLeaf && leaf < boxOfLeaf.size()) boxOf[t] = boxOfLeaf[leaf];
    }
    changed = true;
  }
  if (!changed) return Status();
  for (FoliageBox& b : h->boxes) {
    b.boundsMin = glm::vec3(INFINITY);
    b.boundsMax = glm::vec3(-INFINITY);
    b.firstTriangle = b.triangleCount = 0;
  }
  h->triangles.clear();
  return finish(m, foliage, boxOf, h);
}

}  // namespace canopy
