#include "render/impostors.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "engine/files.h"
#include "engine/hash.h"
#include "render/cache_file.h"
#include "render/foliage_boxes.h"

namespace canopy {
namespace {

constexpr uint32_t kRefinePieces = 64;  // children a refined box gets at most

std::string modelName(const VegetationModel& m) { return m.path.empty() ? std::string("the model") : m.path; }

std::string mib(uint64_t bytes) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f MiB", double(bytes) / double(1 << 20));
  return b;
}

uint64_t subtreeTriangles(const Impostors& imp, uint32_t i) {
  uint64_t n = 0;
  for (uint32_t m = 0; m < imp.materials; ++m) n += imp.subtreeEnd(i, m) - imp.ownFirst(i, m);
  return n;
}

// The atlas for `tiles` views of `tile` pixels: rows of at most maxSide / tile tiles, layers of at
// most as many rows; every layer as large as the first.
struct AtlasShape {
  uint32_t perRow = 1, rows = 1, layers = 1;
  uint64_t bytes = 0;
};
AtlasShape atlasShape(uint64_t tiles, uint32_t tile, uint32_t maxSide) {
  AtlasShape a;
  const uint32_t maxPerRow = std::max<uint32_t>(std::min<uint32_t>(maxSide, 2048) / tile, 1);
  tiles = std::max<uint64_t>(tiles, 1);
  a.perRow = uint32_t(std::min<uint64_t>(uint64_t(std::ceil(std::sqrt(double(tiles)))), maxPerRow));
  a.rows = uint32_t(std::min<uint64_t>((tiles + a.perRow - 1) / a.perRow, maxPerRow));
  const uint64_t perLayer = uint64_t(a.perRow) * a.rows;
  a.layers = uint32_t((tiles + perLayer - 1) / perLayer);
  a.bytes = uint64_t(a.layers) * perLayer * tile * tile * 8;
  return a;
}

}  // namespace

Status buildFoliageBoxes(const VegetationModel& m, const std::vector<uint8_t>& foliage, const LeafRoots& roots,
                         const ImpostorDesc& desc, BoxHierarchy* out) {
  *out = BoxHierarchy{};
  if (m.boxParent.empty()) return boxesFromLeafRoots(m, foliage, roots, desc.maxLeavesPerBox, out);
  CANOPY_TRY(boxesFromModel(m, foliage, out));
  // A box of many leaves of its own (a grass patch) gets regional children.
  return refineBoxes(m, foliage, roots, desc.maxLeavesPerBox, kRefinePieces, out);
}

