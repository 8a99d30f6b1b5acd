// The scene generator (issue 6): every scene has the expected rigid/foliage material split, one
// connected component per generated leaf, the requested face count within 1 %, finite geometry,
// alpha-masked textures, and is deterministic for a seed (also across thread counts). The .glb
// writer round-trips through the hostile-input loader.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <unistd.h>

#include "render/gltf_loader.h"
#include "tools/gltf_writer.h"
#include "render/leaf_roots.h"
#include "render/leaf_attach.h"
#include "render/material_split.h"
#include "tools/scene_generator.h"

using namespace canopy;

namespace {

struct Expected {
  SceneKind kind;
  std::set<std::string> rigid, foliage;  // material names by role (the default material aside)
};

const Expected kScenes[] = {
    {SceneKind::Shrub, {"bark"}, {"leaf"}},
    {SceneKind::TreeCrown, {"bark"}, {"leaf"}},
    {SceneKind::GrassField, {"ground"}, {"grass"}},
    {SceneKind::Kelp, {"kelp stem", "rock"}, {"kelp blade"}},
    {SceneKind::Field, {"bark", "ground"}, {"leaf", "grass"}},
};

VegetationModel generate(SceneKind kind, uint64_t faces, uint32_t seed, SceneStats* st = nullptr, uint32_t threads = 0) {
  SceneDesc d;
  d.kind = kind;
  d.faces = faces;
  d.seed = seed;
  d.textureSize = 64;
  d.threads = threads;
  VegetationModel m;
  SceneStats local;
  const Status s = generateScene(d, &m, st ? st : &local);
  EXPECT_TRUE(s.ok()) << s.message();
  return m;
}

void PrintTo(const Expected& e, std::ostream* os) { *os << sceneName(e.kind); }

class SceneTest : public ::testing::TestWithParam<Expected> {};

}  // namespace

TEST_P(SceneTest, MaterialSplitLeavesFacesAndDeterminism) {
  const Expected& e = GetParam();
  for (uint64_t faces : {uint64_t(kMinSceneFaces), uint64_t(80000), uint64_t(1'000'000)}) {
    SCOPED_TRACE(std::string(sceneName(e.kind)) + " " + std::to_string(faces) + " faces");
    SceneStats st;
    const VegetationModel m = generate(e.kind, faces, 7, &st);
    ASSERT_EQ(st.faces, m.triangleCount());
    EXPECT_LE(std::abs(double(m.triangleCount()) - double(faces)), 0.01 * double(faces));
    EXPECT_EQ(st.rigidFaces + st.leafFaces, st.faces);
    EXPECT_GT(st.rigidFaces, 0u);
    EXPECT_LT(st.rigidFaces, st.faces / 2) << "the foliage is most of the scene";
    ASSERT_EQ(m.normals.size(), m.positions.size());
    ASSERT_EQ(m.uvs.size(), m.positions.size());
    ASSERT_EQ(m.indices.size(), m.triangleMaterial.size() * 3);
    for (uint32_t i : m.indices) ASSERT_LT(i, m.positions.size());
    for (size_t v = 0; v < m.positions.size(); ++v) {
      ASSERT_TRUE(std::isfinite(m.positions[v].x + m.positions[v].y + m.positions[v].z));
      ASSERT_NEAR(glm::length(m.normals[v]), 1.0f, 1e-3f);
      ASSERT_GE(m.positions[v].x, m.boundsMin.x);
      ASSERT_LE(m.positions[v].y, m.boundsMax.y);
    }

    // The default rule of the material split puts every generated material where it belongs.
    MaterialSplit split;
    ASSERT_TRUE(splitMaterials(m, {}, &split).ok());
    std::set<std::string> rigid, foliage;
    for (size_t i = 0; i + 1 < m.materials.size(); ++i)
      (split.role[i] == MaterialRole::Rigid ? rigid : foliage).insert(m.materials[i].name);
    EXPECT_EQ(rigid, e.rigid);
    EXPECT_EQ(foliage, e.foliage);
    EXPECT_EQ(split.rigidTriangles, st.rigidFaces);
    EXPECT_EQ(split.foliageTriangles, st.leafFaces);
    EXPECT_EQ(m.materials.back().name, "(default)");

    // Foliage materials are alpha-masked with a texture that has both holes and solid texels.
    for (size_t i = 0; i + 1 < m.materials.size(); ++i) {
      if (split.role[i] != MaterialRole::Foliage) continue;
      const ModelMaterial& mat = m.materials[i];
      EXPECT_EQ(mat.alphaMode, AlphaMode::Mask) << mat.name;
      ASSERT_GE(mat.baseColorImage, 0) << mat.name;
      const ModelImage& img = m.images[size_t(mat.baseColorImage)];
      size_t clear = 0, solid = 0;
      for (size_t p = 3; p < img.rgba.size(); p += 4) {
        clear += img.rgba[p] == 0;
        solid += img.rgba[p] == 255;
      }
      EXPECT_GT(clear, img.rgba.size() / 40) << mat.name;
      EXPECT_GT(solid, img.rgba.size() / 40) << mat.name;
    }

    // Every leaf is its own connected component (also through equal positions).
    std::vector<uint8_t> isFoliage(m.triangleCount());
    for (size_t t = 0; t < isFoliage.size(); ++t) isFoliage[t] = split.role[m.triangleMaterial[t]] == MaterialRole::Foliage;
    LeafRoots roots;
    ASSERT_TRUE(computeLeafRoots(m, isFoliage, {}, &roots).ok());
    EXPECT_EQ(roots.leafCount(), st.leaves);
    // The root of each leaf is at its attachment: uv (0, 0), the paper's smallest (u, v), unless
    // that lies farther than the attachment reach from every rigid triangle and another of the
    // leaf's vertices does not (a card on a twig too fine to be drawn): then that vertex
    // (LeafRootOptions.attachRoots; docs/design.md "Rigid parts in wind").
    const RigidGrid grid = buildRigidGrid(m, isFoliage, 0.0f);
    for (uint32_t r : roots.leafRoot) {
      if (m.uvs[r] == glm::vec2(0.0f)) continue;
      LeafAttachment at;
      ASSERT_TRUE(nearestRigidPoint(grid, m.positions[r], &at)) << "a leaf rooted off (0, 0) meets a branch there";
    }
    LeafRootOptions paper;
    paper.attachRoots = false;
    ASSERT_TRUE(computeLeafRoots(m, isFoliage, paper, &roots).ok());
    for (uint32_t r : roots.leafRoot) ASSERT_EQ(m.uvs[r], glm::vec2(0.0f));
  }
}

