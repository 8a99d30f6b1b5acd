// Rigid/foliage material split and leaf-root preprocessing (paper 3.2): components through shared
// indices and welded positions, root = smallest (u, v), the cache beside the model.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "render/gltf_loader.h"
#include "render/leaf_roots.h"
#include "render/material_split.h"
#include "render/plants.h"

#include "tests/assets.h"

using namespace canopy;
using canopy::test::kAssets;

namespace {

// Appends a quad (two triangles over 4 shared vertices) with the given corner and uv offset.
void addQuad(VegetationModel& m, glm::vec3 o, glm::vec2 uv0, uint32_t material) {
  const uint32_t b = uint32_t(m.positions.size());
  const glm::vec3 p[4] = {o, o + glm::vec3(1, 0, 0), o + glm::vec3(1, 1, 0), o + glm::vec3(0, 1, 0)};
  const glm::vec2 t[4] = {uv0, uv0 + glm::vec2(1, 0), uv0 + glm::vec2(1, 1), uv0 + glm::vec2(0, 1)};
  for (int i = 0; i < 4; ++i) {
    m.positions.push_back(p[i]);
    m.normals.push_back({0, 0, 1});
    m.uvs.push_back(t[i]);
  }
  for (uint32_t i : {0u, 1u, 2u, 2u, 3u, 0u}) m.indices.push_back(b + i);
  m.triangleMaterial.push_back(material);
  m.triangleMaterial.push_back(material);
}

VegetationModel twoMaterialModel() {
  VegetationModel m;
  m.path = "hand-made";
  m.materials.resize(3);
  m.materials[0].name = "Leaf_Mat";
  m.materials[0].alphaMode = AlphaMode::Mask;
  m.materials[1].name = "TreeBark";
  m.materials[2].name = "default";
  return m;
}

std::vector<uint8_t> allFoliage(const VegetationModel& m) { return std::vector<uint8_t>(m.triangleCount(), 1); }

}  // namespace

TEST(MaterialSplit, DefaultRuleReadsNamesAndAlphaModes) {
  VegetationModel m = twoMaterialModel();
  m.materials.push_back({"Material.001"});  // opaque, no telling name, beside a MASK material
  MaterialSplit s;
  ASSERT_TRUE(splitMaterials(m, {}, &s).ok());
  EXPECT_EQ(s.role[0], MaterialRole::Foliage);
  EXPECT_EQ(s.role[1], MaterialRole::Rigid);
  EXPECT_EQ(s.role[3], MaterialRole::Rigid) << s.reason[3];
  // All-opaque model: unnamed opaque parts are soft foliage, wood stays rigid.
  VegetationModel t;
  t.materials = {{"Wood"}, {"Green"}};
  ASSERT_TRUE(splitMaterials(t, {}, &s).ok());
  EXPECT_EQ(s.role[0], MaterialRole::Rigid);
  EXPECT_EQ(s.role[1], MaterialRole::Foliage);
}

