#include "render/rigid_refine.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "render/plants.h"

namespace canopy {
namespace {

// Per triangle, the longest rigid edge it may keep: kRigidEdgeShare of its own plant's height.
std::vector<float> maxEdges(const VegetationModel& m) {
  std::vector<float> out = {};
  for (const glm::vec3& size : plantSizeOfTriangles(m)) out.push_back(std::max(kRigidEdgeShare * size.y, 1e-12f));
  return out;
}

uint64_t edgeKey(uint32_t a, uint32_t b) { return a < b ? (uint64_t(a) << 32 | b) : (uint64_t(b) << 32 | a); }

}  // namespace

bool needsRigidRefinement(const VegetationModel& m, const std::vector<uint8_t>& foliage) {
  if (!m.bend.empty() || foliage.size() != m.triangleCount()) return false;
  const std::vector<float> longest = maxEdges(m);
  for (size_t t = 0; t < m.triangleCount(); ++t) {
    if (foliage[t]) continue;
    for (int k = 0; k < 3; ++k)
      if (glm::length(m.positions[m.indices[3 * t + size_t(k)]] - m.positions[m.indices[3 * t + size_t((k + 1) % 3)]]) > longest[t])
        return true;
  }
  return false;
}

Status refineRigidParts(const VegetationModel& model, std::vector<uint8_t>* foliage, VegetationModel* out) {
  *out = model;
  VegetationModel& m = *out;
  if (foliage->size() != m.triangleCount()) return Status::error("rigid refinement: the foliage mask disagrees with the model");
  const bool plants = m.trianglePlant.size() == m.triangleCount(), boxes = m.triangleBox.size() == m.triangleCount();
  std::vector<float> longest = maxEdges(m);  // per triangle; a split triangle's parts keep its own
  for (uint32_t pass = 0; pass < kRigidRefinePasses; ++pass) {
    // The rigid edges to split this pass and their midpoints (shared by both triangles of an edge).
    std::unordered_map<uint64_t, uint32_t> mid;
    const size_t nt = m.triangleCount();
    for (size_t t = 0; t < nt; ++t) {
      if ((*foliage)[t]) continue;
      for (int k = 0; k < 3; ++k) {
        const uint32_t a = m.indices[3 * t + size_t(k)], b = m.indices[3 * t + size_t((k + 1) % 3)];
        if (glm::length(m.positions[a] - m.positions[b]) <= longest[t] || mid.count(edgeKey(a, b))) continue;
        const uint32_t v = uint32_t(m.positions.size());
        if (v == 0xffffffffu) return Status::error(Result::InvalidModel, "rigid refinement: more than 32-bit vertex indices hold");
        m.positions.push_back(0.5f * (m.positions[a] + m.positions[b]));
        const glm::vec3 n = m.normals.size() > std::max(a, b) ? m.normals[a] + m.normals[b] : glm::vec3(0, 0, 1);
        if (m.normals.size() + 1 == m.positions.size()) m.normals.push_back(glm::length(n) > 1e-12f ? glm::normalize(n) : glm::vec3(0, 0, 1));
        m.uvs.push_back(0.5f * (m.uvs[a] + m.uvs[b]));
        mid[edgeKey(a, b)] = v;
      }
    }
    if (mid.empty()) break;
    // A rigid edge shared with a foliage triangle is split there too (no crack between the two).
    std::vector<uint32_t> indices;
    std::vector<uint32_t> materials, plantOf, boxOf;
    std::vector<uint8_t> isFoliage;
    std::vector<float> longestOf;
    indices.reserve(m.indices.size() + 9 * mid.size());
    auto emit = [&](size_t t, uint32_t a, uint32_t b, uint32_t c) {
      indices.insert(indices.end(), {a, b, c});
      materials.push_back(m.triangleMaterial[t]);
      isFoliage.push_back((*foliage)[t]);
      longestOf.push_back(longest[t]);
      if (plants) plantOf.push_back(m.trianglePlant[t]);
      if (boxes) boxOf.push_back(m.triangleBox[t]);
    };
    for (size_t t = 0; t < nt; ++t) {
      const uint32_t v[3] = {m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]};
      uint32_t e[3];
      int split = 0;
      for (int k = 0; k < 3; ++k) {
        const auto it = mid.find(edgeKey(v[k], v[(k + 1) % 3]));
        e[k] = it == mid.end() ? 0xffffffffu : it->second;
        split += it != mid.end();
      }
      if (split == 0) {
        emit(t, v[0], v[1], v[2]);
      } else if (split == 3) {
        emit(t, v[0], e[0], e[2]);
        emit(t, e[0], v[1], e[1]);
        emit(t, e[2], e[1], v[2]);
        emit(t, e[0], e[1], e[2]);
      } else {
        // Rotate so the split edges come first (edge k runs from v[k] to v[k + 1]).
        int r = 0;
        if (split == 1) r = e[0] != 0xffffffffu ? 0 : e[1] != 0xffffffffu ? 1 : 2;
        else r = e[0] == 0xffffffffu ? 1 : e[1] == 0xffffffffu ? 2 : 0;  // two: the unsplit one last
        const uint32_t a = v[r], b = v[(r + 1) % 3], c = v[(r + 2) % 3], ab = e[r], bc = e[(r + 1) % 3];
        if (split == 1) {
          emit(t, a, ab, c);
          emit(t, ab, b, c);
        } else {
          emit(t, a, ab, c);
          emit(t, ab, b, bc);
          emit(t, ab, bc, c);
        }
      }
    }
    m.indices = std::move(indices);
    m.triangleMaterial = std::move(materials);
    *foliage = std::move(isFoliage);
    longest = std::move(longestOf);
    if (plants) m.trianglePlant = std::move(plantOf);
    if (boxes) m.triangleBox = std::move(boxOf);
  }
  return Status();
}

}  // namespace canopy
