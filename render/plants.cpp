#include "render/plants.h"

#include <algorithm>
#include <numeric>

namespace canopy {

Status groupPlants(const VegetationModel& m, PlantGroups* out) {
  *out = PlantGroups{};
  const size_t nt = m.triangleCount();
  const bool given = !m.trianglePlant.empty() && m.trianglePlant.size() == nt;
  uint32_t groups = 1;
  if (given)
    for (uint32_t p : m.trianglePlant)
      if (p != kNoPlant) groups = std::max(groups, p + 1);
  if (groups > (1u << 24)) return Status::error("plants: " + std::to_string(groups) + " plants (at most 16777216)");
  std::vector<glm::vec3>& lo = out->lo;
  std::vector<glm::vec3>& hi = out->hi;
  lo.assign(groups, glm::vec3(INFINITY));
  hi.assign(groups, glm::vec3(-INFINITY));
  out->triangle.resize(nt);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t p = out->triangle[t] = given ? m.trianglePlant[t] : 0u;
    if (p == kNoPlant) continue;
    for (int k = 0; k < 3; ++k) {
      const glm::vec3& x = m.positions[m.indices[3 * t + size_t(k)]];
      lo[p] = glm::min(lo[p], x);
      hi[p] = glm::max(hi[p], x);
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
  for (uint32_t& g : out->triangle)
    if (g != kNoPlant) g = find(g);
  return Status();
}

std::vector<glm::vec3> plantSizeOfTriangles(const VegetationModel& m) {
  PlantGroups g;
  const size_t nt = m.triangleCount();
  const glm::vec3 whole = m.boundsMax - m.boundsMin;
  std::vector<glm::vec3> out(nt, whole);
  if (!groupPlants(m, &g).ok()) return out;
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t p = g.triangle[t];
    if (p != kNoPlant && g.lo[p].x <= g.hi[p].x) out[t] = g.hi[p] - g.lo[p];
  }
  return out;
}

Status findPlants(const VegetationModel& m, const LeafRoots& roots, Plants* out, std::vector<uint32_t>* trianglePlant,
                  const std::vector<uint8_t>& foliage) {
  *out = Plants{};
  const size_t nt = m.triangleCount();
  const bool given = !m.trianglePlant.empty() && m.trianglePlant.size() == nt;
  PlantGroups pg;
  CANOPY_TRY(groupPlants(m, &pg));
  const uint32_t groups = uint32_t(pg.lo.size());
  const std::vector<glm::vec3>& lo = pg.lo;
  const std::vector<glm::vec3>& hi = pg.hi;
  auto plantOf = [&](size_t t) { return pg.triangle[t]; };
  std::vector<uint32_t> vertexPlant(m.positions.size(), kNoPlant);
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t p = plantOf(t);
    if (p == kNoPlant) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[3 * t + size_t(k)];
      if (vertexPlant[v] == kNoPlant) vertexPlant[v] = p;
    }
  }
  // Plants with leaves, numbered densely.
  std::vector<uint32_t> dense(groups, kNoPlant);
  out->leafPlant.assign(roots.leafCount(), 0u);
  for (uint32_t leaf = 0; leaf < roots.leafCount(); ++leaf) {
    const uint32_t v = roots.leafRoot[leaf];
    const uint32_t g = v < vertexPlant.size() && vertexPlant[v] != kNoPlant ? vertexPlant[v] : kNoPlant;
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
  // Each plant's foot (vertices of a plant of no leaves, or of no plant, belong to none).
  out->footMin.assign(out->count(), glm::vec3(INFINITY));
  out->footMax.assign(out->count(), glm::vec3(-INFINITY));
  for (size_t t = 0; t < nt; ++t) {
    const uint32_t g = plantOf(t);
    const uint32_t d = g == kNoPlant ? (given ? kNoPlant : 0u) : dense[g];
    if (d == kNoPlant || d >= out->count()) continue;
    const float below = out->boundsMin[d].y + kFootShare * (out->boundsMax[d].y - out->boundsMin[d].y);
    for (int k = 0; k < 3; ++k) {
      const glm::vec3& x = m.positions[m.indices[3 * t + size_t(k)]];
      if (x.y > below) continue;
      out->footMin[d] = glm::min(out->footMin[d], x);
      out->footMax[d] = glm::max(out->footMax[d], x);
    }
  }
  for (uint32_t p = 0; p < out->count(); ++p)
    if (!(out->footMin[p].x <= out->footMax[p].x)) {  // no vertex of it counted (a whole-model plant): its box's bottom
      out->footMin[p] = out->boundsMin[p];
      out->footMax[p] = glm::vec3(out->boundsMax[p].x, out->boundsMin[p].y, out->boundsMax[p].z);
    }
  out->rigid.assign(out->count(), 0);
  if (!foliage.empty())
    for (size_t t = 0; t < nt; ++t) {
      const uint32_t g = plantOf(t);
      if (!foliage[t] && g != kNoPlant && dense[g] != kNoPlant) out->rigid[dense[g]] = 1;
    }
  if (trianglePlant) {
    trianglePlant->assign(nt, kNoPlant);
    for (size_t t = 0; t < nt; ++t) {
      const uint32_t g = plantOf(t);
      (*trianglePlant)[t] = g == kNoPlant ? kNoPlant : dense[g];
    }
  }
  return Status();
}

}  // namespace canopy