Status buildImpostorOrder(const VegetationModel& m, const BoxHierarchy& h, const std::vector<uint32_t>& speciesBoxes,
                          const LeafRoots& roots, const std::vector<uint64_t>& materialStart, Impostors* imp,
                          std::vector<uint32_t>* order) {
  const uint32_t nm = uint32_t(m.materials.size());
  if (materialStart.size() < size_t(nm) + 1) return Status::error("impostors: material starts missing");
  if (speciesBoxes.size() < 2 || speciesBoxes.front() != 0 || speciesBoxes.back() != h.boxes.size())
    return Status::error("impostors: the species' box ranges do not cover the hierarchy");
  const size_t nb = h.boxes.size();
  // Depth-first preorder (children in index order), so a subtree is a contiguous node range and,
  // with each node's own leaves laid out before its children's, a contiguous triangle run.
  std::vector<uint32_t> childStart(nb + 1, 0), childList(nb, 0);
  for (size_t b = 0; b < nb; ++b)
    if (h.boxes[b].parent != kNoBox) childStart[h.boxes[b].parent + 1]++;
  for (size_t b = 0; b < nb; ++b) childStart[b + 1] += childStart[b];
  {
    std::vector<uint32_t> fill(childStart.begin(), childStart.end() - 1);
    for (size_t b = 0; b < nb; ++b)
      if (h.boxes[b].parent != kNoBox) childList[fill[h.boxes[b].parent]++] = uint32_t(b);
  }
  std::vector<uint32_t> pre, rank(nb, kNoTile), stack;
  pre.reserve(nb);
  for (size_t r = nb; r-- > 0;)
    if (h.boxes[r].parent == kNoBox) stack.push_back(uint32_t(r));
  while (!stack.empty()) {
    const uint32_t b = stack.back();
    stack.pop_back();
    rank[b] = uint32_t(pre.size());
    pre.push_back(b);
    for (uint32_t c = childStart[b + 1]; c-- > childStart[b];) stack.push_back(childList[c]);
  }
  if (pre.size() != nb) return Status::error("impostors: the box hierarchy of " + modelName(m) + " is not a forest");
  // A species' boxes are contiguous and only parent each other, so its subtrees are visited
  // together: its preorder range is its box range.
  for (size_t s = 0; s + 1 < speciesBoxes.size(); ++s)
    for (uint32_t b = speciesBoxes[s]; b < speciesBoxes[s + 1]; ++b)
      if (rank[b] < speciesBoxes[s] || rank[b] >= speciesBoxes[s + 1])
        return Status::error("impostors: box " + std::to_string(b) + " of species #" + std::to_string(s) + " has a parent of another species");
  imp->speciesNodes = speciesBoxes;
  imp->nodes.assign(nb, ImpostorNode{});
  imp->materials = nm;
  imp->runs.assign(nb * nm * 3, 0);
  std::vector<uint64_t> cursor(materialStart.begin(), materialStart.begin() + nm);
  std::vector<glm::dvec3> rootSum(nb, glm::dvec3(0));
  std::vector<uint64_t> rootCount(nb, 0);
  std::vector<uint8_t> seen(roots.leafCount(), 0);
  for (uint32_t i = 0; i < nb; ++i) {
    const FoliageBox& box = h.boxes[pre[i]];
    ImpostorNode& n = imp->nodes[i];
    n.parent = box.parent == kNoBox ? kNoTile : rank[box.parent];
    n.level = box.level;
    n.subtreeEnd = i + 1;
    const bool empty = !(box.boundsMin.x <= box.boundsMax.x);
    n.center = empty ? glm::vec3(0) : 0.5f * (box.boundsMin + box.boundsMax);
    n.half = empty ? glm::vec3(0) : 0.5f * (box.boundsMax - box.boundsMin);
    n.radius = glm::length(n.half);
    for (uint32_t k = 0; k < nm; ++k) imp->runs[(size_t(i) * nm + k) * 3] = cursor[k];
    for (uint64_t j = box.firstTriangle; j < box.firstTriangle + box.triangleCount; ++j) {
      const uint32_t t = h.triangles[j];
      const uint32_t mat = m.triangleMaterial[t];
      if (mat >= nm || cursor[mat] >= materialStart[mat + 1])
        return Status::error("impostors: triangle " + std::to_string(t) + " of " + modelName(m) +
                             " does not fit its material's foliage run");
      (*order)[cursor[mat]++] = t;
      const uint32_t leaf = roots.leafOfVertex[m.indices[3 * size_t(t)]];
      if (leaf != kNoLeaf && leaf < seen.size() && !seen[leaf]) {
        seen[leaf] = 1;
        rootSum[i] += glm::dvec3(m.positions[roots.leafRoot[leaf]]);
        rootCount[i]++;
      }
    }
    for (uint32_t k = 0; k < nm; ++k) {
      uint64_t* r = &imp->runs[(size_t(i) * nm + k) * 3];
      r[1] = cursor[k] - r[0];
      r[2] = cursor[k];
    }
  }
  for (uint32_t k = 0; k < nm; ++k)
    if (cursor[k] != materialStart[k + 1])
      return Status::error("impostors: the boxes of " + modelName(m) + " hold " + std::to_string(cursor[k] - materialStart[k]) +
                           " foliage triangles of material " + std::to_string(k) + ", the model " +
                           std::to_string(materialStart[k + 1] - materialStart[k]));
  // Children after parents in preorder: fold subtree ends and root sums upwards.
  for (uint32_t i = uint32_t(nb); i-- > 0;) {
    const uint32_t p = imp->nodes[i].parent;
    if (p == kNoTile) continue;
    imp->nodes[p].subtreeEnd = std::max(imp->nodes[p].subtreeEnd, imp->nodes[i].subtreeEnd);
    for (uint32_t k = 0; k < nm; ++k) {
      uint64_t& e = imp->runs[(size_t(p) * nm + k) * 3 + 2];
      e = std::max(e, imp->runs[(size_t(i) * nm + k) * 3 + 2]);
    }
    rootSum[p] += rootSum[i];
    rootCount[p] += rootCount[i];
  }
  for (uint32_t i = 0; i < nb; ++i) {
    ImpostorNode& n = imp->nodes[i];
    n.root = rootCount[i] ? glm::vec3(rootSum[i] / double(rootCount[i])) : n.center;
  }
  imp->enabled = true;
  return Status();
}

