// The foliage's bounding-box hierarchy (seed 002, Lluch et al., section 3; render/foliage_boxes.h):
// from the generator's L-system PUSH/POP structure and from a k-d split of the leaf roots, every
// foliage triangle in exactly one box, a leaf never split, boxes nested (parents first, each
// containing its children), the generator's boxes one per PUSH plus one per plant and per blade
// patch, and inconsistent inputs refused.
#include <gtest/gtest.h>

#include <set>

#include "render/foliage_boxes.h"
#include "render/leaf_roots.h"
#include "render/material_split.h"
#include "tools/leaf_cloud.h"
#include "tools/scene_generator.h"

using namespace canopy;

namespace {

std::vector<uint8_t> foliageMask(const VegetationModel& m) {
  MaterialSplit split;
  EXPECT_TRUE(splitMaterials(m, {}, &split).ok());
  std::vector<uint8_t> f(m.triangleCount());
  for (size_t t = 0; t < f.size(); ++t) f[t] = split.role[m.triangleMaterial[t]] == MaterialRole::Foliage;
  return f;
}

bool inside(const FoliageBox& c, const FoliageBox& p) {
  return c.boundsMin.x >= p.boundsMin.x && c.boundsMin.y >= p.boundsMin.y && c.boundsMin.z >= p.boundsMin.z &&
         c.boundsMax.x <= p.boundsMax.x && c.boundsMax.y <= p.boundsMax.y && c.boundsMax.z <= p.boundsMax.z;
}

// Exactly-once membership, bounds of own triangles, nesting, parents first, levels; a leaf's
// triangles in one box. Returns the box of every foliage triangle.
std::vector<uint32_t> checkHierarchy(const VegetationModel& m, const std::vector<uint8_t>& foliage, const BoxHierarchy& h,
                                     const LeafRoots& roots) {
  std::vector<uint32_t> boxOf(m.triangleCount(), kNoBox);
  for (uint32_t b = 0; b < h.boxes.size(); ++b) {
    const FoliageBox& box = h.boxes[b];
    if (box.parent != kNoBox) {
      EXPECT_LT(box.parent, b) << "parents come first";
      EXPECT_EQ(box.level, h.boxes[box.parent].level + 1);
      if (box.boundsMin.x <= box.boundsMax.x) EXPECT_TRUE(inside(box, h.boxes[box.parent])) << "box " << b << " nests";
    }
    for (uint64_t i = box.firstTriangle; i < box.firstTriangle + box.triangleCount; ++i) {
      const uint32_t t = h.triangles[i];
      EXPECT_TRUE(foliage[t]) << "triangle " << t << " is foliage";
      EXPECT_EQ(boxOf[t], kNoBox) << "triangle " << t << " in two boxes";
      boxOf[t] = b;
      for (int k = 0; k < 3; ++k) {
        const glm::vec3& p = m.positions[m.indices[3 * t + k]];
        EXPECT_TRUE(glm::all(glm::greaterThanEqual(p, box.boundsMin)) && glm::all(glm::lessThanEqual(p, box.boundsMax)));
      }
    }
  }
  std::vector<uint32_t> boxOfLeaf(roots.leafCount(), kNoBox);
  for (size_t t = 0; t < foliage.size(); ++t) {
    if (!foliage[t]) continue;
    EXPECT_NE(boxOf[t], kNoBox) << "foliage triangle " << t << " in no box";
    const uint32_t leaf = roots.leafOfVertex[m.indices[3 * t]];
    if (boxOfLeaf[leaf] == kNoBox) boxOfLeaf[leaf] = boxOf[t];
    EXPECT_EQ(boxOfLeaf[leaf], boxOf[t]) << "leaf " << leaf << " split between boxes";
  }
  EXPECT_EQ(h.triangles.size(), size_t(std::count(foliage.begin(), foliage.end(), 1)));
  return boxOf;
}

}  // namespace