TEST_P(SceneTest, SameSeedSameHashOtherSeedOtherHash) {
  const Expected& e = GetParam();
  const uint64_t a = modelHash(generate(e.kind, 60000, 3, nullptr, 1));
  const uint64_t b = modelHash(generate(e.kind, 60000, 3, nullptr, 2));  // another thread count
  const uint64_t c = modelHash(generate(e.kind, 60000, 3));
  const uint64_t d = modelHash(generate(e.kind, 60000, 4));
  EXPECT_EQ(a, b);
  EXPECT_EQ(a, c);
  EXPECT_NE(a, d);
}

TEST_P(SceneTest, GlbRoundTripThroughTheLoader) {
  const Expected& e = GetParam();
  const VegetationModel m = generate(e.kind, 20000, 5);
  const std::string path = (std::filesystem::temp_directory_path() / (std::string("canopy_scene_") + sceneName(e.kind) +
                                                                       "_" + std::to_string(::getpid()) + ".glb"))
                               .string();
  ASSERT_TRUE(writeGlb(path, m).ok());
  VegetationModel back;
  const Status s = loadGltf(path, {}, &back);
  std::filesystem::remove(path);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(back.warnings.empty()) << back.warnings.front();
  ASSERT_EQ(back.triangleCount(), m.triangleCount());
  ASSERT_EQ(back.materials.size(), m.materials.size());
  std::map<std::string, size_t> before, after;
  for (uint32_t t : m.triangleMaterial) before[m.materials[t].name]++;
  for (uint32_t t : back.triangleMaterial) after[back.materials[t].name]++;
  EXPECT_EQ(before, after);
  for (size_t i = 0; i < m.materials.size(); ++i) {
    EXPECT_EQ(back.materials[i].name, m.materials[i].name);
    EXPECT_EQ(back.materials[i].alphaMode, m.materials[i].alphaMode);
    EXPECT_EQ(back.materials[i].doubleSided, m.materials[i].doubleSided);
    EXPECT_EQ(back.materials[i].baseColorImage >= 0, m.materials[i].baseColorImage >= 0);
    if (m.materials[i].baseColorImage >= 0)
      EXPECT_EQ(back.images[size_t(back.materials[i].baseColorImage)].rgba,
                m.images[size_t(m.materials[i].baseColorImage)].rgba);  // PNG is lossless
  }
  for (int k = 0; k < 3; ++k) {
    EXPECT_FLOAT_EQ(back.boundsMin[k], m.boundsMin[k]);
    EXPECT_FLOAT_EQ(back.boundsMax[k], m.boundsMax[k]);
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, SceneTest, ::testing::ValuesIn(kScenes),
                         [](const ::testing::TestParamInfo<Expected>& i) { return std::string(sceneName(i.param.kind)); });

TEST(SceneGenerator, RefusesOutOfRangeDescriptions) {
  VegetationModel m;
  SceneDesc d;
  d.faces = kMinSceneFaces - 1;
  Status s = generateScene(d, &m);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("faces"), std::string::npos) << s.message();
  d.faces = kMaxSceneFaces + 1;
  EXPECT_FALSE(generateScene(d, &m).ok());
  d.faces = 80000;
  d.textureSize = 100;
  s = generateScene(d, &m);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("textureSize"), std::string::npos) << s.message();
  d.textureSize = 64;
  d.kind = SceneKind(9);
  EXPECT_FALSE(generateScene(d, &m).ok());
  EXPECT_TRUE(m.positions.empty());
  SceneKind k;
  s = parseSceneKind("palm", &k);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("palm"), std::string::npos);
  EXPECT_TRUE(parseSceneKind("underwater", &k).ok());
  EXPECT_EQ(k, SceneKind::Kelp);
}

