// Layer layout parsing and placement arithmetic (paper 3.2, docs/design.md "Conventions where the paper is silent", layers).
#include <gtest/gtest.h>

#include "render/layer_layout.h"

using namespace canopy;

namespace {

LayerLayout parse(const char* text) {
  LayerLayout l;
  Status s = parseLayerLayout(text, &l);
  EXPECT_TRUE(s.ok()) << text << ": " << s.message();
  return l;
}

void expectPlacement(const char* layout, float zMin, float zMax, std::vector<float> wantBounds,
                     RegionSplit split = RegionSplit{}) {
  std::vector<LayerSlab> slabs;
  std::vector<float> b;
  Status s = placeLayers(parse(layout), split, zMin, zMax, &slabs, &b);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(b.size(), wantBounds.size()) << layout;
  for (size_t i = 0; i < b.size(); ++i) EXPECT_NEAR(b[i], wantBounds[i], 1e-5f) << layout << " boundary " << i;
  ASSERT_EQ(slabs.size() + 1, b.size());
  for (size_t i = 0; i < slabs.size(); ++i) {
    EXPECT_FLOAT_EQ(slabs[i].zNear, b[i]);
    EXPECT_FLOAT_EQ(slabs[i].zFar, b[i + 1]);
    EXPECT_FLOAT_EQ(slabs[i].depth, 0.5f * (b[i] + b[i + 1]));
    EXPECT_FLOAT_EQ(slabs[i].distance, slabs[i].depth - slabs[0].depth);
  }
}

}  // namespace

TEST(LayerLayout, ParsesThePapersNotation) {
  LayerLayout a = parse("3(1-1-1)");
  EXPECT_EQ(a.region[0], 1u);
  EXPECT_EQ(a.region[1], 1u);
  EXPECT_EQ(a.region[2], 1u);
  EXPECT_EQ(a.count(), 3u);
  LayerLayout b = parse("5(3-1-1)");
  EXPECT_EQ(b.region[0], 3u);
  EXPECT_EQ(b.count(), 5u);
  EXPECT_EQ(toString(b), "5(3-1-1)");
  LayerLayout c = parse("4");
  EXPECT_EQ(toString(c), "4(4-0-0)");
  LayerLayout d = parse("1(1-0-0)");
  EXPECT_EQ(d.count(), 1u);
  LayerLayout e = parse("4(0-4-0)");
  EXPECT_EQ(e.region[1], 4u);
  EXPECT_EQ(parse("32").count(), 32u);
}

TEST(LayerLayout, RefusesMalformedLayouts) {
  for (const char* bad : {"", "5(3-1)", "6(3-1-1)", "0", "0(0-0-0)", "33", "5(3-1-1)x", "(3-1-1)", "5(3-1-1",
                          "5[3-1-1]", "-1", "5(3--1-1)", "99999999999999(1-1-1)", "5(a-b-c)"}) {
    LayerLayout l;
    Status s = parseLayerLayout(bad, &l);
    EXPECT_FALSE(s.ok()) << "'" << bad << "' was accepted";
    EXPECT_NE(s.message().find("layer layout"), std::string::npos) << s.message();
  }
  LayerLayout l;
  EXPECT_NE(parseLayerLayout("6(3-1-1)", &l).message().find("hold 5 layers, not 6"), std::string::npos);
}

TEST(LayerPlacement, EqualThirdsAndEqualSpacingInsideRegions) {
  expectPlacement("3(1-1-1)", 0, 9, {0, 3, 6, 9});
  // Near third [0,3] in 3 layers, then one layer each for mid and far.
  expectPlacement("5(3-1-1)", 0, 9, {0, 1, 2, 3, 6, 9});
  expectPlacement("5(3-1-1)", 10, 19, {10, 11, 12, 13, 16, 19});
  std::vector<LayerSlab> slabs;
  std::vector<float> b;
  ASSERT_TRUE(placeLayers(parse("5(3-1-1)"), RegionSplit{}, 0, 9, &slabs, &b).ok());
  const float wantL[] = {0, 1, 2, 4, 7};  // centres 0.5, 1.5, 2.5, 4.5, 7.5
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(slabs[size_t(i)].distance, wantL[i], 1e-5f);
}

