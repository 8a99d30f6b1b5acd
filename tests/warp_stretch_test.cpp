// Issue 67, no streaks: the inverse warp q = p - d(p) stretches a layer by 1 / (1 - |grad d|) along
// the displacement's gradient, so where d changes by a cell's width across one warp cell a texel
// is smeared over the whole cell (the close-up walk's grass drawn as vertical streaks). The
// displacement's change across one warp cell, over every layer and neighbouring corner pair, is
// bounded (docs/design.md "Layers: the warp's stretch").
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "compute/dynamics_reference.h"
#include "engine/transfer.h"
#include "render/canopy.h"
#include "tests/gpu_test.h"
#include "tests/test_host.h"
#include "tools/camera_paths.h"
#include "tools/scene_generator.h"

using namespace canopy;
using canopy::test::GpuTest;
using canopy::test::Host;

namespace {

class WarpStretchTest : public GpuTest {};

struct Stretch {
  float worst = 0.0f;  // the largest |d(a) - d(b)| / cellSize over neighbouring corners a, b
  float p99 = 0.0f;    // its 99th percentile over the corner pairs and frames
  float bounded = 0.0f;    // corners the bound shortened, share of all (every frame after the first 20)
  float referenceOff = 0.0f;  // the largest |GPU - CPU reference| of the bound, relative to max(|reference|, 1 px)
  float largest = 0.0f;       // the largest displacement, pixels
};

// A first-person walk through `model` (the demo's --camera walk) at `speed` m/s, `frames` frames,
// the stretch over the frames after the wind has risen (the first 20).
Stretch walkStretch(Device& dev, const VegetationModel& model, float speed, float maxStretch, int frames) {
  Stretch out;
  Host host;
  host.w = 480;
  host.h = 320;
  EXPECT_TRUE(host.create(dev, 1).ok());
  CanopyDesc d;
  d.width = host.w;
  d.height = host.h;
  d.colorFormat = host.colorFormat;
  CanopyContext* ctx = nullptr;
  Status s = createCanopy(dev, model, d, &ctx);
  EXPECT_TRUE(s.ok()) << s.message();
  CanopyParams p = canopyParams(ctx);
  p.wind.speed = speed;
  p.dynamics.maxStretch = maxStretch;
  if (s.ok()) s = setCanopyParams(ctx, p);
  CameraPath path;
  path.motion = CameraMotion::Walk;
  std::vector<float> steps;
  size_t shortened = 0, total = 0;
  for (int frame = 0; frame < frames && s.ok(); ++frame) {
    const LayerView view = cameraPathView(path, model.boundsMin, model.boundsMax, float(host.w) / float(host.h), uint32_t(frame));
    static uint64_t number = 0;  // never decreasing on one device, across contexts
    s = host.frame(++number, {ctx}, view, 1.0f / 30.0f);
    if (s.ok()) s = host.finish();
    if (!s.ok() || frame < 20) continue;
    const LayerDynamics& dyn = canopyDynamics(ctx);
    const gpu::AnimFrame& a = dyn.current;
    const uint32_t corners = a.gridX * a.gridY;
    std::vector<glm::vec2> disp(size_t(corners) * a.layerCount);
    std::vector<glm::vec2> raw(disp.size());
    s = readbackBuffer(dev, dyn.displacement, disp.data(), disp.size() * 8, rg::stateOf(rg::Use::ComputeStorageRead));
    if (s.ok()) s = readbackBuffer(dev, dyn.raw, raw.data(), raw.size() * 8, rg::stateOf(rg::Use::ComputeStorageRead));
    // The two sweeps on the GPU against the brute-force reference (boundStretchReference).
    const std::vector<glm::vec2> want = boundStretchReference(a, raw);
    for (size_t i = 0; i < disp.size() && s.ok(); ++i) {
      out.referenceOff = std::max(out.referenceOff, glm::length(disp[i] - want[i]) / std::max(glm::length(want[i]), 1.0f));
      out.largest = std::max(out.largest, glm::length(disp[i]));
      shortened += glm::length(disp[i]) < glm::length(raw[i]) - 1e-3f;
      ++total;
    }
    for (uint32_t l = 0; l < a.layerCount && s.ok(); ++l)
      for (uint32_t y = 0; y < a.gridY; ++y)
        for (uint32_t x = 0; x < a.gridX; ++x) {
          const glm::vec2 c = disp[size_t(l) * corners + y * a.gridX + x];
          if (x + 1 < a.gridX) steps.push_back(glm::length(disp[size_t(l) * corners + y * a.gridX + x + 1] - c) / float(a.cellSize));
          if (y + 1 < a.gridY) steps.push_back(glm::length(disp[size_t(l) * corners + (y + 1) * a.gridX + x] - c) / float(a.cellSize));
        }
  }
  EXPECT_TRUE(s.ok()) << s.message();
  destroyCanopy(ctx);
  host.destroy();
  out.bounded = total ? float(shortened) / float(total) : 0.0f;
  if (!steps.empty()) {
    std::sort(steps.begin(), steps.end());
    out.worst = steps.back();
    out.p99 = steps[steps.size() * 99 / 100];
  }
  return out;
}

TEST_F(WarpStretchTest, AWalkThroughGrassInAGaleStretchesNoLayerIntoStreaks) {
  SceneDesc sd;
  sd.kind = SceneKind::GrassField;
  sd.faces = 20000;
  VegetationModel grass;
  ASSERT_TRUE(generateScene(sd, &grass).ok());
  // The library's gale: three times the default breeze (issue 67).
  const float gale = 3.0f * WorldWind{}.speed;
  const float bound = DynamicsParams{}.maxStretch;
  const Stretch st = walkStretch(dev, grass, gale, bound, 36);
  const Stretch free = walkStretch(dev, grass, gale, 0.0f, 36);
  std::printf("walk through grass at %.0f m/s: the displacement's change across one warp cell, worst %.3f cells, "
              "99th percentile %.3f (maxStretch %.2f, %.1f %% of the corners shortened, %.2g off the CPU reference, largest %.0f px); "
              "unbounded: worst %.3f, 99th percentile %.3f\n",
              gale, st.worst, st.p99, bound, 100.0 * st.bounded, st.referenceOff, st.largest, free.worst, free.p99);
  EXPECT_LE(st.referenceOff, 1e-4f) << "the GPU's two sweeps differ from the brute-force reference";
  // A corner just in front of the camera's plane once gave a layer a root line 450 image heights
  // down and every corner tens of thousands of pixels (render/layer_placement.cpp finish).
  EXPECT_LE(st.largest, float(2 * 320)) << "a displacement beyond any plant's on-screen height";
  EXPECT_GT(st.bounded, 0.01f) << "the bound shortened nothing: the reference comparison tests nothing";
  // Half a cell: no texel drawn more than twice its width (1 / (1 - 1/2)). The bound holds the
  // magnitude's change to maxStretch; the direction's turn across a cell adds the rest.
  EXPECT_LE(st.worst, 0.5f) << "a layer stretched into streaks";
  EXPECT_GT(st.worst, 0.1f) << "the wind moved nothing";
  EXPECT_GT(free.worst, 0.5f) << "without the bound the walk passes the bound above (the test could not fail)";
}

}  // namespace
