#pragma once
// Leaf-root preprocessing (paper 3.2, done once per model): the foliage mesh is split into leaves
// (connected components through shared indices and, optionally, through vertices at equal
// positions, since exporters split vertices along UV seams and some models share none), and each
// leaf gets a root vertex: the one with the smallest (u, v), compared u first then v, ties by
// index. The vertex shader reads the root of each vertex's leaf and puts the whole leaf into the
// layer of the root's depth, so no leaf is ever cut.
//
// Cost: linear time; memory 6 bytes a vertex plus about 6 a used vertex while welding, beside the
// output (union-find with path halving and union by rank over the index buffer, its parent array
// becoming rootOfVertex; welding through an open-addressing hash of positions). A leaf's triangles
// may lie anywhere in a glTF index buffer, so the components need the whole mesh at once. The result can be cached in a
// file (render/cache_file.h), keyed by a hash of everything it depends on.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/status.h"
#include "render/model.h"

namespace canopy {

inline constexpr uint32_t kNoLeaf = 0xffffffffu;

// LeafRootOptions: <canopy/canopy_params.h>.
struct LeafRoots {
  std::vector<uint32_t> rootOfVertex;  // per vertex: its leaf's root vertex; kNoLeaf if no foliage triangle uses it
  std::vector<uint32_t> leafOfVertex;  // per vertex: compact leaf index 0..leafCount-1, or kNoLeaf
  std::vector<uint32_t> leafRoot;      // per leaf: its root vertex (leaves numbered by first root index)
  uint32_t leafCount() const { return uint32_t(leafRoot.size()); }
};

// Components of the triangles with triangleIsFoliage[t] != 0. Errors on inconsistent sizes or
// indices past the vertex count (a model from loadGltf has neither).
Status computeLeafRoots(const VegetationModel& model, const std::vector<uint8_t>& triangleIsFoliage,
                        const LeafRootOptions& options, LeafRoots* out, const Progress& progress = {});

// Fills leafOfVertex and leafRoot from rootOfVertex (used after loading a cache).
void indexLeaves(LeafRoots* roots);
// LeafRootOptions.attachRoots: each leaf that meets the rigid parts (render/leaf_attach.h) and
// whose root does not, rooted at its vertex nearest them; leaves renumbered (indexLeaves).
Status rootAtAttachments(const VegetationModel& model, const std::vector<uint8_t>& triangleIsFoliage, LeafRoots* roots);

// A hash of everything the roots depend on (positions, uvs, indices, the foliage mask, options).
uint64_t leafRootKey(const VegetationModel& model, const std::vector<uint8_t>& triangleIsFoliage,
                     const LeafRootOptions& options);

// The cache file of a model in `cacheDir` (render/cache_file.h cacheFilePath; empty: the model's
// own folder, "<model file name>.leafroots").
std::string leafRootCachePath(const std::string& modelPath, const std::string& cacheDir = "");
// Reads a cache (render/cache_file.h: header, key, size and checksum checked, no link followed);
// false (with `why`) when it is absent, damaged, truncated, oversized, for another key or version,
// or its roots are inconsistent.
bool readLeafRootCache(const std::string& path, uint64_t key, size_t vertexCount, LeafRoots* out, std::string* why);
// Writes atomically (a new temporary file renamed into place), then keeps the folder under
// capBytes (0: no cap); `note` gets what was evicted.
Status writeLeafRootCache(const std::string& path, uint64_t key, const LeafRoots& roots, uint64_t capBytes = 0,
                          std::string* note = nullptr);

}  // namespace canopy
