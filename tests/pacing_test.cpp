// Paced re-slices (LayerSettings.pacedReslices; issue 79): a moving camera's re-slice drawn in even
// slices over the frames until its error would pass the thresholds, sliced for the view of the
// frame it is shown in. The policy's work per frame is checked by its counted work (the triangles
// each frame's layer passes are given), never by a timing.
#include <algorithm>

#include "tests/layers_test_fixture.h"

namespace canopy::test::layers {
namespace {

using PacingTest = LayersTest;

uint64_t meshTriangles(const LayeredVegetation& lv) {
  uint64_t n = 0;
  for (const MeshChunk& c : lv.mesh.chunks) n += c.triangleCount;
  return n;
}

// The triangles this frame's layer passes draw: a re-slice at once all of them, a slice its parts.
uint64_t trianglesDrawn(const LayeredVegetation& lv) {
  if (lv.reslice.rebuildPending) return meshTriangles(lv);
  uint64_t n = 0;
  if (lv.reslice.slicePending)
    for (const ChunkPart& p : lv.reslice.spread.slice) n += p.triangleCount;
  return n;
}

// An orbit of 0.4 degrees a frame around the model, 80 frames: every re-slice after the first view
// is paced (none at once), each is shown in the frame whose view it was sliced for (the orbit's
// motion predicted exactly), its layers are those a re-slice at once draws for that view, and no
// frame draws more than 1.5x the triangles of the median frame (the last slice, whose frame also
// copies the set in, draws less: pacedShares).
TEST_F(PacingTest, AnOrbitsReslicesArePacedEvenlyAndEqualOnesAtOnce) {
  const VegetationModel m = straddlingLeaves(12, 8, true);
  LayeredVegetationDesc d = smallDesc();
  d.writeIds = false;
  d.maxChunkVertices = 16;  // many chunks: every slice takes a share of each
  d.settings.pacedReslices = true;
  LayeredVegetationDesc once = d;
  once.settings.pacedReslices = false;
  LayeredVegetation x, y;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &x).ok());
  ASSERT_TRUE(createLayeredVegetation(dev, m, once, &y).ok());
  ASSERT_NE(x.targets.next.color.image, VkImage(VK_NULL_HANDLE)) << "a paced re-slice draws into a second layer set";
  auto run = std::make_unique<LayerFrames>(dev, x);
  ASSERT_TRUE(run->init().ok());
  LayerView v = frontView();
  ASSERT_TRUE(run->frame(v).ok());  // the first view, at once
  const glm::mat4 step = glm::rotate(glm::mat4(1.0f), glm::radians(0.4f), glm::vec3(0, 1, 0));
  std::vector<uint64_t> drawn;
  uint64_t shown = 0;
  bool compared = false;
  for (int frame = 1; frame <= 80; ++frame) {
    v.view = v.view * step;
    const uint64_t rebuildsBefore = x.stats.rebuilds;
    ASSERT_TRUE(run->frame(v).ok());
    drawn.push_back(trianglesDrawn(x));
    if (x.stats.rebuilds != rebuildsBefore)
      EXPECT_EQ(x.stats.lastRebuildReason.rfind("paced", 0), 0u) << "frame " << frame << ": " << x.stats.lastRebuildReason;
    if (x.stats.pacedRebuilds == shown) continue;
    shown = x.stats.pacedRebuilds;
    EXPECT_TRUE(run->changed) << "frame " << frame << ": the paced set is shown";
    // Sliced for this very frame's view.
    const glm::mat4 want = sliceCameraFor(x, v).view;
    float off = 0.0f;
    for (int c = 0; c < 4; ++c) off = std::max(off, glm::length(x.visible.view.view[c] - want[c]));
    EXPECT_LT(off, 1e-4f) << "frame " << frame;
    if (compared) continue;
    // The same layers as a re-slice at once for the slice camera it was drawn for.
    LayerView at = v;
    at.view = x.visible.view.view;
    ASSERT_TRUE(renderOnce(dev, y, at).ok());
    expectSameLayers(x, y, "paced_against_at_once");
    compared = true;
  }
  EXPECT_TRUE(compared) << "the orbit re-sliced";
  EXPECT_GE(shown, 3u);
  EXPECT_EQ(x.stats.rebuilds, 1 + shown + (x.stats.spreadPhase != 0 ? 1 : 0)) << "every re-slice of the orbit was paced";
  std::vector<uint64_t> sorted = drawn;
  std::sort(sorted.begin(), sorted.end());
  const uint64_t median = sorted[sorted.size() / 2], most = sorted.back();
  std::printf("%llu paced re-slices in 80 frames of a 0.4-degree orbit; triangles a frame: median %llu, most %llu (whole mesh %llu)\n",
              (unsigned long long)shown, (unsigned long long)median, (unsigned long long)most,
              (unsigned long long)meshTriangles(x));
  EXPECT_GT(median, 0u) << "a steady orbit draws a share in most frames";
  EXPECT_LE(double(most), 1.5 * double(median)) << "the most any frame draws against the median frame";
  EXPECT_LT(most, meshTriangles(x)) << "no frame draws the whole mesh";
  run.reset();
  destroyLayeredVegetation(x);
  destroyLayeredVegetation(y);
}

// The same orbit without pacing re-slices at once: each re-slice draws the whole mesh in one frame
// and the frames between draw nothing (the spike the pacing removes; the counted check above fails
// here, so it can fail).
TEST_F(PacingTest, WithoutPacingAnOrbitsReslicesComeWholeInOneFrame) {
  const VegetationModel m = straddlingLeaves(12, 8, true);
  LayeredVegetationDesc d = smallDesc();
  d.writeIds = false;
  d.maxChunkVertices = 16;
  LayeredVegetation x;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &x).ok());
  auto run = std::make_unique<LayerFrames>(dev, x);
  ASSERT_TRUE(run->init().ok());
  LayerView v = frontView();
  ASSERT_TRUE(run->frame(v).ok());
  const glm::mat4 step = glm::rotate(glm::mat4(1.0f), glm::radians(0.5f), glm::vec3(0, 1, 0));
  std::vector<uint64_t> drawn;
  for (int frame = 1; frame <= 60; ++frame) {
    v.view = v.view * step;
    ASSERT_TRUE(run->frame(v).ok());
    drawn.push_back(trianglesDrawn(x));
  }
  std::sort(drawn.begin(), drawn.end());
  EXPECT_GT(x.stats.rebuilds, 2u);
  EXPECT_EQ(drawn.back(), meshTriangles(x)) << "a re-slice at once draws the whole mesh in one frame";
  EXPECT_GT(double(drawn.back()), 1.5 * double(drawn[drawn.size() / 2]));
  run.reset();
  destroyLayeredVegetation(x);
}

}  // namespace
}  // namespace canopy::test::layers
