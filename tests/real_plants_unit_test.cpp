// Real plants' preparation (issue 77; docs/design.md "Rigid parts in wind"), on the CPU: trunk and
// foliage told apart by each part's geometry where one material holds both; leaves rooted where
// they meet the wood, and layered at the corner they grow from; long rigid edges refined without
// cracks; each rigid vertex's anchor and share; each plant's sway scale; the file's gloss.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <set>

#include <nlohmann/json.hpp>

#include "render/gltf_loader.h"
#include "render/leaf_attach.h"
#include "render/leaf_roots.h"
#include "render/material_split.h"
#include "render/plant_sway.h"
#include "render/plants.h"
#include "render/rigid_flex.h"
#include "render/rigid_refine.h"
#include "tests/assets.h"

using namespace canopy;
using nlohmann::json;

namespace {

struct Builder {
  VegetationModel m;
  uint32_t vertex(const glm::vec3& p, const glm::vec2& uv = glm::vec2(0.5f)) {
    m.positions.push_back(p);
    m.normals.push_back(glm::vec3(0, 0, 1));
    m.uvs.push_back(uv);
    return uint32_t(m.positions.size() - 1);
  }
  void tri(uint32_t a, uint32_t b, uint32_t c, uint32_t mat) {
    m.indices.insert(m.indices.end(), {a, b, c});
    m.triangleMaterial.push_back(mat);
  }
  // A closed box from lo to hi (12 triangles), material `mat`.
  void box(const glm::vec3& lo, const glm::vec3& hi, uint32_t mat) {
    uint32_t v[8];
    for (int k = 0; k < 8; ++k) v[k] = vertex(glm::vec3(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z));
    const int f[6][4] = {{0, 1, 3, 2}, {4, 6, 7, 5}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 5, 7, 3}};
    for (const auto& q : f) {
      tri(v[q[0]], v[q[1]], v[q[2]], mat);
      tri(v[q[0]], v[q[2]], v[q[3]], mat);
    }
  }
  void finish() {
    m.boundsMin = glm::vec3(INFINITY);
    m.boundsMax = glm::vec3(-INFINITY);
    for (const glm::vec3& p : m.positions) {
      m.boundsMin = glm::min(m.boundsMin, p);
      m.boundsMax = glm::max(m.boundsMax, p);
    }
  }
};

// A tree in one opaque colour-atlas material (KayKit's case): a brown trunk box standing on the
// ground, a green crown box over it, a brown branch box in the crown; UVs pick the atlas' colours.
VegetationModel atlasTree() {
  Builder b;
  b.m.materials.resize(2);
  b.m.materials[0].name = "forest";
  b.m.materials[0].baseColorImage = 0;
  b.m.materials[1].name = "default";
  ModelImage atlas;  // left half brown, right half green
  atlas.width = 2;
  atlas.height = 1;
  atlas.rgba = {120, 70, 30, 255, 60, 150, 50, 255};
  b.m.images.push_back(atlas);
  const size_t trunk = b.m.positions.size();
  b.box({-0.1f, 0.0f, -0.1f}, {0.1f, 2.0f, 0.1f}, 0);
  const size_t crown = b.m.positions.size();
  b.box({-0.8f, 1.6f, -0.8f}, {0.8f, 3.0f, 0.8f}, 0);
  const size_t branch = b.m.positions.size();
  b.box({0.1f, 1.8f, -0.05f}, {0.9f, 1.9f, 0.05f}, 0);
  for (size_t v = 0; v < b.m.positions.size(); ++v) b.m.uvs[v] = glm::vec2(v >= crown && v < branch ? 0.75f : 0.25f, 0.5f);
  (void)trunk;
  b.finish();
  return b.m;
}

TEST(PartSplit, OneAtlasMaterialsTrunkAndBranchAreRigidItsCrownFoliage) {
  const VegetationModel m = atlasTree();
  MaterialSplit s;
  ASSERT_TRUE(splitMaterials(m, {}, &s).ok());
  ASSERT_EQ(s.triangleFoliage.size(), 36u);
  for (size_t t = 0; t < 12; ++t) EXPECT_EQ(s.triangleFoliage[t], 0) << "the trunk (brown, long, on the foot) is wood";
  for (size_t t = 12; t < 24; ++t) EXPECT_EQ(s.triangleFoliage[t], 1) << "the crown (green) is foliage";
  for (size_t t = 24; t < 36; ++t) EXPECT_EQ(s.triangleFoliage[t], 0) << "the branch (brown, long) is wood";
  EXPECT_EQ(s.rigidTriangles, 24u);
  ASSERT_EQ(s.parts.size(), 3u);
  for (const PartReport& p : s.parts) EXPECT_FALSE(p.reason.empty());
  // The user's word decides whole materials.
  MaterialSplitOptions o;
  o.foliage = {"forest"};
  ASSERT_TRUE(splitMaterials(m, o, &s).ok());
  EXPECT_EQ(s.rigidTriangles, 0u);
}

