#include "render/plant_sway.h"

#include <algorithm>
#include <cmath>

namespace canopy {

Status plantLevers(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                   const std::vector<uint32_t>& trianglePlant, const Plants& plants, std::vector<PlantLevers>* out) {
  const uint32_t n = plants.count();
  out->assign(n, PlantLevers{});
  const size_t nt = m.triangleCount();
  if (foliage.size() != nt || trianglePlant.size() != nt || roots.leafOfVertex.size() != m.positions.size())
    return Status::error("plant sway: per-triangle or per-vertex arrays disagree with the model");
  // The baseline's fallback trunk: the model's box (render/per_vertex.cpp bendTrunkOf).
  const glm::vec3 axis(0.5f * (m.boundsMin.x + m.boundsMax.x), 0.0f, 0.5f * (m.boundsMin.z + m.boundsMax.z));
  const float R = std::max(0.5f * glm::length(glm::vec2(m.boundsMax.x - m.boundsMin.x, m.boundsMax.z - m.boundsMin.z)), 1e-9f);
  std::vector<double> lever2D(n, 0.0);
  std::vector<uint8_t> seen(m.positions.size(), 0);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t p = trianglePlant[t];
    if (!foliage[t] || p == kNoPlant || p >= n) continue;
    const float foot = plants.boundsMin[p].y, H = std::max(plants.boundsMax[p].y - foot, 1e-9f);
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[3 * t + size_t(k)];
      if (seen[v]) continue;
      seen[v] = 1;
      const glm::vec3 x = m.positions[v];
      const float h = x.y - foot;
      if (h < H * (2.0f / 3.0f)) continue;  // the top third
      const uint32_t l = roots.leafOfVertex[v];
      const glm::vec3 r = l == kNoLeaf ? x : m.positions[roots.leafRoot[l]];
      PlantLevers& L = (*out)[p];
      L.trunk += 0.045 * std::pow(double(h / H), 1.5) * h;
      const float radial = std::min(glm::length(glm::vec2(r.x - axis.x, r.z - axis.z)) / R, 1.0f);
      L.branch += 0.079 * std::pow(double(radial), 1.5) * glm::length(x - glm::vec3(axis.x, r.y, axis.z));
      L.leaf += 0.3375 * glm::length(x - r);
      lever2D[p] += h;
    }
  }
  for (uint32_t p = 0; p < n; ++p) {
    PlantLevers& L = (*out)[p];
    if (lever2D[p] <= 0.0) continue;
    L.trunk /= lever2D[p];
    L.branch /= lever2D[p];
    L.leaf /= lever2D[p];
    L.measured = true;
  }
  return Status();
}

Status plantSwayScales(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                       const std::vector<uint32_t>& trianglePlant, Plants* plants) {
  plants->sway.assign(plants->count(), 1.0f);
  if (m.ownHierarchy || !m.bend.empty()) return Status();
  std::vector<PlantLevers> levers;
  CANOPY_TRY(plantLevers(m, foliage, roots, trianglePlant, *plants, &levers));
  for (uint32_t p = 0; p < plants->count(); ++p)
    if (levers[p].measured) plants->sway[p] = plantSwayScale(levers[p]);
  return Status();
}

float plantSwayScale(const PlantLevers& L) {
  return std::clamp(float(kSwayTrunk * L.trunk + kSwayBranch * L.branch + kSwayLeaf * L.leaf), kMinPlantSway, kMaxPlantSway);
}

}  // namespace canopy