// Lluch et al.'s level limit: the volume of a node's box over its parent's. A flat box (leaves in a
// plane) counts each extent as at least a thousandth of the parent's largest, so it is not zero.
float volumeRatio(const ImpostorNode& parent, const ImpostorNode& n) {
  const float floor = 1e-3f * std::max(parent.half.x, std::max(parent.half.y, parent.half.z));
  const glm::vec3 a = glm::max(n.half, glm::vec3(floor)), b = glm::max(parent.half, glm::vec3(floor));
  return (a.x * a.y * a.z) / std::max(b.x * b.y * b.z, 1e-30f);
}

Status planImpostorAtlas(const ImpostorDesc& desc, uint32_t maxImageSide, uint32_t maxArrayLayers, Impostors* imp) {
  const uint32_t nb = uint32_t(imp->nodes.size());
  imp->firstView = desc.views == ImpostorViews::Diagonal6 ? IMPOSTOR_FIRST_VIEW_DIAGONAL : IMPOSTOR_FIRST_VIEW_ALL;
  // A node gets views when it is within maxLevel, holds leaves, is not over maxBoxTriangles and is
  // not its only child's twin (the same leaves: a scene box over a single plant).
  std::vector<uint32_t> children(nb, 0);
  for (const ImpostorNode& n : imp->nodes)
    if (n.parent != kNoTile) children[n.parent]++;
  // Levels are counted without twins: an L-system's bracketed axiom is a box with the same leaves
  // as its plant, and its branches are the plant's first real level below.
  std::vector<uint8_t> eligible(nb, 0), twin(nb, 0);
  std::vector<uint32_t> level(nb, 0);
  std::vector<uint64_t> perLevel(size_t(desc.maxLevel) + 1, 0);
  for (uint32_t i = 0; i < nb; ++i) {
    const ImpostorNode& n = imp->nodes[i];
    const uint64_t tris = subtreeTriangles(*imp, i);
    twin[i] = children[i] == 1 && i + 1 < nb && subtreeTriangles(*imp, i + 1) == tris;
    level[i] = n.parent == kNoTile ? 0 : level[n.parent] + (twin[n.parent] ? 0 : 1);
    if (level[i] > desc.maxLevel || tris == 0 || tris > desc.maxBoxTriangles || twin[i]) continue;
    if (desc.minVolumeRatio > 0.0f && n.parent != kNoTile && volumeRatio(imp->nodes[n.parent], n) < desc.minVolumeRatio) continue;
    eligible[i] = 1;
    perLevel[level[i]]++;
  }
  // Levels from the top while the budget holds them at this tile size; the tiles halve (to 8) when
  // not even the first level with boxes fits.
  uint32_t tile = desc.tilePixels, lastLevel = 0;
  bool nothingEligible = true;
  for (uint64_t c : perLevel) nothingEligible = nothingEligible && c == 0;
  bool fits = false;
  uint64_t total = 0;
  for (; tile >= 8 && !fits; tile /= 2) {
    total = 0;
    bool any = false;
    lastLevel = 0;
    for (uint32_t l = 0; l <= desc.maxLevel; ++l) {
      if (!perLevel[l]) {
        lastLevel = l;
        continue;
      }
      if (atlasShape((total + perLevel[l]) * imp->viewCount(), tile, maxImageSide).bytes > desc.memoryBudget) break;
      total += perLevel[l];
      lastLevel = l;
      any = true;
    }
    fits = any || nothingEligible;
    if (fits) break;
  }
  if (!fits) {
    uint64_t first = 0;
    for (uint64_t c : perLevel)
      if (c) {
        first = c;
        break;
      }
    return Status::error("impostors: memoryBudget " + mib(desc.memoryBudget) + " holds no level of the box hierarchy: its top level's " +
                         std::to_string(first) + " boxes need " + mib(first * imp->viewCount() * 8 * 8 * 8) +
                         " at 8-pixel views; raise CanopyDesc.impostors.memoryBudget or lower maxLevel");
  }
  imp->tileSize = tile;
  imp->tiles = 0;
  imp->baked = 0;
  for (uint32_t i = 0; i < nb; ++i) {
    ImpostorNode& n = imp->nodes[i];
    n.firstTile = n.gpuIndex = kNoTile;
    if (!eligible[i] || level[i] > lastLevel) continue;
    n.firstTile = imp->tiles;
    n.gpuIndex = imp->baked++;
    imp->tiles += imp->viewCount();
  }
  imp->speciesBaked.assign(imp->speciesNodes.empty() ? 0 : imp->speciesNodes.size() - 1, 0);
  for (size_t sp = 0; sp < imp->speciesBaked.size(); ++sp)
    for (uint32_t i = imp->speciesNodes[sp]; i < imp->speciesNodes[sp + 1]; ++i) imp->speciesBaked[sp] += imp->nodes[i].firstTile != kNoTile;
  const AtlasShape shape = atlasShape(imp->tiles, tile, maxImageSide);
  imp->tilesPerRow = shape.perRow;
  imp->rowsPerLayer = shape.rows;
  imp->atlasLayers = shape.layers;
  if (imp->atlasLayers > maxArrayLayers)
    return Status::error("impostors: " + std::to_string(imp->tiles) + " views of " + std::to_string(tile) +
                         " pixels need " + std::to_string(imp->atlasLayers) + " atlas layers, the device allows " +
                         std::to_string(maxArrayLayers) + "; lower CanopyDesc.impostors.maxLevel or tilePixels");
  imp->bytes = shape.bytes;
  return Status();
}