TEST(PartSplit, AFlatCardOrACutOutTextureStaysFoliage) {
  VegetationModel m = atlasTree();
  // Grey like bark, but cut out: a leaf card's texture (alpha 0 on the left half).
  m.materials[0].alphaMode = AlphaMode::Mask;
  m.images[0].rgba = {120, 120, 120, 0, 120, 120, 120, 255};
  MaterialSplit s;
  ASSERT_TRUE(splitMaterials(m, {}, &s).ok());
  for (size_t t = 0; t < 12; ++t) EXPECT_EQ(s.triangleFoliage[t], 1) << "cut-out texels: a leaf";
}

TEST(PartSplit, TheRealPlantsSplitAsTheirPartsLook) {
  REQUIRE_ASSETS();
  struct Case {
    const char* file;
    uint64_t rigidAtLeast, rigidAtMost;
  };
  // KayKit: trunk and branches wood, the crown blobs foliage; the PS1 pine: its trunk wood, the
  // needle cards foliage; CommonTree_3: by its material names.
  for (const Case& c : {Case{"kaykit_tree_1_c/Tree_1_C_Color1.gltf", 700, 900}, Case{"sketchfab_pine_ps1_wersaus33/scene.gltf", 50, 120}}) {
    VegetationModel m;
    ASSERT_TRUE(loadGltf(test::kAssets + "/" + c.file, {}, &m).ok()) << c.file;
    MaterialSplit s;
    ASSERT_TRUE(splitMaterials(m, {}, &s).ok());
    std::printf("%s: %llu rigid, %llu foliage triangles\n", c.file, (unsigned long long)s.rigidTriangles, (unsigned long long)s.foliageTriangles);
    EXPECT_GE(s.rigidTriangles, c.rigidAtLeast) << c.file;
    EXPECT_LE(s.rigidTriangles, c.rigidAtMost) << c.file;
    EXPECT_GT(s.foliageTriangles, 0u) << c.file;
  }
}

// A branch (a rigid box) and a leaf card whose smallest (u, v) lies far from it while another
// corner touches it: the leaf is rooted at the touching corner, its layer root at the branch's
// corner nearest that point.
TEST(LeafAttach, ALeafMeetingABranchIsRootedThere) {
  Builder b;
  b.m.materials.resize(2);
  b.m.materials[0].name = "leaf";
  b.m.materials[1].name = "bark";
  b.box({-0.05f, 0.0f, -0.05f}, {0.05f, 2.0f, 0.05f}, 1);
  const uint32_t touch = b.vertex({0.05f, 1.5f, 0.0f}, {1, 1}), far = b.vertex({0.6f, 1.5f, 0.0f}, {0, 0}),
                 far2 = b.vertex({0.6f, 1.7f, 0.0f}, {0, 1});
  b.tri(touch, far, far2, 0);
  b.finish();
  std::vector<uint8_t> foliage(b.m.triangleCount(), 0);
  foliage.back() = 1;
  LeafRoots paper, attached;
  LeafRootOptions o;
  o.attachRoots = false;
  ASSERT_TRUE(computeLeafRoots(b.m, foliage, o, &paper).ok());
  ASSERT_TRUE(computeLeafRoots(b.m, foliage, {}, &attached).ok());
  ASSERT_EQ(paper.leafCount(), 1u);
  EXPECT_EQ(paper.leafRoot[0], far) << "the paper's root: smallest (u, v)";
  EXPECT_EQ(attached.leafRoot[0], touch) << "rooted where it meets the branch";
  std::vector<LeafAttachment> at;
  ASSERT_TRUE(findLeafAttachments(b.m, foliage, attached, 0.0f, &at).ok());
  EXPECT_EQ(at[0].vertex, touch);
  EXPECT_LT(at[0].distance, 1e-5f);
  std::vector<glm::vec3> layerRoots;
  ASSERT_TRUE(leafLayerRoots(b.m, foliage, attached, &layerRoots).ok());
  EXPECT_LT(glm::length(layerRoots[0] - b.m.positions[touch]), 0.6f) << "a corner of the branch near it";
  EXPECT_EQ(layerRoots[0].x, 0.05f) << "on the branch's side it touches";
}

