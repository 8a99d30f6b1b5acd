// Hosts of the shapes that exist (issue 78; docs/embedding.md "Host shapes"): a classic VkRenderPass
// whose colour ends in PRESENT_SRC_KHR with its scene pass pre-recorded once per image and Canopy
// recorded each frame into per-frame command buffers; a host drawing into a viewport (a
// sub-rectangle of its targets, also flipped); a GL projection (clip depth -1..1); a jittered camera
// (TAA): no re-slice from a jitter, motion vectors without it, the composite at the jittered
// position. Validation and synchronization validation are on (GpuTest): any message fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>

#include "engine/camera.h"
#include "engine/transfer.h"
#include "render/canopy.h"
#include "tests/gpu_test.h"
#include "tests/test_host.h"
#include "tools/leaf_cloud.h"

using namespace canopy;
using canopy::test::GpuTest;
using canopy::test::Host;
using canopy::test::differing;
using canopy::test::kSky;

namespace {

class HostShapesTest : public GpuTest {
 protected:
  void configure(DeviceDesc& d) override {
    d.framesInFlight = 2;
    d.deferUploads = true;
    // PRESENT_SRC_KHR is the swapchain extension's layout (the render-pass host's colour ends in it).
    d.instanceExtensions.push_back(VK_KHR_SURFACE_EXTENSION_NAME);
    d.deviceExtensions.push_back(VK_KHR_SWAPCHAIN_EXTENSION_NAME);
  }
  VegetationModel model = makeLeafCloud(3000, 5, true);
  uint64_t frameNumber = 0;

  CanopyContext* make(const Host& host, float wind, VkFormat motion = VK_FORMAT_UNDEFINED) {
    CanopyDesc d;
    d.width = host.w;
    d.height = host.h;
    d.colorFormat = host.colorFormat;
    d.depthFormat = host.depthFormat;
    d.motionFormat = motion;
    d.params.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    d.params.simulation.wind.strength = wind;
    CanopyContext* ctx = nullptr;
    Status s = createCanopy(dev, model, d, &ctx);
    EXPECT_TRUE(s.ok()) << s.message();
    return ctx;
  }
  // `frames` frames at `view` (the camera then changed by host.adjustCamera), the last read back.
  void render(Host& host, const LayerView& view, int frames, float wind, std::vector<glm::vec4>* rgba, std::vector<float>* z) {
    ASSERT_TRUE(host.create(dev, 2).ok());
    CanopyContext* ctx = make(host, wind);
    ASSERT_NE(ctx, nullptr);
    for (int i = 0; i < frames; ++i) {
      Status s = host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f);
      ASSERT_TRUE(s.ok()) << s.message();
    }
    Status s = host.read(rgba, z);
    ASSERT_TRUE(s.ok()) << s.message();
    destroyCanopy(ctx);
    host.destroy();
  }
  LayerView orbit(float yaw, float aspect) const { return orbitView(model.boundsMin, model.boundsMax, yaw, 10.0f, 40.0f, aspect, 1.05f); }
};

// The share of the vegetation (pixels that are not sky) and its coverage-weighted centroid.
struct Coverage {
  double pixels = 0;
  glm::dvec2 centroid{0.0};
};
Coverage coverageOf(const std::vector<glm::vec4>& c, uint32_t w) {
  Coverage r;
  for (size_t i = 0; i < c.size(); ++i) {
    const double a = std::min(1.0, double(canopy::test::maxDiff(c[i], kSky)) / 0.2);  // 0: sky
    r.pixels += a;
    r.centroid += a * glm::dvec2(double(i % w) + 0.5, double(i / w) + 0.5);
  }
  if (r.pixels > 0) r.centroid /= r.pixels;
  return r;
}

// The Halton sequence's k-th point (bases 2 and 3), as a jitter in [-0.5, 0.5) pixels.
glm::vec2 halton23(uint32_t k) {
  auto h = [](uint32_t i, uint32_t b) {
    float f = 1.0f, r = 0.0f;
    for (; i > 0; i /= b) {
      f /= float(b);
      r += f * float(i % b);
    }
    return r;
  };
  return glm::vec2(h(k + 1, 2), h(k + 1, 3)) - 0.5f;
}