TEST(MaterialSplit, UserOverridesWinAndBadOnesAreNamed) {
  VegetationModel m = twoMaterialModel();
  addQuad(m, {0, 0, 0}, {0, 0}, 0);
  addQuad(m, {2, 0, 0}, {0, 0}, 1);
  MaterialSplitOptions o;
  o.foliage = {"treebark"};  // case-insensitive name
  o.rigid = {"#0"};
  MaterialSplit s;
  ASSERT_TRUE(splitMaterials(m, o, &s).ok());
  EXPECT_EQ(s.role[0], MaterialRole::Rigid);
  EXPECT_EQ(s.role[1], MaterialRole::Foliage);
  EXPECT_EQ(s.reason[0], "user override");
  EXPECT_EQ(s.rigidTriangles, 2u);
  EXPECT_EQ(s.foliageTriangles, 2u);
  o = {};
  o.rigid = {"Trunk"};
  Status st = splitMaterials(m, o, &s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("'Trunk' names no material"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("'TreeBark'"), std::string::npos) << st.message();
  o = {};
  o.rigid = {"#7"};
  st = splitMaterials(m, o, &s);
  EXPECT_NE(st.message().find("index out of range"), std::string::npos) << st.message();
  o = {};
  o.rigid = {"#1"};
  o.foliage = {"TreeBark"};
  st = splitMaterials(m, o, &s);
  EXPECT_NE(st.message().find("both rigid and foliage"), std::string::npos) << st.message();
  o = {};
  o.rigid = {"#x1"};
  EXPECT_FALSE(splitMaterials(m, o, &s).ok());
}

TEST(LeafRoots, ComponentsThroughIndicesAndWeldedPositions) {
  VegetationModel m = twoMaterialModel();
  addQuad(m, {0, 0, 0}, {0.5f, 0.5f}, 0);  // leaf A: shared indices
  addQuad(m, {5, 0, 0}, {0.2f, 0.7f}, 0);  // leaf B, first half
  addQuad(m, {6, 0, 0}, {0.1f, 0.9f}, 0);  // leaf B, second half: touches B only by position (UV seam)
  LeafRoots r;
  ASSERT_TRUE(computeLeafRoots(m, allFoliage(m), {}, &r).ok());
  EXPECT_EQ(r.leafCount(), 2u);
  for (uint32_t v = 0; v < 4; ++v) EXPECT_EQ(r.rootOfVertex[v], 0u);  // smallest (u, v) of A: vertex 0
  // Leaf B's smallest u is 0.1 (vertex 8, the second quad's first corner).
  for (uint32_t v = 4; v < 12; ++v) EXPECT_EQ(r.rootOfVertex[v], 8u) << v;
  EXPECT_EQ(r.leafOfVertex[0], 0u);
  EXPECT_EQ(r.leafOfVertex[11], 1u);
  EXPECT_EQ(r.leafRoot[1], 8u);
  LeafRootOptions noWeld;
  noWeld.weldPositions = false;
  ASSERT_TRUE(computeLeafRoots(m, allFoliage(m), noWeld, &r).ok());
  EXPECT_EQ(r.leafCount(), 3u);
}

TEST(LeafRoots, RigidTrianglesAreNotLeavesAndTiesAreStable) {
  VegetationModel m = twoMaterialModel();
  addQuad(m, {0, 0, 0}, {0, 0}, 0);
  addQuad(m, {1, 0, 0}, {0, 0}, 1);  // rigid, touching leaf A by position
  std::vector<uint8_t> mask = {1, 1, 0, 0};
  LeafRoots r;
  // The paper's rule (smallest (u, v)): the leaf touches the rigid quad along x = 1, so the rule that
  // roots a leaf where it meets the wood (attachRoots, tested in real_plants_unit_test) is off.
  LeafRootOptions paper;
  paper.attachRoots = false;
  ASSERT_TRUE(computeLeafRoots(m, mask, paper, &r).ok());
  EXPECT_EQ(r.leafCount(), 1u);
  for (uint32_t v = 4; v < 8; ++v) EXPECT_EQ(r.rootOfVertex[v], kNoLeaf);
  // Vertex 0 has uv (0,0), the smallest; no other vertex of the leaf ties.
  EXPECT_EQ(r.rootOfVertex[3], 0u);
  // Equal uvs everywhere: the lowest index wins.
  for (auto& uv : m.uvs) uv = glm::vec2(0.25f);
  ASSERT_TRUE(computeLeafRoots(m, mask, paper, &r).ok());
  EXPECT_EQ(r.rootOfVertex[2], 0u);
}

// The in-place union-find (issue 16: 6 bytes a vertex) against a plain reference: components by
// repeated relaxation over the triangles and welded positions, root = the first vertex in index
// order with the smallest (u, v). Random meshes with many uv ties, welded duplicates, unused and
// rigid-only vertices.
TEST(LeafRoots, MatchesAPlainReferenceOnRandomMeshes) {
  uint32_t state = 12345;
  auto next = [&](uint32_t n) {
    state = state * 1664525u + 1013904223u;
    return (state >> 8) % n;
  };
  for (int round = 0; round < 40; ++round) {
    VegetationModel m = twoMaterialModel();
    const uint32_t nv = 20 + next(200), nt = 5 + next(150);
    for (uint32_t v = 0; v < nv; ++v) {
      m.positions.push_back(glm::vec3(float(next(12)), float(next(3)), 0.0f));  // many equal positions
      m.normals.push_back({0, 0, 1});
      m.uvs.push_back(glm::vec2(float(next(3)) * 0.5f, float(next(3)) * 0.5f));  // many equal uvs
    }
    std::vector<uint8_t> mask;
    for (uint32_t t = 0; t < nt; ++t) {
      for (int k = 0; k < 3; ++k) m.indices.push_back(next(nv));
      mask.push_back(next(4) != 0);
      m.triangleMaterial.push_back(mask.back() ? 0 : 1);
    }
    for (bool weld : {false, true}) {
      LeafRootOptions o;
      o.weldPositions = weld;
      o.attachRoots = false;  // the reference is the paper's rule (random leaves touch the rigid triangles)
      LeafRoots r;
      ASSERT_TRUE(computeLeafRoots(m, mask, o, &r).ok());
      std::vector<uint32_t> comp(nv);
      std::vector<bool> used(nv, false);
      for (uint32_t v = 0; v < nv; ++v) comp[v] = v;
      for (uint32_t t = 0; t < nt; ++t)
        if (mask[t])
          for (int k = 0; k < 3; ++k) used[m.indices[3 * t + k]] = true;
      for (bool changed = true; changed;) {  // smallest index of the component, by relaxation
        changed = false;
        auto join = [&](uint32_t a, uint32_t b) {
          const uint32_t c = std::min(comp[a], comp[b]);
          if (comp[a] != c || comp[b] != c) comp[a] = comp[b] = c, changed = true;
        };
        for (uint32_t t = 0; t < nt; ++t)
          if (mask[t]) join(m.indices[3 * t], m.indices[3 * t + 1]), join(m.indices[3 * t + 1], m.indices[3 * t + 2]);
        if (weld)
          for (uint32_t a = 0; a < nv; ++a)
            for (uint32_t b = a + 1; b < nv; ++b)
              if (used[a] && used[b] && m.positions[a] == m.positions[b]) join(a, b);
      }
      for (uint32_t v = 0; v < nv; ++v) {
        if (!used[v]) {
          EXPECT_EQ(r.rootOfVertex[v], kNoLeaf);
          continue;
        }
        uint32_t best = kNoLeaf;
        for (uint32_t u = 0; u < nv; ++u)
          if (used[u] && comp[u] == comp[v] &&
              (best == kNoLeaf || m.uvs[u].x < m.uvs[best].x || (m.uvs[u].x == m.uvs[best].x && m.uvs[u].y < m.uvs[best].y)))
            best = u;
        ASSERT_EQ(r.rootOfVertex[v], best) << "round " << round << " weld " << weld << " vertex " << v;
        EXPECT_EQ(r.leafRoot[r.leafOfVertex[v]], best);
      }
    }
  }
}

TEST(LeafRoots, RefusesInconsistentInput) {
  VegetationModel m = twoMaterialModel();
  addQuad(m, {0, 0, 0}, {0, 0}, 0);
  LeafRoots r;
  EXPECT_FALSE(computeLeafRoots(m, {1}, {}, &r).ok());
  m.indices[4] = 99;
  Status s = computeLeafRoots(m, allFoliage(m), {}, &r);
  EXPECT_NE(s.message().find("indexes past"), std::string::npos) << s.message();
}

TEST(LeafRoots, CacheRoundTripAndRejection) {
  VegetationModel m = twoMaterialModel();
  for (int i = 0; i < 10; ++i) addQuad(m, {2.0f * i, 0, 0}, {0.1f * i, 0}, 0);
  const auto mask = allFoliage(m);
  LeafRoots r;
  ASSERT_TRUE(computeLeafRoots(m, mask, {}, &r).ok());
  const std::string path = (std::filesystem::temp_directory_path() / "canopy_leafroots_test.leafroots").string();
  const uint64_t key = leafRootKey(m, mask, {});
  ASSERT_TRUE(writeLeafRootCache(path, key, r).ok());
  LeafRoots back;
  std::string why;
  ASSERT_TRUE(readLeafRootCache(path, key, m.positions.size(), &back, &why)) << why;
  EXPECT_EQ(back.rootOfVertex, r.rootOfVertex);
  EXPECT_EQ(back.leafOfVertex, r.leafOfVertex);
  EXPECT_EQ(back.leafRoot, r.leafRoot);
  // Other options or data: another key.
  LeafRootOptions noWeld;
  noWeld.weldPositions = false;
  EXPECT_NE(leafRootKey(m, mask, noWeld), key);
  VegetationModel moved = m;
  moved.positions[3].x += 1e-3f;
  EXPECT_NE(leafRootKey(moved, mask, {}), key);
  EXPECT_FALSE(readLeafRootCache(path, key + 1, m.positions.size(), &back, &why));
  EXPECT_NE(why.find("other data"), std::string::npos);
  // Truncated and corrupted files are rejected, never trusted (tests/cache_files_test.cpp tries
  // every truncation and bit flip of the format).
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 3);
  EXPECT_FALSE(readLeafRootCache(path, key, m.positions.size(), &back, &why));
  EXPECT_NE(why.find("truncated"), std::string::npos) << why;
  ASSERT_TRUE(writeLeafRootCache(path, key, r).ok());
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(64 + 4 * 5);
    const uint32_t bad = 7;
    f.write(reinterpret_cast<const char*>(&bad), 4);
  }
  EXPECT_FALSE(readLeafRootCache(path, key, m.positions.size(), &back, &why));
  EXPECT_EQ(why, "damaged: the contents' checksum does not match");
  // A well-formed file whose roots are inconsistent (vertex 5's root becomes 7, which is not a
  // root): rejected too, before anything indexes with it.
  LeafRoots broken = r;
  broken.rootOfVertex[5] = 7;
  ASSERT_NE(r.rootOfVertex[7], 7u);
  ASSERT_TRUE(writeLeafRootCache(path, key, broken).ok());
  EXPECT_FALSE(readLeafRootCache(path, key, m.positions.size(), &back, &why));
  EXPECT_EQ(why, "inconsistent contents");
  EXPECT_FALSE(readLeafRootCache(path + ".absent", key, m.positions.size(), &back, &why));
  std::filesystem::remove(path);
}