TEST(LayerPlacement, EmptyRegionsAreAbsorbedByTheirNeighbours) {
  expectPlacement("4(4-0-0)", 0, 8, {0, 2, 4, 6, 8});
  expectPlacement("4", 0, 8, {0, 2, 4, 6, 8});
  expectPlacement("3(0-3-0)", 0, 9, {0, 3, 6, 9});
  expectPlacement("2(0-0-2)", 0, 9, {0, 4.5f, 9});
  // Mid empty: near and far meet in the middle of the mid region.
  expectPlacement("2(1-0-1)", 0, 9, {0, 4.5f, 9});
  expectPlacement("3(2-0-1)", 0, 9, {0, 2.25f, 4.5f, 9});
  // Near empty: mid starts at the front.
  expectPlacement("2(0-1-1)", 0, 9, {0, 6, 9});
}

TEST(LayerPlacement, SingleLayerAndDegenerateRanges) {
  expectPlacement("1(1-0-0)", 2, 5, {2, 5});
  expectPlacement("1", 2, 5, {2, 5});
  expectPlacement("3(1-1-1)", 4, 4, {4, 4, 4, 4});
}

TEST(LayerPlacement, AbsoluteAndCustomRegionSplits) {
  RegionSplit fr;
  fr.nearEnd = 0.5f;
  fr.farStart = 0.75f;
  expectPlacement("3(1-1-1)", 0, 8, {0, 4, 6, 8}, fr);
  RegionSplit abs;
  abs.absolute = true;
  abs.nearEnd = 12;
  abs.farStart = 100;  // clamped to the range's end: the far region is empty in effect
  expectPlacement("4(2-1-1)", 10, 20, {10, 11, 12, 20, 20}, abs);
  RegionSplit bad;
  bad.nearEnd = 0.8f;
  bad.farStart = 0.2f;
  std::vector<LayerSlab> slabs;
  std::vector<float> b;
  EXPECT_FALSE(placeLayers(parse("3(1-1-1)"), bad, 0, 1, &slabs, &b).ok());
  EXPECT_FALSE(placeLayers(parse("3(1-1-1)"), RegionSplit{}, 2, 1, &slabs, &b).ok());
}

TEST(LayerPlacement, LayerOfDepthPutsEveryDepthInExactlyOneLayer) {
  std::vector<LayerSlab> slabs;
  std::vector<float> b;
  ASSERT_TRUE(placeLayers(parse("5(3-1-1)"), RegionSplit{}, 0, 9, &slabs, &b).ok());
  gpu::LayerFrame f{};
  f.layerCount = 5;
  for (size_t i = 0; i < b.size(); ++i) f.boundaries[i] = b[i];
  EXPECT_EQ(gpu::layerOfDepth(f, -100.0f), 0u);  // in front of the range: first layer
  EXPECT_EQ(gpu::layerOfDepth(f, 0.0f), 0u);
  EXPECT_EQ(gpu::layerOfDepth(f, 1.0f), 0u);     // on a boundary: the nearer layer (half-open (b_i, b_i+1])
  EXPECT_EQ(gpu::layerOfDepth(f, 1.0001f), 1u);
  EXPECT_EQ(gpu::layerOfDepth(f, 2.5f), 2u);
  EXPECT_EQ(gpu::layerOfDepth(f, 5.0f), 3u);
  EXPECT_EQ(gpu::layerOfDepth(f, 8.9f), 4u);
  EXPECT_EQ(gpu::layerOfDepth(f, 1e9f), 4u);     // behind: last layer
  for (float z = -1; z < 10; z += 0.01f) {
    const uint32_t l = gpu::layerOfDepth(f, z);
    ASSERT_LT(l, 5u);
    if (z > b[l] && z <= b[l + 1]) continue;
    EXPECT_TRUE((l == 0 && z <= b[1]) || (l == 4 && z > b[4])) << z;
  }
}
