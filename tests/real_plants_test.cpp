// Real plants in wind (issue 77; docs/design.md "Rigid parts in wind"): a plant whose foliage is one
// welded part sways at any size; the trunk bends with the crown it carries and its base stands
// (RigidMotion::FollowFoliage), where the paper's still background leaves it; Kenney's palm sways.
// Through createCanopy with the library's default (world) wind, validation and synchronization
// validation on.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "render/canopy.h"
#include "render/gltf_loader.h"
#include "render/layers.h"
#include "tests/assets.h"
#include "tests/gpu_test.h"
#include "tests/test_host.h"
#include "tools/leaf_cloud.h"

using namespace canopy;
using canopy::test::GpuTest;
using canopy::test::Host;

namespace {

class RealPlantsTest : public GpuTest {
 protected:
  uint64_t frameNumber = 0;
};

// A palm of `height` units: a rigid trunk (a thin box, "bark") and fronds welded into one foliage
// part ("leaves": a fan of quads sharing the crown's centre vertex), as Kenney's palm is.
VegetationModel weldedPalm(float height) {
  VegetationModel m;
  m.materials.resize(3);
  m.materials[0].name = "leaves";
  m.materials[0].baseColorFactor = glm::vec4(0.2f, 0.6f, 0.3f, 1.0f);
  m.materials[1].name = "bark";
  m.materials[1].baseColorFactor = glm::vec4(0.5f, 0.35f, 0.2f, 1.0f);
  m.materials[2].name = "default";
  auto vertex = [&](const glm::vec3& p) {
    m.positions.push_back(p * height);
    m.normals.push_back(glm::vec3(0, 0, 1));
    m.uvs.push_back(glm::vec2(p.x, p.y));
    return uint32_t(m.positions.size() - 1);
  };
  auto tri = [&](uint32_t a, uint32_t b, uint32_t c, uint32_t mat) {
    m.indices.insert(m.indices.end(), {a, b, c});
    m.triangleMaterial.push_back(mat);
  };
  // The trunk: two crossed quads from the foot to the crown.
  const float w = 0.03f;
  for (int k = 0; k < 2; ++k) {
    const glm::vec3 side = k ? glm::vec3(0, 0, w) : glm::vec3(w, 0, 0);
    const uint32_t a = vertex(-side), b = vertex(side), c = vertex(side + glm::vec3(0, 0.9f, 0)), d = vertex(-side + glm::vec3(0, 0.9f, 0));
    tri(a, b, c, 1);
    tri(a, c, d, 1);
  }
  // Eight fronds, every one sharing the crown's centre: one welded leaf.
  const uint32_t centre = vertex(glm::vec3(0, 0.9f, 0));
  for (int k = 0; k < 8; ++k) {
    const float a0 = float(k) * 0.785f, a1 = a0 + 0.3f;
    const uint32_t p = vertex(glm::vec3(0.45f * std::cos(a0), 0.75f, 0.45f * std::sin(a0)));
    const uint32_t q = vertex(glm::vec3(0.45f * std::cos(a1), 0.78f, 0.45f * std::sin(a1)));
    tri(centre, p, q, 0);
  }
  m.boundsMin = glm::vec3(INFINITY);
  m.boundsMax = glm::vec3(-INFINITY);
  for (const glm::vec3& p : m.positions) {
    m.boundsMin = glm::min(m.boundsMin, p);
    m.boundsMax = glm::max(m.boundsMax, p);
  }
  return m;
}

struct Frames {
  std::vector<std::vector<glm::vec4>> color;  // per frame
  std::vector<std::vector<float>> depth;
};

// `frames` frames of `model` at 320x240 in the default world wind of `speed` m/s (after 60 frames of
// warm-up), `rigid` motion; `woodApart`: no wood carried into the layers (LayerMesh::woodApart, as
// the Layers debug view has it: every rigid triangle drawn every frame), `carried`: the carried
// rigid triangles of the context.
Frames render(Device& dev, uint64_t& frameNumber, const VegetationModel& model, float speed, int frames,
           RigidMotion rigid = RigidMotion::FollowFoliage, bool woodApart = false, uint64_t* carried = nullptr) {
  Frames out;
  Host host;
  host.w = 320;
  host.h = 240;
  EXPECT_TRUE(host.create(dev, 1).ok());
  CanopyDesc d;
  d.width = host.w;
  d.height = host.h;
  d.colorFormat = host.colorFormat;
  d.params.wind.speed = speed;
  d.params.layers.rigidMotion = rigid;
  CanopyContext* ctx = nullptr;
  const Status made = createCanopy(dev, model, d, &ctx);
  EXPECT_TRUE(made.ok()) << made.message();
  if (!made.ok()) return out;
  LayeredVegetation& lv = canopyLayers(ctx);
  lv.mesh.woodApart = woodApart;
  if (carried) {
    *carried = 0;
    for (const MeshChunk& c : lv.mesh.chunks)
      if (c.carried) *carried += c.triangleCount;
  }
  const LayerView view = orbitView(model.boundsMin, model.boundsMax, 0.0f, 10.0f, 40.0f, 320.0f / 240.0f, 1.05f);
  for (int i = 0; i < 60 + frames; ++i) {
    EXPECT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok());
    if (i < 60) continue;
    std::vector<glm::vec4> c;
    std::vector<float> z;
    EXPECT_TRUE(host.read(&c, &z).ok());
    out.color.push_back(std::move(c));
    out.depth.push_back(std::move(z));
  }
  destroyCanopy(ctx);
  host.destroy();
  return out;
}