TEST(FoliageBoxes, TheGeneratorsBoxesFollowItsLSystemBrackets) {
  for (SceneKind kind : {SceneKind::Shrub, SceneKind::TreeCrown, SceneKind::Field, SceneKind::Kelp}) {
    SCOPED_TRACE(sceneName(kind));
    SceneDesc d;
    d.kind = kind;
    d.faces = 30000;
    VegetationModel plain, m;
    ASSERT_TRUE(generateScene(d, &plain).ok());
    d.boxes = true;
    SceneStats st;
    ASSERT_TRUE(generateScene(d, &m, &st).ok());
    EXPECT_TRUE(plain.boxParent.empty());
    ASSERT_EQ(m.positions, plain.positions) << "the boxes change no geometry";
    // Box 0 the scene, one per L-system plant, one per PUSH, one per blade or ribbon patch.
    // (The field counts its grass as a plant; kelp stems are not L-system plants.)
    const size_t patches = kind == SceneKind::Kelp || kind == SceneKind::Field ? 1 : 0;
    const size_t lsystemPlants = kind == SceneKind::Kelp ? 0 : kind == SceneKind::Field ? st.plants - 1 : st.plants;
    EXPECT_EQ(m.boxParent.size(), 1 + lsystemPlants + st.pushes + patches);
    const std::vector<uint8_t> foliage = foliageMask(m);
    LeafRoots roots;
    ASSERT_TRUE(computeLeafRoots(m, foliage, {}, &roots).ok());
    BoxHierarchy h;
    Status s = boxesFromModel(m, foliage, &h);
    ASSERT_TRUE(s.ok()) << s.message();
    checkHierarchy(m, foliage, h, roots);
    if (kind == SceneKind::Shrub || kind == SceneKind::TreeCrown) {
      size_t deepest = 0;
      for (const FoliageBox& b : h.boxes) deepest = std::max<size_t>(deepest, b.level);
      // Each derivation step nests its rule's brackets once more: scene, plant, the axiom's bracket,
      // then one level per step (a POP that did not close its box would nest every later one).
      EXPECT_GE(deepest, st.lsystemIterations) << "bracket depth grows with the derivation";
      EXPECT_LE(deepest, st.lsystemIterations + 3) << "every POP closes its box";
    }
  }
}

TEST(FoliageBoxes, AKdSplitOfTheLeafRootsStandsInForModelsWithoutBranches) {
  const VegetationModel m = makeLeafCloud(20000, 5, true);
  const std::vector<uint8_t> foliage = foliageMask(m);
  LeafRoots roots;
  ASSERT_TRUE(computeLeafRoots(m, foliage, {}, &roots).ok());
  for (uint32_t maxLeaves : {1u, 7u, 256u, 1u << 20}) {
    SCOPED_TRACE(maxLeaves);
    BoxHierarchy h;
    Status s = boxesFromLeafRoots(m, foliage, roots, maxLeaves, &h);
    ASSERT_TRUE(s.ok()) << s.message();
    checkHierarchy(m, foliage, h, roots);
    std::vector<std::set<uint32_t>> leaves(h.boxes.size());
    for (size_t b = 0; b < h.boxes.size(); ++b)
      for (uint64_t i = h.boxes[b].firstTriangle; i < h.boxes[b].firstTriangle + h.boxes[b].triangleCount; ++i)
        leaves[b].insert(roots.leafOfVertex[m.indices[3 * h.triangles[i]]]);
    std::vector<bool> hasChild(h.boxes.size(), false);
    for (const FoliageBox& b : h.boxes)
      if (b.parent != kNoBox) hasChild[b.parent] = true;
    for (size_t b = 0; b < h.boxes.size(); ++b) {
      EXPECT_LE(leaves[b].size(), maxLeaves) << "box " << b;
      if (hasChild[b]) EXPECT_TRUE(leaves[b].empty()) << "an inner box owns no leaves";
    }
    if (maxLeaves >= roots.leafCount()) EXPECT_EQ(h.boxes.size(), 1u);
  }
}