// ---------------------------------------------------------------------------------------------
// Viewports

// A 128x96 host drawing into the 64x48 rectangle at (40, 24) shows there what a 64x48 host shows,
// and leaves every pixel outside it as the host left it; a flipped viewport (negative height, the
// projection's y mirrored) shows the same.
TEST_F(HostShapesTest, AViewportShowsWhatATargetOfItsSizeShowsAndNothingOutsideIt) {
  const LayerView view = orbit(20.0f, 64.0f / 48.0f);
  std::vector<glm::vec4> small, big, flipped;
  std::vector<float> zSmall, zBig, zFlipped;
  Host a;
  a.w = 64;
  a.h = 48;
  render(a, view, 6, 1.5f, &small, &zSmall);
  Host b;
  b.w = 128;
  b.h = 96;
  b.adjustCamera = [](CanopyCamera& c) { c.viewport = {32.0f, 16.0f, 64.0f, 48.0f, 0.0f, 1.0f}; };
  render(b, view, 6, 1.5f, &big, &zBig);
  Host f;
  f.w = 128;
  f.h = 96;
  f.adjustCamera = [](CanopyCamera& c) {
    c.viewport = {32.0f, 64.0f, 64.0f, -48.0f, 0.0f, 1.0f};  // y up, as a GL-minded host sets it
    for (int col = 0; col < 4; ++col) c.proj.m[col * 4 + 1] = -c.proj.m[col * 4 + 1];
  };
  render(f, view, 6, 1.5f, &flipped, &zFlipped);
  std::vector<glm::vec4> inside;
  std::vector<float> zInside;
  size_t outsideTouched = 0;
  for (uint32_t y = 0; y < b.h; ++y)
    for (uint32_t x = 0; x < b.w; ++x) {
      const size_t i = size_t(y) * b.w + x;
      if (x >= 32 && x < 96 && y >= 16 && y < 64) {
        inside.push_back(big[i]);
        zInside.push_back(zBig[i]);
      } else {
        outsideTouched += canopy::test::maxDiff(big[i], kSky) > 1e-3f || zBig[i] != 1.0f;
      }
    }
  const Coverage cov = coverageOf(small, a.w);
  EXPECT_GT(cov.pixels, 0.05 * small.size()) << "the plant fills part of the viewport";
  const double d = differing(inside, small, 3.0f / 255.0f);
  size_t depthOff = 0;
  for (size_t i = 0; i < zInside.size(); ++i) depthOff += std::abs(zInside[i] - zSmall[i]) > 1e-5f;
  const Coverage covIn = coverageOf(inside, a.w);
  std::printf("viewport: coverage %.1f vs %.1f px, centroid (%.3f, %.3f) vs (%.3f, %.3f)\n", covIn.pixels, cov.pixels, covIn.centroid.x,
              covIn.centroid.y, cov.centroid.x, cov.centroid.y);
  std::printf("viewport: %.4f of the rectangle's pixels differ from the small host's, %zu depths; %zu touched outside\n", d,
              depthOff, outsideTouched);
  // The rectangle's corner on a warp-grid corner of both hosts' layers: the same warp, the same image.
  EXPECT_LE(d, 0.002);
  EXPECT_LE(double(depthOff) / zInside.size(), 0.002);
  EXPECT_NEAR(covIn.centroid.x, cov.centroid.x, 0.02) << "the same sway: the simulation's tile spans the viewport";
  EXPECT_EQ(outsideTouched, 0u) << "nothing is drawn outside the viewport";
  EXPECT_LE(differing(flipped, big, 3.0f / 255.0f), 0.002) << "a flipped viewport with the projection's y mirrored";
}

