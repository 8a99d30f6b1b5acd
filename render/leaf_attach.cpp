#include "render/leaf_attach.h"

#include <algorithm>
#include <cmath>

#include "render/plants.h"

namespace canopy {

glm::vec3 closestPointOnTriangle(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b, const glm::vec3& c) {
  const glm::vec3 ab = b - a, ac = c - a, ap = p - a;
  const float d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0.0f && d2 <= 0.0f) return a;
  const glm::vec3 bp = p - b;
  const float d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0.0f && d4 <= d3) return b;
  const float vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0f && d1 >= 0.0f && d3 <= 0.0f) return a + ab * (d1 / (d1 - d3));
  const glm::vec3 cp = p - c;
  const float d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0.0f && d5 <= d6) return c;
  const float vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0f && d2 >= 0.0f && d6 <= 0.0f) return a + ac * (d2 / (d2 - d6));
  const float va = d3 * d6 - d5 * d4;
  if (va <= 0.0f && (d4 - d3) >= 0.0f && (d5 - d6) >= 0.0f) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const float denom = va + vb + vc;
  if (!(std::abs(denom) > 0.0f)) return a;  // a degenerate triangle: its first corner
  const float v = vb / denom, w = vc / denom;
  return a + ab * v + ac * w;
}

namespace {

// A cell of the uniform grid, packed into 64 bits (21 bits an axis, offset so negatives pack).
uint64_t cellKey(const glm::ivec3& c) {
  const uint64_t m = (1u << 21) - 1u, o = 1u << 20;
  return (uint64_t(uint32_t(c.x + int32_t(o)) & m) << 42) | (uint64_t(uint32_t(c.y + int32_t(o)) & m) << 21) |
         uint64_t(uint32_t(c.z + int32_t(o)) & m);
}

glm::ivec3 cellOf(const RigidGrid& g, const glm::vec3& p) { return glm::ivec3(glm::floor((p - g.origin) / g.cell)); }

}  // namespace

RigidGrid buildRigidGrid(const VegetationModel& m, const std::vector<uint8_t>& foliage, float maxDistance) {
  RigidGrid g;
  g.model = &m;
  const size_t nt = m.triangleCount();
  const float diagonal = glm::length(m.boundsMax - m.boundsMin);
  if (foliage.size() != nt) return g;
  // Each rigid triangle's reach: kAttachShare of its own plant's height (a file of many plants; the
  // height, not the box's diagonal, so a copy turned about the vertical reaches as far).
  g.reachOf.assign(nt, maxDistance);
  if (!(maxDistance > 0.0f)) {
    const std::vector<glm::vec3> size = plantSizeOfTriangles(m);
    for (size_t t = 0; t < nt; ++t) g.reachOf[t] = kAttachShare * size[t].y;
  }
  g.reach = 0.0f;
  for (size_t t = 0; t < nt; ++t)
    if (!foliage[t] && std::isfinite(g.reachOf[t])) g.reach = std::max(g.reach, g.reachOf[t]);
  if (!(g.reach > 0.0f) || !std::isfinite(g.reach)) return g;
  // The cell: the reach, or the rigid triangles' median extent where that is larger (a big trunk
  // triangle then spans a few cells, not thousands).
  std::vector<float> extents;
  for (size_t t = 0; t < nt; ++t) {
    if (foliage[t]) continue;
    const glm::vec3 a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]], c = m.positions[m.indices[3 * t + 2]];
    const glm::vec3 e = glm::max(glm::max(a, b), c) - glm::min(glm::min(a, b), c);
    extents.push_back(std::max(std::max(e.x, e.y), e.z));
  }
  if (extents.empty()) return g;
  std::nth_element(extents.begin(), extents.begin() + std::ptrdiff_t(extents.size() / 2), extents.end());
  // At most 2^19 cells an axis across the model (the key's range).
  g.cell = std::max({g.reach, extents[extents.size() / 2], diagonal / float(1 << 19)});
  g.origin = m.boundsMin;
  for (size_t t = 0; t < nt; ++t) {
    if (foliage[t]) continue;
    const glm::vec3 a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]], c = m.positions[m.indices[3 * t + 2]];
    const glm::ivec3 lo = cellOf(g, glm::min(glm::min(a, b), c) - glm::vec3(g.reachOf[t])),
                     hi = cellOf(g, glm::max(glm::max(a, b), c) + glm::vec3(g.reachOf[t]));
    // A triangle far larger than the cells (a ground plane) is capped: it is found from the cells
    // around its corners and centre, not every cell it covers.
    const glm::ivec3 span = hi - lo + 1;
    if (uint64_t(span.x) * uint64_t(span.y) * uint64_t(span.z) > 4096u) {
      for (const glm::vec3& q : {a, b, c, (a + b + c) / 3.0f}) g.cells[cellKey(cellOf(g, q))].push_back(uint32_t(t));
      continue;
    }
    for (int z = lo.z; z <= hi.z; ++z)
      for (int y = lo.y; y <= hi.y; ++y)
        for (int x = lo.x; x <= hi.x; ++x) g.cells[cellKey({x, y, z})].push_back(uint32_t(t));
  }
  return g;
}