TEST(SceneGenerator, WriterRefusesInconsistentModels) {
  VegetationModel m = generate(SceneKind::Shrub, 4000, 1);
  m.triangleMaterial[0] = 99;
  EXPECT_FALSE(writeGlb("/tmp/canopy_never_written.glb", m).ok());
  m = generate(SceneKind::Shrub, 4000, 1);
  m.indices[5] = uint32_t(m.positions.size());
  EXPECT_FALSE(writeGlb("/tmp/canopy_never_written.glb", m).ok());
  EXPECT_FALSE(std::filesystem::exists("/tmp/canopy_never_written.glb"));
}

// The per-vertex baseline's hierarchy (SceneDesc::hierarchy; shared/bend.h): the same geometry,
// a branch table in the L-system's bracket structure (parents first, each a level below its
// parent, at most BEND_LEVELS deep), the wood on its branches with w growing along them, leaf cards
// riding branches, grass blades and ground with the leaf level only.
TEST(SceneGenerator, HierarchyFollowsTheLSystemBrackets) {
  for (SceneKind kind : {SceneKind::Shrub, SceneKind::TreeCrown, SceneKind::GrassField, SceneKind::Field}) {
    SCOPED_TRACE(sceneName(kind));
    SceneDesc d;
    d.kind = kind;
    d.faces = 30000;
    VegetationModel plain, m;
    ASSERT_TRUE(generateScene(d, &plain).ok());
    d.hierarchy = true;
    ASSERT_TRUE(generateScene(d, &m).ok());
    EXPECT_TRUE(plain.bend.empty() && plain.branches.empty());
    ASSERT_EQ(m.positions, plain.positions) << "the hierarchy changes no geometry";
    ASSERT_EQ(m.bend.size(), m.positions.size());
    for (size_t i = 0; i < m.branches.size(); ++i) {
      const gpu::BendBranch& b = m.branches[i];
      ASSERT_LT(b.level, uint32_t(BEND_LEVELS));
      if (b.parent == BEND_NO_PARENT) {
        EXPECT_EQ(b.level, 0u);
      } else {
        ASSERT_LT(b.parent, i) << "parents come first";
        EXPECT_EQ(b.level, m.branches[b.parent].level + 1);
      }
      EXPECT_NEAR(glm::length(b.axis), 1.0f, 1e-4f);
    }
    MaterialSplit split;
    ASSERT_TRUE(splitMaterials(m, {}, &split).ok());
    size_t onBranches = 0, leafOnly = 0;
    struct Ends {
      uint32_t minW = 256, maxW = 0;
      float alongMin = 0, alongMax = 0;
    };
    std::map<uint32_t, Ends> ends;
    for (size_t t = 0; t < m.triangleCount(); ++t) {
      const bool rigid = split.role[m.triangleMaterial[t]] == MaterialRole::Rigid;
      for (int k = 0; k < 3; ++k) {
        const gpu::BendVertex& v = m.bend[m.indices[3 * t + k]];
        if (v.branch == BEND_LEAF_ONLY) {
          ++leafOnly;
          continue;
        }
        ASSERT_LT(v.branch, m.branches.size());
        ++onBranches;
        // The wood of a branch lies along it: its w grows towards the tip.
        if (rigid) {
          const gpu::BendBranch& b = m.branches[v.branch];
          const uint32_t w = (v.w >> (8 * b.level)) & 255u;
          const float along = glm::dot(m.positions[m.indices[3 * t + k]] - b.origin, b.axis);
          Ends& e = ends[v.branch];
          if (w < e.minW) e.minW = w, e.alongMin = along;
          if (w > e.maxW || (w == e.maxW && along > e.alongMax)) e.maxW = w, e.alongMax = along;
        }
      }
    }
    for (const auto& [branch, e] : ends)
      if (e.maxW > e.minW + 64) EXPECT_GT(e.alongMax, e.alongMin) << "branch " << branch;
    if (kind == SceneKind::GrassField) {
      EXPECT_EQ(onBranches, 0u) << "grass has no branches";
    } else {
      EXPECT_GT(onBranches, leafOnly) << "plants: leaves and wood ride branches";
      EXPECT_GE(m.branches.size(), 4u);
    }
  }
}