// A GL projection (clip depth -w..w) drawn with depth clip control's negativeOneToOne writes
// (z/w + 1) / 2, which for the same near and far is Vulkan's depth: both draw the same image.
TEST_F(HostShapesTest, AGlProjectionWithItsClipDepthNamedDrawsWhatTheVulkanOneDraws) {
  LayerView view = orbit(20.0f, 96.0f / 64.0f);
  const glm::vec3 centre = 0.5f * (model.boundsMin + model.boundsMax);
  const float dist = glm::length(glm::vec3(glm::inverse(view.view)[3]) - centre), radius = 0.5f * glm::length(model.boundsMax - model.boundsMin);
  const float zn = std::max(0.05f * dist, dist - 2.0f * radius), zf = dist + 2.0f * radius;
  glm::mat4 vk = glm::perspectiveRH_ZO(glm::radians(40.0f), 96.0f / 64.0f, zn, zf), gl = glm::perspectiveRH_NO(glm::radians(40.0f), 96.0f / 64.0f, zn, zf);
  vk[1][1] *= -1.0f;
  gl[1][1] *= -1.0f;
  view.proj = vk;
  std::vector<glm::vec4> cv, cg;
  std::vector<float> zv, zg;
  Host a, b;
  render(a, view, 5, 1.5f, &cv, &zv);
  b.adjustCamera = [gl](CanopyCamera& c) {
    c.proj = toFloat4x4(gl);
    c.clipDepth = ClipDepth::NegativeOneToOne;
  };
  render(b, view, 5, 1.5f, &cg, &zg);
  size_t depthOff = 0, covered = 0;
  for (size_t i = 0; i < zv.size(); ++i) {
    covered += zv[i] < 1.0f;
    depthOff += std::abs(zv[i] - zg[i]) > 1e-5f;
  }
  EXPECT_GT(covered, zv.size() / 20);
  EXPECT_LE(differing(cv, cg, 3.0f / 255.0f), 0.002);
  EXPECT_LE(double(depthOff) / zv.size(), 0.002) << "the depth the host's negativeOneToOne viewport writes";
}

// A viewport outside the targets, a depth range other than 0..1, a jitter beyond a pixel and an
// unknown clip depth are refused, naming the field; the host's frame goes on without Canopy.
TEST_F(HostShapesTest, ACameraTheTargetsCannotHoldIsRefusedByName) {
  Host host;
  ASSERT_TRUE(host.create(dev, 2).ok());
  CanopyContext* ctx = make(host, 1.0f);
  ASSERT_NE(ctx, nullptr);
  const LayerView view = orbit(20.0f, 1.5f);
  struct Case {
    std::function<void(CanopyCamera&)> change;
    const char* named;
  };
  const Case cases[] = {
      {[](CanopyCamera& c) { c.viewport = {40.0f, 10.0f, 64.0f, 48.0f, 0.0f, 1.0f}; }, "reaches outside the 96x64 targets"},
      {[](CanopyCamera& c) { c.viewport = {0.0f, 0.0f, 48.0f, 32.0f, 0.5f, 1.0f}; }, "minDepth = 0.5"},
      {[](CanopyCamera& c) { c.viewport = {0.0f, 0.0f, -4.0f, 32.0f, 0.0f, 1.0f}; }, "width must be > 0"},
      {[](CanopyCamera& c) { c.jitter[1] = 1.5f; }, "CanopyCamera.jitter.y = 1.5 pixels is outside [-1, 1]"},
      {[](CanopyCamera& c) { c.jitter[0] = NAN; }, "non-finite"},
      {[](CanopyCamera& c) { c.clipDepth = ClipDepth(7); }, "CanopyCamera.clipDepth = 7"},
  };
  for (const Case& k : cases) {
    host.adjustCamera = k.change;
    Status refusal;
    ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f, false, nullptr, &refusal).ok());
    EXPECT_FALSE(refusal.ok());
    EXPECT_NE(refusal.message().find(k.named), std::string::npos) << refusal.message();
  }
  host.adjustCamera = nullptr;
  ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok()) << "and the next good frame records";
  ASSERT_TRUE(host.finish().ok());
  destroyCanopy(ctx);
  host.destroy();
}

// ---------------------------------------------------------------------------------------------
// Jittered cameras (TAA, upscalers)

