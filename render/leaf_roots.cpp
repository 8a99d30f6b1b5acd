#include "render/leaf_roots.h"

#include "engine/files.h"
#include "engine/hash.h"
#include "render/cache_file.h"
#include "render/leaf_attach.h"

#include <cstring>

namespace canopy {
namespace {

uint32_t findRoot(std::vector<uint32_t>& parent, uint32_t x) {
  while (parent[x] != x) {
    parent[x] = parent[parent[x]];  // path halving
    x = parent[x];
  }
  return x;
}

// Union by rank (a byte: ranks stay below 64) keeps the trees shallow at 1 byte a vertex, not 4.
void unite(std::vector<uint32_t>& parent, std::vector<uint8_t>& rank, uint32_t a, uint32_t b) {
  a = findRoot(parent, a);
  b = findRoot(parent, b);
  if (a == b) return;
  if (rank[a] < rank[b]) std::swap(a, b);
  parent[b] = a;
  if (rank[a] == rank[b]) rank[a]++;
}

uint32_t floatKey(float f) {
  if (f == 0.0f) f = 0.0f;  // -0 and +0 weld
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}

uint64_t hashPosition(const glm::vec3& p) {
  return mix64((uint64_t(floatKey(p.x)) << 32 | floatKey(p.y)) ^ mix64(floatKey(p.z) + 0x9e3779b97f4a7c15ull));
}

}  // namespace

// A leaf that meets the rigid parts is rooted at its vertex nearest them, unless its paper root
// (smallest u, v) already lies on them (docs/design.md "Rigid parts in wind").
Status rootAtAttachments(const VegetationModel& m, const std::vector<uint8_t>& foliage, LeafRoots* r) {
  std::vector<LeafAttachment> at;
  CANOPY_TRY(findLeafAttachments(m, foliage, *r, 0.0f, &at));
  const RigidGrid grid = buildRigidGrid(m, foliage, 0.0f);
  std::vector<uint32_t> newRoot(r->leafCount(), kNoLeaf);
  bool any = false;
  for (uint32_t l = 0; l < r->leafCount(); ++l) {
    if (at[l].vertex == kNoLeaf || at[l].vertex == r->leafRoot[l]) continue;
    LeafAttachment own;
    if (nearestRigidPoint(grid, m.positions[r->leafRoot[l]], &own)) continue;  // the paper's root is on a branch
    newRoot[l] = at[l].vertex;
    any = true;
  }
  if (!any) return Status();
  for (size_t v = 0; v < r->rootOfVertex.size(); ++v) {
    const uint32_t l = r->leafOfVertex[v];
    if (l != kNoLeaf && newRoot[l] != kNoLeaf) r->rootOfVertex[v] = newRoot[l];
  }
  indexLeaves(r);
  return Status();
}

void indexLeaves(LeafRoots* r) {
  const size_t n = r->rootOfVertex.size();
  r->leafOfVertex.assign(n, kNoLeaf);
  r->leafRoot.clear();
  for (size_t v = 0; v < n; ++v)
    if (r->rootOfVertex[v] == v) {
      r->leafOfVertex[v] = uint32_t(r->leafRoot.size());
      r->leafRoot.push_back(uint32_t(v));
    }
  for (size_t v = 0; v < n; ++v) {
    const uint32_t root = r->rootOfVertex[v];
    if (root != kNoLeaf) r->leafOfVertex[v] = r->leafOfVertex[root];
  }
}

Status computeLeafRoots(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRootOptions& o,
                        LeafRoots* out, const Progress& progress) {
  *out = LeafRoots{};
  const size_t nv = m.positions.size(), nt = m.indices.size() / 3;
  if (m.indices.size() % 3) return Status::error("leaf roots: index count " + std::to_string(m.indices.size()) + " is not a multiple of 3");
  if (foliage.size() != nt)
    return Status::error("leaf roots: foliage mask has " + std::to_string(foliage.size()) + " entries for " +
                         std::to_string(nt) + " triangles");
  if (m.uvs.size() != nv) return Status::error("leaf roots: " + std::to_string(m.uvs.size()) + " uvs for " + std::to_string(nv) + " vertices");
  if (nv >= kNoLeaf) return Status::error("leaf roots: too many vertices");
  // Progress over the four linear passes: triangles (union), vertices (weld), vertices (roots), vertices (assign).
  const uint64_t work = uint64_t(nt) + 3ull * nv;
  auto report = [&](uint64_t done) {
    if (progress) progress("leaf roots", done, work);
  };
  // Working memory (issue 16: preparation memory): parent (4 bytes a vertex, which becomes the
  // output's rootOfVertex), rank and use (1 each) and the weld table (about 6 bytes a used vertex,
  // freed before the roots are chosen). The result does not depend on the union order.
  std::vector<uint32_t> parent(nv);
  for (size_t v = 0; v < nv; ++v) parent[v] = uint32_t(v);
  std::vector<uint8_t> used(nv, 0);
  {
    std::vector<uint8_t> rank(nv, 0);
    for (size_t t = 0; t < nt; ++t) {
      if ((t & 0xfffff) == 0) report(t);
      if (!foliage[t]) continue;
      const uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], c = m.indices[3 * t + 2];
      if (a >= nv || b >= nv || c >= nv)
        return Status::error("leaf roots: triangle " + std::to_string(t) + " indexes past the " + std::to_string(nv) + " vertices");
      used[a] = used[b] = used[c] = 1;
      unite(parent, rank, a, b);
      unite(parent, rank, b, c);
    }
    if (o.weldPositions) {
      size_t usedCount = 0;
      for (uint8_t u : used) usedCount += u;
      // Open addressing with linear probing at a load of at most 2/3; the slot is the hash scaled
      // to the table (any size, not a power of two).
      const uint64_t cap = std::max<uint64_t>(16, usedCount + usedCount / 2);
      std::vector<uint32_t> table(cap, kNoLeaf);  // vertex index
      for (size_t v = 0; v < nv; ++v) {
        if ((v & 0xfffff) == 0) report(nt + v);
        if (!used[v]) continue;
        uint64_t slot = uint64_t((unsigned __int128)hashPosition(m.positions[v]) * cap >> 64);
        for (;; slot = slot + 1 == cap ? 0 : slot + 1) {
          const uint32_t other = table[slot];
          if (other == kNoLeaf) {
            table[slot] = uint32_t(v);
            break;
          }
          const glm::vec3 &p = m.positions[v], &q = m.positions[other];
          if (floatKey(p.x) == floatKey(q.x) && floatKey(p.y) == floatKey(q.y) && floatKey(p.z) == floatKey(q.z)) {
            unite(parent, rank, uint32_t(v), other);
            break;
          }
        }
      }
    }
  }
  // Every used vertex points at its component's representative, marked used = 2.
  for (size_t v = 0; v < nv; ++v)
    if (used[v]) {
      const uint32_t c = findRoot(parent, uint32_t(v));
      parent[v] = c;
      used[c] = 2;
    }
  // Root: smallest (u, v) in each component (u first, then v, then the lower index), kept in the
  // representative's own entry (it starts as the representative itself).
  auto before = [&](uint32_t a, uint32_t b) {
    const glm::vec2 ua = m.uvs[a], ub = m.uvs[b];
    return ua.x < ub.x || (ua.x == ub.x && (ua.y < ub.y || (ua.y == ub.y && a < b)));
  };
  for (size_t v = 0; v < nv; ++v) {
    if ((v & 0xfffff) == 0) report(nt + nv + v);
    if (used[v] != 1) continue;
    const uint32_t c = parent[v];
    if (before(uint32_t(v), parent[c])) parent[c] = uint32_t(v);
  }
  // In place: a representative's entry already holds its root; every other vertex takes it.
  for (size_t v = 0; v < nv; ++v) {
    if ((v & 0xfffff) == 0) report(nt + 2 * nv + v);
    if (!used[v]) parent[v] = kNoLeaf;
    else if (used[v] == 1) parent[v] = parent[parent[v]];
  }
  out->rootOfVertex = std::move(parent);
  report(work);
  indexLeaves(out);
  if (o.attachRoots) CANOPY_TRY(rootAtAttachments(m, foliage, out));
  return Status();
}

