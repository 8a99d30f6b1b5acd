#include "render/rigid_flex.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "render/leaf_attach.h"
#include "render/plants.h"
#include "shared/layers.h"

namespace canopy {

Status rigidFlexibility(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                        const std::vector<uint32_t>& trianglePlant, std::vector<uint16_t>* out) {
  const size_t nt = m.triangleCount(), nv = m.positions.size();
  if (foliage.size() != nt || trianglePlant.size() != nt || roots.leafOfVertex.size() != nv)
    return Status::error("rigid flexibility: per-triangle or per-vertex arrays disagree with the model");
  uint32_t plants = 0;
  for (uint32_t p : trianglePlant)
    if (p != kNoPlant) plants = std::max(plants, p + 1);
  // Each plant's foot (its lowest point, rigid parts too) and its leaves' root heights.
  std::vector<float> foot(plants, INFINITY);
  std::vector<uint32_t> leafPlant(roots.leafCount(), kNoPlant);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t p = trianglePlant[t];
    if (p == kNoPlant) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[3 * t + size_t(k)];
      foot[p] = std::min(foot[p], m.positions[v].y);
      if (foliage[t] && roots.leafOfVertex[v] != kNoLeaf && leafPlant[roots.leafOfVertex[v]] == kNoPlant)
        leafPlant[roots.leafOfVertex[v]] = p;
    }
  }
  std::vector<std::vector<float>> rootHeights(plants);
  // The lowest root sitting on the rigid parts (render/leaf_attach.h): the wood follows in full
  // wherever a leaf grows from it.
  std::vector<float> lowestAttached(plants, INFINITY);
  const RigidGrid grid = buildRigidGrid(m, foliage, 0.0f);
  for (uint32_t l = 0; l < roots.leafCount(); ++l) {
    if (leafPlant[l] == kNoPlant) continue;
    const glm::vec3 r = m.positions[roots.leafRoot[l]];
    rootHeights[leafPlant[l]].push_back(r.y);
    LeafAttachment at;
    if (r.y < lowestAttached[leafPlant[l]] && nearestRigidPoint(grid, r, &at)) lowestAttached[leafPlant[l]] = r.y;
  }
  // The crown's base: the kCrownBaseQuantile of the roots' heights (nth_element: linear).
  std::vector<float> crown(plants, -INFINITY);
  for (uint32_t p = 0; p < plants; ++p) {
    std::vector<float>& h = rootHeights[p];
    if (h.empty()) continue;
    const size_t k = std::min(h.size() - 1, size_t(std::floor(kCrownBaseQuantile * float(h.size()))));
    std::nth_element(h.begin(), h.begin() + std::ptrdiff_t(k), h.end());
    crown[p] = std::min(h[k], lowestAttached[p]);
    std::vector<float>().swap(h);
  }
  // The foot band (render/plants.h kFootShare of each plant's height, the box eq. 7's root line
  // stands on) is held still: the displacement just above a plant's root line is not zero where a
  // layer's grid blends in the crown's (a gale moved KayKit's foot 0.76 px with a share of 0.08).
  const std::vector<glm::vec3> size = plantSizeOfTriangles(m);
  out->assign(nv, uint16_t(LAYER_RIGID_FULL));
  std::vector<uint8_t> done(nv, 0);
  for (size_t t = 0; t < nt; ++t) {
    if (foliage[t]) continue;
    const uint32_t p = trianglePlant[t];
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[3 * t + size_t(k)];
      if (done[v]) continue;
      done[v] = 1;
      float w = 0.0f;  // a rigid part of no plant with leaves: still
      if (p != kNoPlant && std::isfinite(crown[p])) {
        const float band = kFootShare * size[t].y, base = foot[p] + band, span = crown[p] - base;
        // Leaves from the foot up (a bush's stems): the rigid parts above the foot band follow as
        // the leaves do; otherwise a smoothstep from the band's top to the crown's base.
        const float y = m.positions[v].y;
        const float x = y <= base ? 0.0f : span > 1e-6f * std::max(std::abs(crown[p]), 1.0f) ? (y - base) / span : 1.0f;
        const float c = std::clamp(x, 0.0f, 1.0f);
        w = c * c * (3.0f - 2.0f * c);
      }
      (*out)[v] = uint16_t(std::lround(w * float(LAYER_RIGID_FULL)));
    }
  }
  return Status();
}

Status rigidAnchors(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                    const std::vector<uint32_t>& trianglePlant, std::vector<gpu::LayerLeafRoot>* out) {
  std::vector<uint16_t> share;
  CANOPY_TRY(rigidFlexibility(m, foliage, roots, trianglePlant, &share));
  const size_t nv = m.positions.size();
  out->resize(nv);
  std::vector<uint8_t> rigid(nv, 0);
  // Each rigid vertex's radius: kAnchorShare of its plant's height (a file of many plants).
  std::vector<float> radiusOf(nv, 0.0f);
  const std::vector<glm::vec3> size = plantSizeOfTriangles(m);
  for (size_t t = 0; t < m.triangleCount(); ++t)
    if (!foliage[t])
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = m.indices[3 * t + size_t(k)];
        rigid[v] = 1;
        radiusOf[v] = std::max(radiusOf[v], kAnchorShare * size[t].y);
      }
  // The rigid vertices in a grid of cells the largest radius wide: a vertex's neighbours lie in
  // the 27 cells around its own.
  float radius = 1e-12f;
  for (float r : radiusOf) radius = std::max(radius, r);
  auto cellOf = [&](const glm::vec3& p) { return glm::ivec3(glm::floor((p - m.boundsMin) / radius)); };
  auto key = [](const glm::ivec3& c) {
    return (uint64_t(uint32_t(c.x) & 0x1fffff) << 42) | (uint64_t(uint32_t(c.y) & 0x1fffff) << 21) | uint64_t(uint32_t(c.z) & 0x1fffff);
  };
  std::unordered_map<uint64_t, std::vector<uint32_t>> cells;
  for (size_t v = 0; v < nv; ++v)
    if (rigid[v]) cells[key(cellOf(m.positions[v]))].push_back(uint32_t(v));
  for (size_t v = 0; v < nv; ++v) {
    gpu::LayerLeafRoot& e = (*out)[v];
    e.position = m.positions[v];
    e.leaf = share[v];
    if (!rigid[v]) continue;
    const glm::ivec3 c = cellOf(m.positions[v]);
    glm::dvec3 sum(0.0);
    double n = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const auto it = cells.find(key(c + glm::ivec3(dx, dy, dz)));
          if (it == cells.end()) continue;
          for (uint32_t u : it->second)
            if (glm::length(m.positions[u] - m.positions[v]) <= std::max(radiusOf[v], 1e-12f)) {
              sum += glm::dvec3(m.positions[u]);
              n += 1;
            }
        }
    if (n > 0) e.position = glm::vec3(sum / n);
  }
  return Status();
}

}  // namespace canopy