TEST(FoliageBoxes, InconsistentInputsAreRefused) {
  SceneDesc d;
  d.faces = 4000;
  d.boxes = true;
  VegetationModel m;
  ASSERT_TRUE(generateScene(d, &m).ok());
  const std::vector<uint8_t> foliage = foliageMask(m);
  BoxHierarchy h;
  VegetationModel bad = m;
  bad.boxParent[3] = 7;
  Status s = boxesFromModel(bad, foliage, &h);
  EXPECT_NE(s.message().find("box 3 has parent 7"), std::string::npos) << s.message();
  bad = m;
  const size_t t = size_t(std::find(foliage.begin(), foliage.end(), 1) - foliage.begin());
  bad.triangleBox[t] = uint32_t(m.boxParent.size());
  s = boxesFromModel(bad, foliage, &h);
  EXPECT_NE(s.message().find("foliage triangle " + std::to_string(t)), std::string::npos) << s.message();
  s = boxesFromModel(m, std::vector<uint8_t>(3, 1), &h);
  EXPECT_NE(s.message().find("foliage mask"), std::string::npos) << s.message();
  LeafRoots roots;
  ASSERT_TRUE(computeLeafRoots(m, foliage, {}, &roots).ok());
  s = boxesFromLeafRoots(m, foliage, roots, 0, &h);
  EXPECT_NE(s.message().find("maxLeavesPerBox"), std::string::npos) << s.message();
}

TEST(FoliageBoxes, ABoxOfManyLeavesIsRefinedIntoRegionalChildren) {
  // The field's grass is one patch box of thousands of blades: refined, it gets up to 16 children
  // of at most 64 blades each (or as close as 16 pieces allow), and the hierarchy stays valid.
  SceneDesc d;
  d.kind = SceneKind::Field;
  d.faces = 40000;
  d.boxes = true;
  VegetationModel m;
  ASSERT_TRUE(generateScene(d, &m).ok());
  const std::vector<uint8_t> foliage = foliageMask(m);
  LeafRoots roots;
  ASSERT_TRUE(computeLeafRoots(m, foliage, {}, &roots).ok());
  BoxHierarchy h;
  ASSERT_TRUE(boxesFromModel(m, foliage, &h).ok());
  const size_t before = h.boxes.size();
  auto ownLeaves = [&](const BoxHierarchy& x, uint32_t b) {
    std::set<uint32_t> leaves;
    for (uint64_t i = x.boxes[b].firstTriangle; i < x.boxes[b].firstTriangle + x.boxes[b].triangleCount; ++i)
      leaves.insert(roots.leafOfVertex[m.indices[3 * size_t(x.triangles[i])]]);
    return leaves.size();
  };
  size_t big = 0;
  for (uint32_t b = 0; b < before; ++b) big += ownLeaves(h, b) > 64;
  ASSERT_GT(big, 0u) << "the grass patch holds more than 64 blades";
  Status s = refineBoxes(m, foliage, roots, 64, 16, &h);
  ASSERT_TRUE(s.ok()) << s.message();
  checkHierarchy(m, foliage, h, roots);
  EXPECT_GT(h.boxes.size(), before);
  EXPECT_LE(h.boxes.size(), before + 16 * big);
  for (uint32_t b = 0; b < before; ++b) {
    size_t children = 0;
    for (uint32_t c = uint32_t(before); c < h.boxes.size(); ++c) children += h.boxes[c].parent == b;
    if (children) EXPECT_EQ(ownLeaves(h, b), 0u) << "a refined box hands all its leaves to its pieces";
  }
  for (uint32_t c = uint32_t(before); c < h.boxes.size(); ++c) {
    size_t siblings = 0;
    for (uint32_t x = uint32_t(before); x < h.boxes.size(); ++x) siblings += h.boxes[x].parent == h.boxes[c].parent;
    if (siblings < 16) EXPECT_LE(ownLeaves(h, c), 64u) << "piece " << c;
  }
  EXPECT_FALSE(refineBoxes(m, foliage, roots, 0, 16, &h).ok());
}