// The covered pixels' horizontal centroid in rows [y0, y1) (`pick`: which of them count).
double centroidX(const std::vector<float>& depth, const std::vector<glm::vec4>& color, int y0, int y1,
                 const std::function<bool(const glm::vec4&)>& pick = {}) {
  double sum = 0, n = 0;
  for (int y = std::max(y0, 0); y < std::min(y1, 240); ++y)
    for (int x = 0; x < 320; ++x) {
      const size_t i = size_t(y) * 320 + size_t(x);
      if (depth[i] >= 1.0f || (pick && !pick(color[i]))) continue;
      sum += x;
      n += 1;
    }
  return n > 0 ? sum / n : NAN;
}

// The rows the vegetation covers in a frame.
void coveredRows(const std::vector<float>& depth, int* top, int* bottom) {
  *top = 240;
  *bottom = -1;
  for (int y = 0; y < 240; ++y)
    for (int x = 0; x < 320; ++x)
      if (depth[size_t(y) * 320 + size_t(x)] < 1.0f) {
        *top = std::min(*top, y);
        *bottom = std::max(*bottom, y);
      }
}

// How far the top third of the vegetation sways (the range of its centroid over the frames) and
// bends (its mean centroid against the windless run's), pixels.
void swayAndBend(const Frames& wind, const Frames& calm, double* sway, double* bend) {
  int top = 0, bottom = 0;
  coveredRows(calm.depth[0], &top, &bottom);
  const int end = top + (bottom - top + 1) / 3;
  double lo = INFINITY, hi = -INFINITY, mean = 0, calmMean = 0;
  for (size_t f = 0; f < wind.depth.size(); ++f) {
    const double c = centroidX(wind.depth[f], wind.color[f], top, end);
    lo = std::min(lo, c);
    hi = std::max(hi, c);
    mean += c / double(wind.depth.size());
    calmMean += centroidX(calm.depth[f], calm.color[f], top, end) / double(wind.depth.size());
  }
  *sway = hi - lo;
  *bend = mean - calmMean;
}

// Before issue 77 a plant whose foliage is one welded part stood still in any wind: every root at
// one depth, the vertex shader put the leaf in the last layer while the placement counted it in the
// first, and that layer's height was 1 px. At any size it sways and bends now.
TEST_F(RealPlantsTest, APlantInOneWeldedPartSwaysAtAnySize) {
  for (float height : {0.1f, 1.36f, 30.0f}) {
    const VegetationModel palm = weldedPalm(height);
    const Frames calm = render(dev, frameNumber, palm, 0.0f, 45), breeze = render(dev, frameNumber, palm, 3.0f, 45),
              gale = render(dev, frameNumber, palm, 9.0f, 45);
    double swayB, bendB, swayG, bendG;
    swayAndBend(breeze, calm, &swayB, &bendB);
    swayAndBend(gale, calm, &swayG, &bendG);
    std::printf("welded palm %.2f units: breeze sway %.2f px bend %.2f px, gale sway %.2f px bend %.2f px\n", double(height), swayB,
                bendB, swayG, bendG);
    EXPECT_GE(std::abs(bendB), 0.5) << "a " << height << "-unit palm bends in a breeze";
    EXPECT_GE(swayG, 0.5) << "a " << height << "-unit palm sways in a gale";
    EXPECT_GT(std::abs(bendG), std::abs(bendB)) << "a gale bends it further";
  }
}

// Kenney's palm (../shared/assets), whose fronds are welded into one part: it sways in a breeze
// and a gale at 320x240 by at least half a pixel.
TEST_F(RealPlantsTest, KenneysPalmSways) {
  REQUIRE_ASSETS();
  VegetationModel palm;
  const Status s = loadGltf(test::kAssets + "/kenney_nature_palm_tall/tree_palmTall.glb", {}, &palm);
  ASSERT_TRUE(s.ok()) << s.message();
  const Frames calm = render(dev, frameNumber, palm, 0.0f, 45), breeze = render(dev, frameNumber, palm, 3.0f, 45),
            gale = render(dev, frameNumber, palm, 9.0f, 45);
  double swayB, bendB, swayG, bendG;
  swayAndBend(breeze, calm, &swayB, &bendB);
  swayAndBend(gale, calm, &swayG, &bendG);
  std::printf("Kenney's palm: breeze sway %.2f px bend %.2f px, gale sway %.2f px bend %.2f px\n", swayB, bendB, swayG, bendG);
  EXPECT_GE(swayB, 0.5);
  EXPECT_GE(swayG, 0.5);
}

