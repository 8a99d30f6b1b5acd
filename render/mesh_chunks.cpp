#include "render/mesh_chunks.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <glm/gtc/packing.hpp>

namespace canopy {
namespace {

// Octahedral encoding (Meyer et al. 2010, "On floating-point normal vectors"): the unit sphere
// folded onto [-1, 1]^2; gpu::layerDecodeNormal (shared/layers.h) undoes it.
glm::vec2 octahedral(glm::vec3 n) {
  const float l1 = std::abs(n.x) + std::abs(n.y) + std::abs(n.z);
  if (!(l1 > 0.0f) || !std::isfinite(l1)) return glm::vec2(0.0f, 0.0f);  // no normal: +Z
  n /= l1;
  glm::vec2 e(n.x, n.y);
  if (n.z < 0.0f)
    e = (1.0f - glm::abs(glm::vec2(n.y, n.x))) * glm::vec2(n.x >= 0.0f ? 1.0f : -1.0f, n.y >= 0.0f ? 1.0f : -1.0f);
  return e;
}

std::string modelName(const VegetationModel& m) { return m.path.empty() ? std::string("the model") : m.path; }

uint64_t alignUp(uint64_t v, uint64_t a) { return (v + a - 1) / a * a; }

// Chunk-local numbers of model vertices (or leaves): an open-addressing table of 2^17 slots for
// the at most 65535 entries of one chunk, an entry valid only while its stamp is the current
// chunk's. Its size does not depend on the model (issue 16: a bounded working set; per-vertex
// arrays cost 15 bytes a face at 50M faces).
class ChunkLocal {
 public:
  static constexpr uint32_t kBits = 17, kMask = (1u << kBits) - 1;
  ChunkLocal() : key_(1u << kBits), stamp_(1u << kBits, 0), local_(1u << kBits) {}
  // The chunk-local number of `x` in chunk `stamp`, or kNoLeaf when it has none yet.
  uint32_t find(uint32_t x, uint32_t stamp) const {
    for (uint32_t i = slot(x);; i = (i + 1) & kMask) {
      if (stamp_[i] != stamp) return kNoLeaf;
      if (key_[i] == x) return local_[i];
    }
  }
  void insert(uint32_t x, uint32_t stamp, uint32_t local) {
    uint32_t i = slot(x);
    while (stamp_[i] == stamp) i = (i + 1) & kMask;
    key_[i] = x;
    stamp_[i] = stamp;
    local_[i] = local;
  }