// A long rigid triangle is split until no rigid edge passes 5 % of the height, both triangles of
// a split edge alike (no T-junction), the foliage untouched.
TEST(RigidRefine, LongRigidEdgesAreSplitWithoutCracks) {
  Builder b;
  b.m.materials.resize(2);
  b.m.materials[0].name = "leaf";
  b.m.materials[1].name = "bark";
  const uint32_t a = b.vertex({0, 0, 0}), c = b.vertex({0.1f, 0, 0}), d = b.vertex({0, 4, 0}), e = b.vertex({0.1f, 4, 0});
  b.tri(a, c, e, 1);
  b.tri(a, e, d, 1);
  const uint32_t l0 = b.vertex({0, 4, 0}), l1 = b.vertex({0.5f, 4.2f, 0}), l2 = b.vertex({0.2f, 4.4f, 0});
  b.tri(l0, l1, l2, 0);
  b.finish();
  std::vector<uint8_t> foliage = {0, 0, 1};
  ASSERT_TRUE(needsRigidRefinement(b.m, foliage));
  VegetationModel r;
  ASSERT_TRUE(refineRigidParts(b.m, &foliage, &r).ok());
  EXPECT_FALSE(needsRigidRefinement(r, foliage));
  ASSERT_EQ(foliage.size(), r.triangleCount());
  EXPECT_EQ(std::count(foliage.begin(), foliage.end(), uint8_t(1)), 1) << "the leaf is one triangle still";
  // Conforming: every edge of the refined rigid surface is used by one triangle (the border) or two.
  std::map<std::pair<uint32_t, uint32_t>, int> uses;
  double area = 0;
  for (size_t t = 0; t < r.triangleCount(); ++t) {
    if (foliage[t]) continue;
    const glm::vec3 p0 = r.positions[r.indices[3 * t]], p1 = r.positions[r.indices[3 * t + 1]], p2 = r.positions[r.indices[3 * t + 2]];
    area += 0.5 * glm::length(glm::cross(p1 - p0, p2 - p0));
    for (int k = 0; k < 3; ++k) {
      uint32_t u = r.indices[3 * t + size_t(k)], v = r.indices[3 * t + size_t((k + 1) % 3)];
      uses[{std::min(u, v), std::max(u, v)}]++;
    }
  }
  size_t border = 0;
  for (const auto& [edge, n] : uses) {
    EXPECT_LE(n, 2);
    border += n == 1;
  }
  EXPECT_NEAR(area, 0.4, 1e-4) << "the same surface";
  std::printf("refined: %zu rigid triangles, %zu border edges\n", r.triangleCount() - 1, border);
  // A border edge is on the rectangle's outline: x = 0, x = 0.1, y = 0 or y = 4.
  for (const auto& [edge, n] : uses) {
    if (n != 1) continue;
    const glm::vec3 p = 0.5f * (r.positions[edge.first] + r.positions[edge.second]);
    EXPECT_TRUE(std::abs(p.x) < 1e-5f || std::abs(p.x - 0.1f) < 1e-5f || std::abs(p.y) < 1e-5f || std::abs(p.y - 4.0f) < 1e-5f)
        << "an inner T-junction at " << p.x << ", " << p.y;
  }
}

// Each rigid vertex's share rises from 0 in the plant's foot band to 1 at its crown's base, and its
// anchor is the middle of the wood around it: the front and back of a trunk share it.
TEST(RigidFlex, TheTrunkStandsAtItsFootAndItsSidesFollowOneLayer) {
  Builder b;
  b.m.materials.resize(2);
  b.m.materials[0].name = "leaf";
  b.m.materials[1].name = "bark";
  b.box({-0.05f, 0.0f, -0.05f}, {0.05f, 4.0f, 0.05f}, 1);
  // A strip of bark on the trunk's face: a vertex in the foot band (5 % of 4.2 m), one between the
  // band and the crown's base (2.5 m), one in the crown.
  const uint32_t inBand = b.vertex({0.05f, 0.15f, 0.0f}), between = b.vertex({0.05f, 1.0f, 0.02f}), high = b.vertex({0.05f, 3.0f, 0.0f});
  b.tri(inBand, between, high, 1);
  for (int k = 0; k < 8; ++k) {  // leaves from 2.5 up
    const float y = 2.5f + 0.2f * float(k);
    const uint32_t p = b.vertex({0.05f, y, 0}), q = b.vertex({0.5f, y, 0}), r = b.vertex({0.3f, y + 0.3f, 0});
    b.tri(p, q, r, 0);
  }
  b.finish();
  std::vector<uint8_t> foliage(b.m.triangleCount(), 1);
  for (size_t t = 0; t < 13; ++t) foliage[t] = 0;
  LeafRoots roots;
  ASSERT_TRUE(computeLeafRoots(b.m, foliage, {}, &roots).ok());
  Plants plants;
  std::vector<uint32_t> trianglePlant;
  ASSERT_TRUE(findPlants(b.m, roots, &plants, &trianglePlant, foliage).ok());
  std::vector<gpu::LayerLeafRoot> anchors;
  ASSERT_TRUE(rigidAnchors(b.m, foliage, roots, trianglePlant, &anchors).ok());
  for (uint32_t v = 0; v < 8; ++v) {
    const float share = gpu::layerRigidShare(anchors[v].leaf);
    if (b.m.positions[v].y == 0.0f) EXPECT_EQ(share, 0.0f) << "the foot stands";
    else EXPECT_EQ(share, 1.0f) << "the top follows";
  }
  EXPECT_EQ(gpu::layerRigidShare(anchors[inBand].leaf), 0.0f) << "the foot band stands";
  const float mid = gpu::layerRigidShare(anchors[between].leaf);
  EXPECT_GT(mid, 0.0f);
  EXPECT_LT(mid, 0.5f) << "a smoothstep from the band's top (0.21 m) to the crown's base (2.5 m): 0.27 at 1 m";
  EXPECT_EQ(gpu::layerRigidShare(anchors[high].leaf), 1.0f);
  // The box's four top corners: their anchors lie between them (front and back alike).
  for (uint32_t v : {2u, 3u, 6u, 7u}) {
    EXPECT_LT(std::abs(anchors[v].position.z), 0.03f) << "anchor of corner " << v;
    EXPECT_LT(std::abs(anchors[v].position.x), 0.03f) << "anchor of corner " << v;
  }
  ASSERT_TRUE(plantSwayScales(b.m, foliage, roots, trianglePlant, &plants).ok());
  ASSERT_EQ(plants.sway.size(), 1u);
  EXPECT_GE(plants.sway[0], kMinPlantSway);
  EXPECT_LE(plants.sway[0], kMaxPlantSway);
  b.m.ownHierarchy = true;
  ASSERT_TRUE(plantSwayScales(b.m, foliage, roots, trianglePlant, &plants).ok());
  EXPECT_EQ(plants.sway[0], 1.0f) << "a plant with a hierarchy of its own keeps the default";
}