std::string impostorCachePath(const std::string& modelPath, const std::string& cacheDir) {
  return cacheFilePath(modelPath, cacheDir.empty() ? parentFolder(modelPath) : cacheDir, CacheKind::ImpostorViews);
}

uint64_t impostorModelKey(const Impostors& imp, const VegetationModel& m, const std::vector<uint64_t>& meshHashes) {
  uint64_t h = 0x3c6ef372fe94f82bull;
  h = hashBytes(h, meshHashes.data(), meshHashes.size() * 8);
  for (const ModelMaterial& mm : m.materials) {
    const float f[] = {mm.baseColorFactor.r, mm.baseColorFactor.g, mm.baseColorFactor.b, mm.baseColorFactor.a,
                       mm.alphaCutoff, mm.transmissionFactor, mm.transmissionColor.r, mm.transmissionColor.g,
                       mm.transmissionColor.b, mm.normalScale};
    const int32_t i[] = {mm.baseColorImage, int32_t(mm.alphaMode), mm.transmissionImage, mm.transmissionColorImage,
                         mm.normalImage};
    h = hashBytes(hashBytes(h, f, sizeof f), i, sizeof i);
  }
  for (const ModelImage& im : m.images) {
    const uint32_t dims[] = {im.width, im.height, im.linear ? 1u : 0u};
    h = hashBytes(hashBytes(h, dims, sizeof dims), im.rgba.data(), im.rgba.size());
  }
  h = hashBytes(h, imp.runs.data(), imp.runs.size() * 8);
  for (const ImpostorNode& n : imp.nodes) {
    const float b[] = {n.center.x, n.center.y, n.center.z, n.half.x, n.half.y, n.half.z};
    h = hashBytes(hashBytes(h, b, sizeof b), &n.firstTile, 4);
  }
  const uint32_t plan[] = {imp.tiles, imp.tileSize, imp.tilesPerRow, imp.rowsPerLayer, imp.atlasLayers, imp.firstView};
  return hashBytes(h, plan, sizeof plan);
}

glm::mat4 impostorViewProj(const ImpostorNode& box, uint32_t k) {
  const gpu::ImpostorFrame f = gpu::impostorFrameOf(k);
  const glm::vec3 e = gpu::impostorExtent(f, box.half, 1e-4f * std::max(box.radius, 1e-6f));
  const glm::vec3& c = box.center;
  glm::mat4 m(0.0f);
  // Rows: x = (p - c).u / e.x; y = -(p - c).v / e.y (texel row 0 is +v); z = (e.z - (p - c).n) / 2e.z.
  const glm::vec3 rows[3] = {f.u / e.x, -f.v / e.y, -f.n / (2.0f * e.z)};
  const float offs[3] = {-glm::dot(c, f.u) / e.x, glm::dot(c, f.v) / e.y, 0.5f + glm::dot(c, f.n) / (2.0f * e.z)};
  for (int r = 0; r < 3; ++r) {
    for (int col = 0; col < 3; ++col) m[col][r] = rows[r][col];
    m[3][r] = offs[r];
  }
  m[3][3] = 1.0f;
  return m;
}