TEST(LeafRoots, RealModelsSplitAndWeld) {
  REQUIRE_ASSETS();
  struct Case {
    const char* file;
    std::set<std::string> rigid;
    uint32_t leavesWelded;
  };
  // Leaf counts measured with canopy-layers; the Quaternius models share no vertices, so without
  // welding every foliage triangle would be its own leaf.
  const Case cases[] = {{"quaternius_CommonTree_1/CommonTree_1.glb", {"Wood"}, 2},
                        {"quaternius_PineTree_1/PineTree_1.glb", {"Wood"}, 0},
                        {"DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf", {"base"}, 36},
                        {"fern_02/fern_02.glb", {}, 53}};
  for (const Case& c : cases) {
    VegetationModel m;
    ASSERT_TRUE(loadGltf(kAssets + "/" + c.file, {}, &m).ok()) << c.file;
    MaterialSplit s;
    ASSERT_TRUE(splitMaterials(m, {}, &s).ok());
    std::set<std::string> rigid;
    std::vector<uint64_t> used(m.materials.size());
    for (uint32_t t : m.triangleMaterial) used[t]++;
    for (size_t i = 0; i < m.materials.size(); ++i)
      if (used[i] && s.role[i] == MaterialRole::Rigid) rigid.insert(m.materials[i].name);
    EXPECT_EQ(rigid, c.rigid) << c.file;
    std::vector<uint8_t> mask(m.triangleCount());
    uint64_t foliage = 0;
    for (size_t t = 0; t < mask.size(); ++t) foliage += mask[t] = s.role[m.triangleMaterial[t]] == MaterialRole::Foliage;
    LeafRoots r;
    ASSERT_TRUE(computeLeafRoots(m, mask, {}, &r).ok());
    if (c.leavesWelded) EXPECT_EQ(r.leafCount(), c.leavesWelded) << c.file;
    // Every vertex of a foliage triangle has a root in its own leaf.
    for (size_t t = 0; t < mask.size(); ++t) {
      if (!mask[t]) continue;
      const uint32_t a = m.indices[3 * t], b = m.indices[3 * t + 1], cc = m.indices[3 * t + 2];
      ASSERT_NE(r.rootOfVertex[a], kNoLeaf);
      ASSERT_EQ(r.rootOfVertex[a], r.rootOfVertex[b]);
      ASSERT_EQ(r.rootOfVertex[a], r.rootOfVertex[cc]);
    }
    if (std::string(c.file).find("quaternius") != std::string::npos) {
      const uint32_t welded = r.leafCount();
      LeafRootOptions noWeld;
      noWeld.weldPositions = false;
      ASSERT_TRUE(computeLeafRoots(m, mask, noWeld, &r).ok());
      EXPECT_GT(r.leafCount(), 4 * welded) << c.file << ": unwelded, the split vertices fall apart";
      EXPECT_LE(r.leafCount(), foliage);
    }
  }
}