// The file's gloss: roughnessFactor (default 1) and KHR_materials_specular's factors; a factor
// outside [0, 1] is refused by name.
TEST(Gloss, TheFilesRoughnessAndSpecularAreRead) {
  std::vector<unsigned char> bin(44, 0);
  const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(&bin[0], p, 36);
  const uint16_t idx[3] = {0, 1, 2};
  std::memcpy(&bin[36], idx, 6);
  auto model = [&](const json& materials) {
    json m = {{"asset", {{"version", "2.0"}}},
              {"scene", 0},
              {"scenes", json::array({{{"nodes", {0}}}})},
              {"nodes", json::array({{{"mesh", 0}}})},
              {"meshes", json::array({{{"primitives", json::array({{{"attributes", {{"POSITION", 0}}}, {"indices", 1}, {"material", 0}}})}}})},
              {"buffers", json::array({{{"byteLength", 44}, {"uri", "tri.bin"}}})},
              {"bufferViews", json::array({{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
                                           {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 6}}})},
              {"accessors", json::array({{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
                                         {{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "SCALAR"}}})},
              {"materials", materials}};
    const std::string text = m.dump();
    VegetationModel out;
    const Status s = loadGltfFromMemory("gloss.gltf", std::vector<unsigned char>(text.begin(), text.end()), {{"tri.bin", bin}}, {}, &out);
    return std::make_pair(s, out);
  };
  auto [s1, m1] = model(json::array({{{"name", "leaf"}}}));
  ASSERT_TRUE(s1.ok()) << s1.message();
  EXPECT_EQ(m1.materials[0].roughness, 1.0f) << "glTF's default: fully rough";
  EXPECT_EQ(m1.materials[0].specularFactor, 1.0f);
  auto [s2, m2] = model(json::array({{{"name", "leaf"},
                                      {"pbrMetallicRoughness", {{"roughnessFactor", 0.3}}},
                                      {"extensions", {{"KHR_materials_specular", {{"specularFactor", 0.5}, {"specularColorFactor", {0.2, 0.4, 0.8}}}}}}}}));
  ASSERT_TRUE(s2.ok()) << s2.message();
  EXPECT_FLOAT_EQ(m2.materials[0].roughness, 0.3f);
  EXPECT_FLOAT_EQ(m2.materials[0].specularFactor, 0.4f);
  auto [s3, m3] = model(json::array({{{"name", "leaf"}, {"pbrMetallicRoughness", {{"roughnessFactor", 1.5}}}}}));
  EXPECT_FALSE(s3.ok());
  EXPECT_NE(s3.message().find("roughnessFactor"), std::string::npos) << s3.message();
  auto [s4, m4] = model(json::array({{{"name", "leaf"}, {"extensions", {{"KHR_materials_specular", {{"specularFactor", -1}}}}}}}));
  EXPECT_FALSE(s4.ok());
  EXPECT_NE(s4.message().find("KHR_materials_specular.specularFactor"), std::string::npos) << s4.message();
}

}  // namespace
