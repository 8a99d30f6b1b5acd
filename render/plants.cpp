#include "render/plants.h"

#include <algorithm>
#include <numeric>

namespace canopy {

Status findPlants(const VegetationModel& m, const LeafRoots& roots, Plants* out, std::vector<uint32_t>* trianglePlant,
                  const std::vector<uint8_t>& foliage) {
  *out = Plants{};
  const size_t nt = m.triangleCount();
  const bool given = !m.trianglePlant.empty() && m.trianglePlant.size() == nt;
  uint32_t groups = 1;
  if (given)
    for (uint32_t p : m.trianglePlant)
      if (p != kNoPlant) groups = std::max(groups, p + 1);
  if (groups > (1u << 24)) return Status::error("plants: " + std::to_string(groups) + " plants (at most 16777216)");
  auto plantOf = [&](size_t t) { return given ? m.trianglePlant[t] : 0u; };
  std::vector<glm::vec3> lo(groups, glm::vec3(INFINITY)), hi(groups, glm::vec3(-INFINITY));
  std::vector<uint32_t> vertexPlant(m.positions.size(), kNoPlant);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t p = plantOf(t);
    if (p == kNoPlant) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[3 * t + size_t(k)];
      lo[p] = glm::min(lo[p], m.positions[v]);
      hi[p] = glm::max(hi[p], m.positions[v]);
      if (vertexPlant[v] == kNoPlant) vertexPlant[v] = p;
    }
  }
  // Union of groups whose boxes overlap on the ground plane (x, z), when asked: a file's root nodes
  // may be the parts of one plant (a pot, a stem, leaves) rather than plants standing apart.
  std::vector<uint32_t> parent(groups);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  if (m.mergeOverlappingPlants && groups <= 4096)
    for (bool merged = true; merged;) {  // until no two merged boxes overlap
      merged = false;
      for (uint32_t a = 0; a < groups; ++a)
        for (uint32_t b = a + 1; b < groups; ++b) {
          const uint32_t ra = find(a), rb = find(b);
          if (ra == rb || !(lo[ra].x <= hi[rb].x && lo[rb].x <= hi[ra].x && lo[ra].z <= hi[rb].z && lo[rb].z <= hi[ra].z)) continue;
          parent[rb] = ra;
          lo[ra] = glm::min(lo[ra], lo[rb]);
          hi[ra] = glm::max(hi[ra], hi[rb]);
          merged = true;
        }
    }
  else if (m.mergeOverlappingPlants) {  // too many root nodes to compare: one plant
    std::fill(parent.begin(), parent.end(), 0u);
    lo.assign(groups, glm::vec3(INFINITY));
    hi.assign(groups, glm::vec3(-INFINITY));
    lo[0] = m.boundsMin;
    hi[0] = m.boundsMax;
  }
  // Plants with leaves, numbered densely.
  std::vector<uint32_t> dense(groups, kNoPlant);
  out->leafPlant.assign(roots.leafCount(), 0u);
  for (uint32_t leaf = 0; leaf < roots.leafCount(); ++leaf) {
    const uint32_t v = roots.leafRoot[leaf];
    const uint32_t g = v < vertexPlant.size() && vertexPlant[v] != kNoPlant ? find(vertexPlant[v]) : kNoPlant;
    if (g == kNoPlant) {
      out->leafPlant[leaf] = kNoPlant;
      continue;
    }
    if (dense[g] == kNoPlant) {
      dense[g] = out->count();
      out->boundsMin.push_back(lo[g]);
      out->boundsMax.push_back(hi[g]);
    }
    out->leafPlant[leaf] = dense[g];
  }
  // Leaves of no plant (a leaf on the ground's triangles only): the first plant, or a plant of the whole model.
  if (out->count() == 0) {
    out->boundsMin.push_back(m.boundsMin);
    out->boundsMax.push_back(m.boundsMax);
  }
  for (uint32_t& p : out->leafPlant)
    if (p == kNoPlant) p = 0;
  out->rigid.assign(out->count(), 0);
  if (!foliage.empty())
    for (size_t t = 0; t < nt; ++t) {
      const uint32_t g = plantOf(t);
      if (!foliage[t] && g != kNoPlant && dense[find(g)] != kNoPlant) out->rigid[dense[find(g)]] = 1;
    }
  if (trianglePlant) {
    trianglePlant->assign(nt, kNoPlant);
    for (size_t t = 0; t < nt; ++t) {
      const uint32_t g = plantOf(t);
      (*trianglePlant)[t] = g == kNoPlant ? kNoPlant : dense[find(g)];
    }
  }
  return Status();
}

}  // namespace canopy