// A crown on a trunk in a gale: with the rigid parts following the foliage the top of the trunk
// moves with the crown above it and its foot stands; the paper's still background leaves the
// trunk's top where it was while the crown leans off it.
TEST_F(RealPlantsTest, TheTrunkBendsWithItsCrownAndItsFootStands) {
  const VegetationModel tree = makeLeafCloud(3000, 7, true);
  // Bark pixels: the trunk's brown (leaf_cloud.cpp), the leaves green.
  auto bark = [](const glm::vec4& c) { return c.r > c.g; };
  const Frames calm = render(dev, frameNumber, tree, 0.0f, 30), follow = render(dev, frameNumber, tree, 9.0f, 30),
            still = render(dev, frameNumber, tree, 9.0f, 30, RigidMotion::Still);
  int top = 0, bottom = 0;
  coveredRows(calm.depth[0], &top, &bottom);
  // The trunk's rows below the crown: from where bark first shows alone to the foot.
  int trunkTop = bottom;
  for (int y = bottom; y > top; --y) {
    const double c = centroidX(calm.depth[0], calm.color[0], y, y + 1, [&](const glm::vec4& c) { return !bark(c); });
    if (!std::isnan(c)) break;  // foliage in this row: the crown
    trunkTop = y;
  }
  const int foot0 = bottom - (bottom - trunkTop) / 5, upper0 = trunkTop, upper1 = trunkTop + (bottom - trunkTop) / 5;
  double footShift = 0, upperFollow = 0, upperStill = 0;
  for (size_t f = 0; f < calm.depth.size(); ++f) {
    const double footCalm = centroidX(calm.depth[f], calm.color[f], foot0, bottom + 1, bark);
    const double upperCalm = centroidX(calm.depth[f], calm.color[f], upper0, upper1, bark);
    footShift = std::max(footShift, std::abs(centroidX(follow.depth[f], follow.color[f], foot0, bottom + 1, bark) - footCalm));
    upperFollow += (centroidX(follow.depth[f], follow.color[f], upper0, upper1, bark) - upperCalm) / double(calm.depth.size());
    upperStill += (centroidX(still.depth[f], still.color[f], upper0, upper1, bark) - upperCalm) / double(calm.depth.size());
  }
  double sway, crownBend;
  swayAndBend(follow, calm, &sway, &crownBend);
  std::printf("gale: crown bends %.2f px; the trunk's top %.2f px (still background: %.2f px); its foot at most %.2f px\n", crownBend,
              upperFollow, upperStill, footShift);
  EXPECT_GT(std::abs(crownBend), 2.0) << "the gale bends the crown";
  EXPECT_GT(std::abs(upperFollow), 0.25 * std::abs(crownBend)) << "the trunk's top goes with the crown";
  EXPECT_GT(upperFollow * crownBend, 0.0) << "the same way";
  EXPECT_LT(std::abs(upperStill), 0.25) << "the paper's background stays";
  EXPECT_LE(footShift, 0.5) << "the trunk's foot stands";
}

// The wood that follows its leaves fully is drawn into the layers at each re-slice, each triangle in
// its anchor's layer, and warped with them (render/layer_mesh.h carriesWood): it lands where the
// frame-by-frame draw of the same triangles puts it, the shared/rigid.h fixed point of the same
// displacement. Bark pixels' centroid per 8-row band, carried against drawn every frame, in a gale.
TEST_F(RealPlantsTest, TheWoodCarriedInTheLayersLandsWhereTheFrameByFrameDrawPutsIt) {
  const VegetationModel tree = makeLeafCloud(3000, 7, true);
  auto bark = [](const glm::vec4& c) { return c.r > c.g; };
  uint64_t carried = 0, apartCarried = 0;
  const Frames layers = render(dev, frameNumber, tree, 9.0f, 20, RigidMotion::FollowFoliage, false, &carried),
               apart = render(dev, frameNumber, tree, 9.0f, 20, RigidMotion::FollowFoliage, true, &apartCarried);
  ASSERT_GT(carried, 0u) << "the crown's branches follow fully: carried";
  ASSERT_EQ(layers.color.size(), apart.color.size());
  int top = 0, bottom = 0;
  coveredRows(apart.depth[0], &top, &bottom);
  double worst = 0, sum = 0;
  int bands = 0;
  for (size_t f = 0; f < layers.color.size(); ++f)
    for (int y = top; y + 8 <= bottom; y += 8) {
      const double a = centroidX(layers.depth[f], layers.color[f], y, y + 8, bark), b = centroidX(apart.depth[f], apart.color[f], y, y + 8, bark);
      if (std::isnan(a) || std::isnan(b)) continue;
      worst = std::max(worst, std::abs(a - b));
      sum += std::abs(a - b);
      ++bands;
    }
  ASSERT_GT(bands, 0);
  std::printf("carried %llu rigid triangles; bark centroid per band, carried against drawn every frame: mean %.3f px, max %.3f px (%d bands)\n",
              (unsigned long long)carried, sum / bands, worst, bands);
  EXPECT_LT(sum / bands, 0.25) << "the carried wood is where the frame-by-frame draw puts it (0.47 px with every carried triangle in the nearest layer)";
  EXPECT_LT(worst, 3.0);
}

}  // namespace
