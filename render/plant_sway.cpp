#include "render/plant_sway.h"

#include <algorithm>
#include <cmath>

namespace canopy {

Status plantSwayScales(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                       const std::vector<uint32_t>& trianglePlant, Plants* plants) {
  const uint32_t n = plants->count();
  plants->sway.assign(n, 1.0f);
  if (m.ownHierarchy || !m.bend.empty()) return Status();
  const size_t nt = m.triangleCount();
  if (foliage.size() != nt || trianglePlant.size() != nt || roots.leafOfVertex.size() != m.positions.size())
    return Status::error("plant sway: per-triangle or per-vertex arrays disagree with the model");
  std::vector<double> trunk(n, 0.0), leaf(n, 0.0), lever2D(n, 0.0);
  std::vector<uint8_t> seen(m.positions.size(), 0);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t p = trianglePlant[t];
    if (!foliage[t] || p == kNoPlant || p >= n) continue;
    const float foot = plants->boundsMin[p].y, H = std::max(plants->boundsMax[p].y - foot, 1e-9f);
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[3 * t + size_t(k)];
      if (seen[v]) continue;
      seen[v] = 1;
      const glm::vec3 x = m.positions[v];
      const float h = x.y - foot;
      if (h < H * (2.0f / 3.0f)) continue;  // the top third
      const uint32_t l = roots.leafOfVertex[v];
      trunk[p] += 0.045 * std::pow(double(h / H), 1.5) * h;
      if (l != kNoLeaf) leaf[p] += 0.3375 * glm::length(x - m.positions[roots.leafRoot[l]]);
      lever2D[p] += h;
    }
  }
  for (uint32_t p = 0; p < n; ++p)
    if (lever2D[p] > 0.0)
      plants->sway[p] = std::clamp(float(7.0 * (trunk[p] + 1.1 * leaf[p]) / lever2D[p]), kMinPlantSway, kMaxPlantSway);
  return Status();
}

}  // namespace canopy