void impostorCut(const Impostors& imp, const ImpostorCutInput& in, ImpostorCut* out) {
  *out = ImpostorCut{};
  out->active = true;
  out->perCopy = !in.copies.empty();
  const uint32_t nb = uint32_t(imp.nodes.size()), nm = imp.materials;
  const ImpostorSettings& s = in.settings;
  const bool debug = s.debugView;
  std::vector<float> carry(nb, 0.0f);
  std::vector<std::vector<ImpostorCut::Run>> perMaterial(nm);
  constexpr float kEps = 1e-4f;
  // One pass over nodes [begin, end) for a copy seen through `model` (its depth row in model space,
  // its radius scale); false when something of it is an impostor or fades.
  auto cutNodes = [&](uint32_t begin, uint32_t end, const glm::mat4& model, uint32_t copy, uint32_t runCopy) {
    const glm::vec4 depthRow = glm::transpose(model) * in.depthRow;  // depthRow . (model p)
    const float scale = std::max(glm::length(glm::vec3(model[0])), std::max(glm::length(glm::vec3(model[1])), glm::length(glm::vec3(model[2]))));
    bool whole = true;
    for (uint32_t i = begin; i < end;) {
      const ImpostorNode& n = imp.nodes[i];
      const float left = n.parent == kNoTile ? 1.0f : carry[n.parent];
      float a = 0.0f;
      if (n.firstTile != kNoTile && s.mode != ImpostorMode::Off) {
        const float z = glm::dot(depthRow, glm::vec4(n.center, 1.0f)), r = n.radius * scale;
        const float p = in.perspective ? (z > r ? 2.0f * r * in.pixelScale / z : INFINITY) : 2.0f * r * in.pixelScale;
        a = gpu::impostorSizeWeight(p, s.switchPixels, s.band);
        if (s.mode == ImpostorMode::FarRegion)
          a *= gpu::impostorDepthWeight(glm::dot(depthRow, glm::vec4(n.root, 1.0f)), in.farStart - in.farBand, in.farBand);
      }
      const float w = left * a;
      carry[i] = left * (1.0f - a);
      if (w > kEps) {
        const gpu::ImpostorInstance inst{n.gpuIndex, std::min(w, 1.0f), n.level, copy};
        (w >= 1.0f - kEps ? out->opaque : out->fading).push_back(inst);
        whole = false;
      }
      if (carry[i] <= kEps) {  // nothing of this subtree is drawn as leaves, nor as finer impostors
        i = n.subtreeEnd;
        whole = false;
        continue;
      }
      const float weight = carry[i] >= 1.0f - kEps ? 1.0f : carry[i];
      whole = whole && weight == 1.0f;
      for (uint32_t k = 0; k < nm; ++k) {
        const uint64_t first = imp.ownFirst(i, k), count = imp.ownCount(i, k);
        if (!count) continue;
        std::vector<ImpostorCut::Run>& runs = perMaterial[k];
        if (!runs.empty() && runs.back().first + runs.back().count == first && runs.back().weight == weight &&
            runs.back().copy == runCopy && (!debug || runs.back().level == n.level))
          runs.back().count += count;
        else
          runs.push_back({k, first, count, weight, n.level, runCopy});
        out->triangles += count;
      }
      ++i;
    }
    return whole;
  };
  if (in.copies.empty()) {
    cutNodes(0, nb, glm::mat4(1.0f), 0u, kEveryCopy);
  } else {
    const size_t species = imp.speciesNodes.size() - 1;
    std::vector<uint32_t> speciesWhole(species, 0);  // its whole copies
    std::vector<size_t> mark(nm);
    for (const ImpostorCopy& c : in.copies) {
      if (c.species >= species) continue;
      for (uint32_t k = 0; k < nm; ++k) mark[k] = perMaterial[k].size();
      const uint64_t triangles = out->triangles;
      if (!cutNodes(imp.speciesNodes[c.species], imp.speciesNodes[c.species + 1], c.model, c.index, c.index)) continue;
      // The whole foliage at full weight: drawn with the species' other whole copies, instanced.
      for (uint32_t k = 0; k < nm; ++k) perMaterial[k].resize(mark[k]);
      out->triangles = triangles;
      out->wholeCopies.push_back(c.index);
      speciesWhole[c.species]++;
    }
    std::sort(out->wholeCopies.begin(), out->wholeCopies.end());
    // Each such species' foliage, root by root: its subtrees' runs per material.
    for (size_t sp = 0; sp < species; ++sp) {
      if (!speciesWhole[sp]) continue;
      for (uint32_t i = imp.speciesNodes[sp]; i < imp.speciesNodes[sp + 1]; i = imp.nodes[i].subtreeEnd)
        for (uint32_t k = 0; k < nm; ++k) {
          const uint64_t first = imp.ownFirst(i, k), count = imp.subtreeEnd(i, k) - first;
          if (!count) continue;
          perMaterial[k].push_back({k, first, count, 1.0f, imp.nodes[i].level, kEveryCopy});
          out->triangles += count * speciesWhole[sp];
        }
    }
  }
  for (auto& runs : perMaterial) out->geometry.insert(out->geometry.end(), runs.begin(), runs.end());
}

}  // namespace canopy