// 64 frames of a still camera jittered by Halton (2, 3) in wind: no re-slice after the first.
TEST_F(HostShapesTest, AJitterAloneNeverReslices) {
  Host host;
  ASSERT_TRUE(host.create(dev, 2).ok());
  CanopyContext* ctx = make(host, 2.0f);
  ASSERT_NE(ctx, nullptr);
  const LayerView view = orbit(20.0f, 1.5f);
  ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok());
  const uint64_t rebuilds = canopyStats(ctx).layers.rebuilds;
  uint32_t k = 0;
  host.adjustCamera = [&k](CanopyCamera& c) {
    const glm::vec2 j = halton23(k++ % 8);
    c.jitter[0] = j.x;
    c.jitter[1] = j.y;
  };
  for (int i = 0; i < 64; ++i) ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok());
  EXPECT_EQ(canopyStats(ctx).layers.rebuilds, rebuilds) << "a jitter alone re-sliced: " << canopyStats(ctx).layers.lastRebuildReason;
  ASSERT_TRUE(host.finish().ok());
  destroyCanopy(ctx);
  host.destroy();
}

// The motion vectors of a jittered host equal the unjittered host's (a still and an orbiting
// camera, in wind), and the image moves by the jitter: the composite reads the layers at the
// jittered position.
TEST_F(HostShapesTest, MotionVectorsExcludeTheJitterAndTheImageMovesByIt) {
  for (const float turn : {0.0f, 0.4f}) {
    std::vector<glm::vec2> motion[2];
    std::vector<glm::vec4> color[2];
    for (int jittered = 0; jittered < 2; ++jittered) {
      Host host;
      host.motion = true;
      ASSERT_TRUE(host.create(dev, 2).ok());
      CanopyContext* ctx = make(host, 2.0f, VK_FORMAT_R16G16_SFLOAT);
      ASSERT_NE(ctx, nullptr);
      uint32_t k = 0;
      if (jittered)
        host.adjustCamera = [&k](CanopyCamera& c) {
          const glm::vec2 j = halton23(k++ % 8);
          c.jitter[0] = j.x;
          c.jitter[1] = j.y;
        };
      for (int i = 0; i < 12; ++i) ASSERT_TRUE(host.frame(++frameNumber, {ctx}, orbit(20.0f + turn * float(i), 1.5f), 1.0f / 30.0f).ok());
      std::vector<float> z;
      ASSERT_TRUE(host.read(&color[jittered], &z).ok());
      ASSERT_TRUE(host.readMotion(&motion[jittered]).ok());
      destroyCanopy(ctx);
      host.destroy();
    }
    // The jitter of frame 12 (k = 11) against frame 11's: what motion vectors with the jitter would add.
    const glm::vec2 jNow = halton23(11 % 8), jBefore = halton23(10 % 8);
    // Per pixel the two sample the layers half a pixel apart (a leaf's edge, the sway's gradient);
    // on average over the foliage the difference is what the jitter would add: its step.
    glm::dvec2 mean0(0.0), mean1(0.0);
    double perPixel = 0;
    size_t n = 0;
    for (size_t i = 0; i < motion[0].size(); ++i) {
      if (motion[0][i] == glm::vec2(0.0f) || motion[1][i] == glm::vec2(0.0f)) continue;  // not the front foliage in both
      mean0 += glm::dvec2(motion[0][i]);
      mean1 += glm::dvec2(motion[1][i]);
      perPixel += glm::length(motion[1][i] - motion[0][i]);
      ++n;
    }
    ASSERT_GT(n, 50u);
    const double offset = glm::length(mean1 - mean0) / double(n), step = glm::length(jNow - jBefore);
    const Coverage c0 = coverageOf(color[0], 96), c1 = coverageOf(color[1], 96);
    const glm::dvec2 moved = c1.centroid - c0.centroid;
    std::printf("turn %.1f deg/frame: mean motion (jittered - not) %.4f px over %zu pixels, per pixel %.3f px (the jitter's "
                "step %.3f px); centroid moved (%.3f, %.3f) px for a jitter (%.3f, %.3f)\n",
                turn, offset, n, perPixel / double(n), step, moved.x, moved.y, jNow.x, jNow.y);
    EXPECT_LE(offset, 0.05 * step) << "the motion vectors carry no jitter";
    EXPECT_NEAR(moved.x, jNow.x, 0.12);
    EXPECT_NEAR(moved.y, jNow.y, 0.12);
  }
}

}  // namespace