uint64_t leafRootKey(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRootOptions& o) {
  uint64_t h = 0x6a09e667f3bcc909ull ^ (o.weldPositions ? 1 : 2) ^ (o.attachRoots ? 4 : 0);
  h = hashBytes(h, m.positions.data(), m.positions.size() * sizeof(glm::vec3));
  h = hashBytes(h, m.uvs.data(), m.uvs.size() * sizeof(glm::vec2));
  h = hashBytes(h, m.indices.data(), m.indices.size() * sizeof(uint32_t));
  h = hashBytes(h, foliage.data(), foliage.size());
  // The attachment reach is a share of each plant's height (render/leaf_attach.h): the plants too,
  // and the rule's revision (2: per plant, issue 77).
  if (o.attachRoots) {
    h = hashBytes(h ^ (0x2ull << 8), m.trianglePlant.data(), m.trianglePlant.size() * sizeof(uint32_t));
    h ^= m.mergeOverlappingPlants ? 0x100000ull : 0;
  }
  return h;
}

std::string leafRootCachePath(const std::string& modelPath, const std::string& cacheDir) {
  return cacheFilePath(modelPath, cacheDir.empty() ? parentFolder(modelPath) : cacheDir, CacheKind::LeafRoots);
}

bool readLeafRootCache(const std::string& path, uint64_t key, size_t nv, LeafRoots* out, std::string* why) {
  *out = LeafRoots{};
  std::vector<uint8_t> payload;
  if (!readCacheFile(path, CacheKind::LeafRoots, key, uint64_t(nv) * 4, &payload, why)) return false;
  out->rootOfVertex.resize(nv);
  std::memcpy(out->rootOfVertex.data(), payload.data(), nv * 4);
  // A root must be in range and be its own root: a file that passed the checksum but was made
  // with other rules (or by hand) must not index out of range later.
  for (size_t v = 0; v < nv; ++v) {
    const uint32_t r = out->rootOfVertex[v];
    if (r != kNoLeaf && (r >= nv || out->rootOfVertex[r] != r)) {
      *why = "inconsistent contents";
      out->rootOfVertex.clear();
      return false;
    }
  }
  indexLeaves(out);
  return true;
}

Status writeLeafRootCache(const std::string& path, uint64_t key, const LeafRoots& r, uint64_t capBytes, std::string* note) {
  return writeCacheFile(path, CacheKind::LeafRoots, key, r.rootOfVertex.data(), uint64_t(r.rootOfVertex.size()) * 4, capBytes, note);
}

}  // namespace canopy