// Per-plant roots (docs/design.md "Per-plant roots"): leaves take their plant from
// VegetationModel::trianglePlant; plants whose ground boxes overlap merge when the model asks (a
// glTF file's root nodes); no plant ids: one plant, the whole model.
TEST(Plants, LeavesTakeTheirPlantAndOverlappingNodesMerge) {
  // Four one-triangle leaves: two at x ~ 0, two at x ~ 10 (plants 0 and 1), one ground triangle.
  VegetationModel m;
  auto tri = [&](glm::vec3 o, uint32_t plant) {
    const uint32_t b = uint32_t(m.positions.size());
    for (glm::vec3 q : {glm::vec3(0, 0, 0), glm::vec3(1, 0, 0), glm::vec3(0, 1, 0)}) m.positions.push_back(o + q);
    m.indices.insert(m.indices.end(), {b, b + 1, b + 2});
    m.triangleMaterial.push_back(0);
    m.trianglePlant.push_back(plant);
  };
  tri({0, 1, 0}, 0);
  tri({0, 2, 0.5f}, 0);
  tri({10, 1, 0}, 1);
  tri({10, 3, 0}, 1);
  tri({-20, 0, 0}, kNoPlant);
  m.normals.assign(m.positions.size(), glm::vec3(0, 0, 1));
  m.uvs.assign(m.positions.size(), glm::vec2(0));
  m.materials.resize(1);
  m.boundsMin = glm::vec3(-20, 0, 0);
  m.boundsMax = glm::vec3(11, 4, 0.5f);
  std::vector<uint8_t> foliage = {1, 1, 1, 1, 0};
  LeafRoots roots;
  ASSERT_TRUE(computeLeafRoots(m, foliage, {}, &roots).ok());
  ASSERT_EQ(roots.leafCount(), 4u);
  Plants p;
  ASSERT_TRUE(findPlants(m, roots, &p).ok());
  ASSERT_EQ(p.count(), 2u);
  for (uint32_t leaf = 0; leaf < 4; ++leaf) {
    const float x = m.positions[roots.leafRoot[leaf]].x;
    EXPECT_EQ(p.boundsMin[p.leafPlant[leaf]].x, x < 5 ? 0.0f : 10.0f) << "leaf " << leaf;
  }
  EXPECT_EQ(p.boundsMax[p.leafPlant[0]].y, 3.0f);  // the plant's own box, not the ground's
  // Overlapping on the ground: one plant when the model asks for merging.
  m.positions[6] = glm::vec3(0.5f, 1, 0);  // plant 1's first triangle reaches into plant 0's box
  m.mergeOverlappingPlants = true;
  ASSERT_TRUE(findPlants(m, roots, &p).ok());
  EXPECT_EQ(p.count(), 1u);
  m.mergeOverlappingPlants = false;
  ASSERT_TRUE(findPlants(m, roots, &p).ok());
  EXPECT_EQ(p.count(), 2u);
  // No plant ids: the whole model.
  m.trianglePlant.clear();
  ASSERT_TRUE(findPlants(m, roots, &p).ok());
  EXPECT_EQ(p.count(), 1u);
}
