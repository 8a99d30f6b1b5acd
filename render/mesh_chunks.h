#pragma once
// The compact, chunked GPU form of a vegetation mesh (issue 16; docs/design.md, "Layers: mesh
// chunks"). The triangles, in the layers' GPU order (foliage by material, then rigid by material),
// are cut into chunks of at most `maxChunkVertices` distinct vertices, each drawn on its own:
// - 16-bit indices, local to the chunk;
// - positions quantised to 16 bits per axis inside the chunk's bounds (error within one step:
//   half a step of rounding plus float rounding; step = chunk extent / 65535 per axis), octahedral
//   normals as 2 x snorm16, UVs as half floats;
// - a leaf-root table per chunk (gpu::LayerLeafRoot: the root at full precision and the model-wide
//   leaf index), which vertices index with 16 bits. A leaf whose triangles fall into two chunks has
//   its root in both tables, so a chunk border never cuts a leaf, and no table is sized by the
//   whole model (the global table hit the device's storage-buffer range at ~8M leaves).
// 16 bytes per vertex and 2 per index, against 28 and 4 before, plus 16 per leaf and chunk.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "engine/status.h"
#include "render/model.h"
#include "render/leaf_roots.h"
#include "shared/layers.h"

namespace canopy {

constexpr uint32_t kMaxChunkVertices = 65535;  // 16-bit indices
// Chunk-local leaves below LAYER_CHUNK_RIGID: the field's values from it up are rigid vertices
// (shared/layers.h); a chunk's 65535 vertices hold at most 21845 leaves anyway.
constexpr uint32_t kMaxChunkLeaves = LAYER_CHUNK_RIGID;

struct MeshChunk {
  uint32_t material = 0;
  uint32_t species = 0;        // the material's species (render/species.h; materials never span species)
  bool foliage = true;
  // A rigid chunk whose every vertex follows the foliage fully (share LAYER_RIGID_FULL,
  // render/rigid_flex.h): drawn into the layers with the foliage, each triangle in the layer of its
  // anchor, where the rigid parts move with the leaves (MeshDrawOptions::carryWood).
  bool carried = false;
  uint64_t firstTriangle = 0;  // GPU-order triangle index of the chunk's first (the id output's base)
  uint32_t triangleCount = 0;
  uint64_t firstVertex = 0;    // into CompactMesh::vertices (the draw's vertexOffset)
  uint32_t vertexCount = 0;
  uint64_t firstIndex = 0;     // into CompactMesh::indices
  uint64_t firstRoot = 0;      // into CompactMesh::roots, a multiple of the root alignment
  uint32_t rootCount = 0;      // leaves with a vertex in the chunk
  // A rigid chunk's entries at firstRoot instead: one per vertex, its anchor and share
  // (CompactMeshOptions::rigidAnchors; shared/layers.h LAYER_CHUNK_RIGID); 0: none.
  uint32_t anchorCount = 0;
  uint32_t tableEntries() const { return rootCount > anchorCount ? rootCount : anchorCount; }  // bound per draw
  glm::vec3 origin{0}, scale{0};  // world position = origin + q * scale, q in 0..65535
};

struct CompactMesh {
  std::vector<gpu::LayerVertex> vertices;
  std::vector<uint16_t> indices;
  std::vector<gpu::LayerLeafRoot> roots;  // per chunk, each chunk's block aligned (bind offsets)
  std::vector<MeshChunk> chunks;          // foliage chunks first, then rigid, in GPU triangle order
  // With CompactMeshOptions::bend: the model's branch index and w per vertex, parallel to `vertices`
  // (the per-vertex wind baseline reads it at gl_VertexIndex).
  std::vector<gpu::BendVertex> bend;
  uint64_t bytes() const {
    return vertices.size() * sizeof(gpu::LayerVertex) + indices.size() * 2 + roots.size() * sizeof(gpu::LayerLeafRoot) +
           bend.size() * sizeof(gpu::BendVertex);
  }
};

struct CompactMeshOptions {
  uint32_t maxChunkVertices = kMaxChunkVertices;  // 3..65535
  uint32_t rootAlignment = 1;  // chunk root blocks start at multiples of this many entries (>= 1)
  bool bend = false;           // also CompactMesh::bend (the model must have VegetationModel::bend)
  // Per model vertex, a rigid vertex's anchor and share (render/rigid_flex.h): the rigid chunks'
  // root tables hold one entry per chunk vertex, which the vertex's leaf field names (at most
  // LAYER_RIGID_FULL + 1 vertices a rigid chunk then); null or empty: none (LAYER_CHUNK_NO_LEAF).
  const std::vector<gpu::LayerLeafRoot>* rigidAnchors = nullptr;
  // Per model leaf, the root position its layer is decided by (render/leaf_attach.h
  // leafLayerRoots: the rigid corner it grows from); null or empty: its root vertex's.
  const std::vector<glm::vec3>* leafRootPositions = nullptr;
};

// One draw range of the GPU order: `count` triangles from `first`, all of `material`.
struct TriangleRange {
  uint32_t material = 0;
  bool foliage = true;
  uint64_t first = 0, count = 0;
  bool carried = false;  // rigid triangles that follow the foliage fully (MeshChunk::carried)
};

// Builds the compact mesh of model `m` whose triangles in GPU order are `triangleOrder` (GPU
// triangle -> model triangle; empty: the model's own order) cut into `ranges` (GPU triangle
// numbers); `roots` from computeLeafRoots (its leafOfVertex and leafRoot). Errors name the model
// and the offending vertex (a texture coordinate outside the half-float range, a non-finite
// position) or option. `progress` (optional) gets ("vertices", triangles done, total) about every
// million triangles. Working memory besides the output: two fixed tables of 2^17 slots.
Status buildCompactMesh(const VegetationModel& m, const std::vector<uint32_t>& triangleOrder,
                        const std::vector<TriangleRange>& ranges, const LeafRoots& roots,
                        const CompactMeshOptions& options, CompactMesh* out, const Progress& progress = {});
// The decoding the vertex shader does (tests and tools): world position, unit normal, UV.
glm::vec3 decodePosition(const MeshChunk& c, const gpu::LayerVertex& v);
glm::vec3 decodeNormal(const gpu::LayerVertex& v);
glm::vec2 decodeUv(const gpu::LayerVertex& v);
uint32_t chunkLeaf(const gpu::LayerVertex& v);  // chunk-local leaf, LAYER_CHUNK_NO_LEAF for none (a rigid vertex)
uint32_t chunkRigidEntry(const gpu::LayerVertex& v);  // a rigid vertex's root-table entry, or LAYER_CHUNK_NO_LEAF

}  // namespace canopy