 private:
  static uint32_t slot(uint32_t x) { return (x * 0x9E3779B1u) >> (32 - kBits); }
  std::vector<uint32_t> key_, stamp_, local_;
};

}  // namespace

glm::vec3 decodePosition(const MeshChunk& c, const gpu::LayerVertex& v) {
  const glm::vec3 q(float(v.positionXY & 0xffffu), float(v.positionXY >> 16), float(v.positionZLeaf & 0xffffu));
  return c.origin + q * c.scale;
}

glm::vec3 decodeNormal(const gpu::LayerVertex& v) { return gpu::layerDecodeNormal(glm::unpackSnorm2x16(v.normal)); }

glm::vec2 decodeUv(const gpu::LayerVertex& v) { return glm::unpackHalf2x16(v.uv); }

uint32_t chunkLeaf(const gpu::LayerVertex& v) {
  const uint32_t field = v.positionZLeaf >> 16;
  return gpu::layerFieldIsLeaf(field) ? field : LAYER_CHUNK_NO_LEAF;
}

uint32_t chunkRigidEntry(const gpu::LayerVertex& v) { return gpu::layerRigidEntry(v.positionZLeaf >> 16); }

namespace {

// The options and the per-vertex and per-triangle arrays buildCompactMesh reads, checked.
Status checkCompactMeshInput(const VegetationModel& m, const std::vector<uint32_t>& triangleOrder, const LeafRoots& roots,
                             const CompactMeshOptions& o) {
  if (o.maxChunkVertices < 3 || o.maxChunkVertices > kMaxChunkVertices)
    return Status::error("mesh chunks: maxChunkVertices " + std::to_string(o.maxChunkVertices) + " is outside 3.." +
                         std::to_string(kMaxChunkVertices));
  if (o.rootAlignment < 1 || o.rootAlignment > 4096)
    return Status::error("mesh chunks: rootAlignment " + std::to_string(o.rootAlignment) + " is outside 1..4096");
  const size_t nv = m.positions.size(), nt = m.indices.size() / 3;
  if (roots.leafOfVertex.size() != nv || m.uvs.size() != nv)
    return Status::error("mesh chunks: " + modelName(m) + ": per-vertex arrays disagree with the vertex count");
  if (o.bend && m.bend.size() != nv)
    return Status::error("mesh chunks: " + modelName(m) + ": the branch hierarchy has " + std::to_string(m.bend.size()) +
                         " vertices for " + std::to_string(nv));
  if (!triangleOrder.empty() && triangleOrder.size() != nt)
    return Status::error("mesh chunks: the triangle order has " + std::to_string(triangleOrder.size()) + " entries for " +
                         std::to_string(nt) + " triangles");
  return Status();
}

}  // namespace

Status buildCompactMesh(const VegetationModel& m, const std::vector<uint32_t>& triangleOrder,
                        const std::vector<TriangleRange>& ranges, const LeafRoots& roots,
                        const CompactMeshOptions& o, CompactMesh* out, const Progress& progress) {
  *out = CompactMesh{};
  CANOPY_TRY(checkCompactMeshInput(m, triangleOrder, roots, o));
  const size_t nv = m.positions.size(), nt = m.indices.size() / 3;
  // Model vertex k (0..2) of GPU triangle t.
  auto corner = [&](uint64_t t, int k) -> uint32_t {
    const uint64_t mt = triangleOrder.empty() ? t : triangleOrder[t];
    return mt < nt ? m.indices[mt * 3 + k] : uint32_t(nv);
  };
  // Chunk-local numbers of vertices and leaves (stamp = the current chunk + 1).
  ChunkLocal vLocal, lLocal;
  std::vector<uint32_t> chunkVertices, chunkLeaves;
  // The output's sizes, reserved so that growing them never holds two copies (2.2 GB at 50M faces):
  // indices exactly; vertices and roots the model's, plus a margin for those repeated in two chunks.
  uint64_t triangles = 0;
  for (const TriangleRange& r : ranges) triangles += r.count;
  out->indices.reserve(3 * triangles);
  out->vertices.reserve(nv + nv / 32 + kMaxChunkVertices);
  if (o.bend) out->bend.reserve(out->vertices.capacity());
  out->roots.reserve(roots.leafCount() + roots.leafCount() / 32 + 65536);
  uint32_t stamp = 0;
  MeshChunk cur;
  // The leaf a vertex brings into the chunk's root table (foliage chunks only).
  auto chunkLeafOf = [&](uint32_t v) -> uint32_t { return cur.foliage ? roots.leafOfVertex[v] : kNoLeaf; };
  const bool anchors = o.rigidAnchors && o.rigidAnchors->size() == nv;
  const bool rootPositions = o.leafRootPositions && o.leafRootPositions->size() == roots.leafCount();
  auto open = [&](const TriangleRange& r, uint64_t firstTriangle) {
    ++stamp;
    cur = MeshChunk{};
    cur.material = r.material;
    cur.foliage = r.foliage;
    cur.carried = !r.foliage && r.carried;
    cur.firstTriangle = firstTriangle;
    cur.firstIndex = out->indices.size();
    cur.firstVertex = out->vertices.size();
    chunkVertices.clear();
    chunkLeaves.clear();
  };
  auto close = [&]() -> Status {
    if (cur.triangleCount == 0) return Status();
    glm::vec3 lo(INFINITY), hi(-INFINITY);
    for (uint32_t v : chunkVertices) {
      lo = glm::min(lo, m.positions[v]);
      hi = glm::max(hi, m.positions[v]);
    }
    cur.origin = lo;
    cur.scale = (hi - lo) / 65535.0f;
    const glm::vec3 inv(cur.scale.x > 0 ? 1.0f / cur.scale.x : 0.0f, cur.scale.y > 0 ? 1.0f / cur.scale.y : 0.0f,
                        cur.scale.z > 0 ? 1.0f / cur.scale.z : 0.0f);
    cur.vertexCount = uint32_t(chunkVertices.size());
    for (size_t local = 0; local < chunkVertices.size(); ++local) {
      const uint32_t v = chunkVertices[local];
      const glm::vec3 q = glm::clamp(glm::round((m.positions[v] - lo) * inv), glm::vec3(0.0f), glm::vec3(65535.0f));
      // A rigid chunk's vertices name their own root-table entry (anchor and share), not a leaf (a
      // vertex a leaf shares with the trunk is drawn there as trunk).
      uint32_t leaf = LAYER_CHUNK_NO_LEAF;
      if (cur.foliage) {
        if (roots.leafOfVertex[v] != kNoLeaf) leaf = lLocal.find(roots.leafOfVertex[v], stamp);
      } else if (anchors) {
        leaf = LAYER_CHUNK_RIGID | uint32_t(local);
      }
      const glm::vec2 uv = m.uvs[v];
      if (!(std::abs(uv.x) <= 65504.0f && std::abs(uv.y) <= 65504.0f))
        return Status::error(modelName(m) + ": vertex " + std::to_string(v) + " has texture coordinate (" +
                             std::to_string(uv.x) + ", " + std::to_string(uv.y) +
                             ") outside the half-float range [-65504, 65504] of the compact mesh");
      gpu::LayerVertex x;
      x.positionXY = uint32_t(q.x) | uint32_t(q.y) << 16;
      x.positionZLeaf = uint32_t(q.z) | leaf << 16;
      x.normal = glm::packSnorm2x16(octahedral(v < m.normals.size() ? m.normals[v] : glm::vec3(0, 0, 1)));
      x.uv = glm::packHalf2x16(uv);
      out->vertices.push_back(x);
      if (o.bend) out->bend.push_back(m.bend[v]);
    }
    // Root blocks start aligned so each chunk's block can be bound at its own offset; a chunk
    // without leaves still gets one (unused) entry, since a binding's range cannot be 0.
    cur.firstRoot = alignUp(out->roots.size(), o.rootAlignment);
    cur.rootCount = uint32_t(chunkLeaves.size());
    if (!cur.foliage && anchors) {  // a rigid chunk: an entry per vertex, its anchor and share
      cur.rootCount = 0;
      cur.anchorCount = uint32_t(chunkVertices.size());
      out->roots.resize(cur.firstRoot + chunkVertices.size(), gpu::LayerLeafRoot{});
      for (size_t i = 0; i < chunkVertices.size(); ++i) out->roots[cur.firstRoot + i] = (*o.rigidAnchors)[chunkVertices[i]];
      out->chunks.push_back(cur);
      return Status();
    }
    out->roots.resize(cur.firstRoot + std::max<size_t>(chunkLeaves.size(), 1), gpu::LayerLeafRoot{});
    for (size_t i = 0; i < chunkLeaves.size(); ++i) {
      gpu::LayerLeafRoot& r = out->roots[cur.firstRoot + i];
      r.position = rootPositions ? (*o.leafRootPositions)[chunkLeaves[i]] : m.positions[roots.leafRoot[chunkLeaves[i]]];
      r.leaf = chunkLeaves[i];
    }
    out->chunks.push_back(cur);
    return Status();
  };
  for (const TriangleRange& r : ranges) {
    if (r.first + r.count > nt)
      return Status::error("mesh chunks: triangle range past the index list");
    open(r, r.first);
    for (uint64_t t = r.first; t < r.first + r.count; ++t) {
      if (progress && (t & 0xfffff) == 0) progress("vertices", t, nt);
      // New vertices and leaves this triangle would add to the chunk.
      uint32_t newV = 0, newL = 0;
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = corner(t, k);
        if (v >= nv) return Status::error("mesh chunks: " + modelName(m) + ": index " + std::to_string(v) + " past the vertices");
        if (!std::isfinite(m.positions[v].x) || !std::isfinite(m.positions[v].y) || !std::isfinite(m.positions[v].z))
          return Status::error(modelName(m) + ": vertex " + std::to_string(v) + " has a non-finite position");
        bool seen = vLocal.find(v, stamp) != kNoLeaf;
        for (int j = 0; j < k; ++j) seen = seen || corner(t, j) == v;
        newV += !seen;
        const uint32_t leaf = chunkLeafOf(v);
        if (leaf != kNoLeaf && !seen && lLocal.find(leaf, stamp) == kNoLeaf) ++newL;  // over-counts a leaf new twice: harmless
      }
      // A rigid chunk with anchors names each vertex's entry in 15 bits.
      const size_t maxVertices = !cur.foliage && anchors ? std::min<size_t>(o.maxChunkVertices, LAYER_RIGID_FULL + 1) : o.maxChunkVertices;
      if (cur.triangleCount > 0 && (chunkVertices.size() + newV > maxVertices || chunkLeaves.size() + newL > kMaxChunkLeaves - 1)) {
        CANOPY_TRY(close());
        open(r, t);
      }
      for (int k = 0; k < 3; ++k) {
        const uint32_t v = corner(t, k);
        uint32_t local = vLocal.find(v, stamp);
        if (local == kNoLeaf) {
          local = uint32_t(chunkVertices.size());
          vLocal.insert(v, stamp, local);
          chunkVertices.push_back(v);
          const uint32_t leaf = chunkLeafOf(v);
          if (leaf != kNoLeaf && lLocal.find(leaf, stamp) == kNoLeaf) {
            lLocal.insert(leaf, stamp, uint32_t(chunkLeaves.size()));
            chunkLeaves.push_back(leaf);
          }
        }
        out->indices.push_back(uint16_t(local));
      }
      cur.triangleCount++;
    }
    CANOPY_TRY(close());
  }
  if (progress) progress("vertices", nt, nt);
  return Status();
}

}  // namespace canopy