bool nearestRigidPoint(const RigidGrid& g, const glm::vec3& p, LeafAttachment* out) {
  if (!g.model || g.cells.empty()) return false;
  const auto it = g.cells.find(cellKey(cellOf(g, p)));
  if (it == g.cells.end()) return false;
  const VegetationModel& m = *g.model;
  bool found = false;
  for (uint32_t t : it->second) {
    const glm::vec3 q = closestPointOnTriangle(p, m.positions[m.indices[3 * t]], m.positions[m.indices[3 * t + 1]],
                                               m.positions[m.indices[3 * t + 2]]);
    const float d = glm::length(p - q);
    if (d <= g.reachOf[t] && d < out->distance) {
      out->distance = d;
      out->rigidPoint = q;
      out->triangle = t;
      found = true;
    }
  }
  return found;
}

Status findLeafAttachments(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRoots& roots, float maxDistance,
                           std::vector<LeafAttachment>* out) {
  const size_t nt = m.triangleCount(), nv = m.positions.size();
  if (foliage.size() != nt || roots.leafOfVertex.size() != nv)
    return Status::error("leaf attachments: per-triangle or per-vertex arrays disagree with the model");
  out->assign(roots.leafCount(), LeafAttachment{});
  const RigidGrid grid = buildRigidGrid(m, foliage, maxDistance);
  if (grid.cells.empty()) return Status();
  for (size_t v = 0; v < nv; ++v) {
    const uint32_t leaf = roots.leafOfVertex[v];
    if (leaf == kNoLeaf) continue;
    LeafAttachment& at = (*out)[leaf];
    if (nearestRigidPoint(grid, m.positions[v], &at)) at.vertex = uint32_t(v);
  }
  return Status();
}

Status leafLayerRoots(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                      std::vector<glm::vec3>* out, const std::vector<gpu::LayerLeafRoot>* anchors) {
  if (foliage.size() != m.triangleCount() || roots.leafOfVertex.size() != m.positions.size())
    return Status::error("leaf layer roots: per-triangle or per-vertex arrays disagree with the model");
  out->resize(roots.leafCount());
  const RigidGrid grid = buildRigidGrid(m, foliage, 0.0f);
  for (uint32_t l = 0; l < roots.leafCount(); ++l) {
    const glm::vec3 root = m.positions[roots.leafRoot[l]];
    (*out)[l] = root;
    LeafAttachment at;
    if (grid.cells.empty() || !nearestRigidPoint(grid, root, &at)) continue;
    float best = INFINITY;
    for (int k = 0; k < 3; ++k) {
      const uint32_t v = m.indices[3 * size_t(at.triangle) + size_t(k)];
      const glm::vec3 c = m.positions[v];
      const float d = glm::length(c - at.rigidPoint);
      if (d < best) {
        best = d;
        (*out)[l] = anchors && anchors->size() == m.positions.size() ? (*anchors)[v].position : c;
      }
    }
  }
  return Status();
}

}  // namespace canopy
