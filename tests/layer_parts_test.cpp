// The layered vegetation's parts alone (CONTRIBUTING.md "The module map"): each is handed the plain
// structs it reads, so these tests build them by hand, without a device or a model. The re-slice
// scheduler's decisions (docs/design.md "Layers: reprojection" and "Layers: spread re-slicing")
// from a hand-made visible set, copies' bounds, mesh size and settings; the mesh part's run
// cutting at chunk borders; the placement part's footprint.
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <gtest/gtest.h>

#include "engine/camera.h"
#include "render/layer_mesh.h"
#include "render/layer_placement.h"
#include "render/reslice_scheduler.h"

namespace canopy {
namespace {

const glm::vec3 kMin(-1.0f, 0.0f, -1.0f), kMax(1.0f, 2.0f, 1.0f);
constexpr uint32_t kWidth = 1024, kHeight = 768;

LayerView orbit(float yawDegrees) {
  return orbitView(kMin, kMax, yawDegrees, 10.0f, 45.0f, float(kWidth) / float(kHeight));
}

// What the scheduler is handed, made by hand: one copy of a 2 m box, four slabs through it for the
// camera the visible set was drawn from, a mesh of `triangles` in one chunk.
struct SchedulerScene {
  LayerSettings settings;
  LayerMesh mesh;
  LayerInstances instances;
  VisibleLayers visible;
  LayerStats stats;
  PlacementInputs placement;
  ResliceScheduler scheduler;
  bool spread = false;
  uint32_t fixedSlice = 0;

  explicit SchedulerScene(uint32_t triangles = 1000) {
    instances.models = {glm::mat4(1.0f)};
    instances.boundsMin = kMin;
    instances.boundsMax = kMax;
    MeshChunk c;
    c.triangleCount = triangles;
    c.foliage = true;
    mesh.chunks = {c};
  }
  ResliceParts parts() {
    placement.mesh = &mesh;
    placement.instances = &instances;
    placement.settings = &settings;
    placement.width = kWidth;
    placement.height = kHeight;
    return ResliceParts{placement, settings, mesh, visible, stats, nullptr, glm::uvec2(kWidth, kHeight), spread, fixedSlice};
  }
  ResliceDecision decide(const LayerView& view) { return decideReslice(scheduler, parts(), view, view); }
  // A decision taken as advanceReslice takes it, without the placement: a re-slice for `view`
  // makes the visible set that camera's (its slabs through the box's centre).
  ResliceDecision step(const LayerView& view) {
    const ResliceDecision d = decide(view);
    if (!d.reason.empty()) {
      acceptReslice(scheduler, view);
      visible.view = view;
      const float centre = -(view.view * glm::vec4(0.0f, 1.0f, 0.0f, 1.0f)).z;
      visible.layers.assign(4, LayerInfo{});
      for (int i = 0; i < 4; ++i) {
        LayerSlab& s = visible.layers[i].slab;
        s.zNear = centre - 1.5f + 0.75f * float(i);
        s.zFar = s.zNear + 0.75f;
        s.depth = 0.5f * (s.zNear + s.zFar);
        s.distance = s.depth - (centre - 1.5f + 0.375f);
      }
    }
    return d;
  }
};

TEST(ResliceScheduler, FirstViewIsAtOnceUnlessTheMeshIsStreamed) {
  SchedulerScene a;
  a.spread = true;  // a first view has nothing to show meanwhile: at once all the same
  ResliceDecision d = a.decide(orbit(0.0f));
  EXPECT_EQ(d.reason, "first view");
  EXPECT_TRUE(d.atOnce);

  SchedulerScene b;
  b.mesh.streamed = true;  // cannot be drawn in one frame: slices as large as the ring, no fade
  d = b.decide(orbit(0.0f));
  EXPECT_EQ(d.reason, "first view");
  EXPECT_FALSE(d.atOnce);
  EXPECT_TRUE(d.immediate);
}

TEST(ResliceScheduler, CameraErrorDecides) {
  SchedulerScene s;
  ASSERT_FALSE(s.step(orbit(0.0f)).reason.empty());
  // The same camera, and a turn whose error stays under half a pixel: the visible set serves.
  EXPECT_EQ(s.step(orbit(0.0f)).reason, "");
  EXPECT_EQ(s.step(orbit(0.001f)).reason, "");
  // A 5 degree orbit: parallax within the slabs far over the threshold.
  const ResliceDecision d = s.step(orbit(5.0f));
  EXPECT_NE(d.reason.find("reprojection error"), std::string::npos) << d.reason;
  EXPECT_TRUE(d.atOnce);  // no rebuild budget: never spread
  // Measured from the new set: the same camera again needs nothing.
  EXPECT_EQ(s.step(orbit(5.0f)).reason, "");
  // A looser threshold lets the same orbit through.
  s.settings.errorThresholdPixels = 1000.0f;
  s.settings.turnThresholdDegrees = 180.0f;
  EXPECT_EQ(s.step(orbit(10.0f)).reason, "");
}

TEST(ResliceScheduler, RequestsSettingsAndPolicy) {
  SchedulerScene s;
  s.spread = true;
  s.step(orbit(0.0f));
  requestReslice(s.scheduler, "asked", false);
  ResliceDecision d = s.step(orbit(0.0f));
  EXPECT_EQ(d.reason, "asked");
  EXPECT_FALSE(d.atOnce);  // spread: a rebuild budget and not asked at once
  requestReslice(s.scheduler, "asked at once", true);
  d = s.step(orbit(0.0f));
  EXPECT_EQ(d.reason, "asked at once");
  EXPECT_TRUE(d.atOnce);
  rescheduleAfterChange(s.scheduler, true, false, false);
  EXPECT_EQ(s.step(orbit(0.0f)).reason, "settings changed");
  EXPECT_EQ(s.step(orbit(0.0f)).reason, "");
  s.settings.policy = ReslicePolicy::EveryFrame;
  d = s.step(orbit(0.0f));
  EXPECT_EQ(d.reason, "every frame");
  EXPECT_TRUE(d.atOnce);
}

TEST(ResliceScheduler, SpreadRunsToItsEndUnlessOutrunOrForced) {
  SchedulerScene s;
  s.spread = true;
  s.step(orbit(0.0f));
  ResliceDecision d = s.step(orbit(3.0f));  // a single jump: spread
  ASSERT_FALSE(d.reason.empty());
  EXPECT_FALSE(d.atOnce);
  s.scheduler.spread.phase = SpreadPhase::Drawing;  // ... and under way, its set still the old camera's
  s.visible.view = orbit(0.0f);
  // Beyond the threshold but within kSpreadBehind of the visible set: the spread re-slice goes on.
  s.settings.errorThresholdPixels = 200.0f;
  s.settings.turnThresholdDegrees = 4.0f;
  s.scheduler.lastRebuildView = orbit(0.0f);
  EXPECT_EQ(s.decide(orbit(3.0f)).reason, "");
  // Past kSpreadBehind x the thresholds of the visible set: dropped for a re-slice at once.
  d = s.decide(orbit(20.0f));
  EXPECT_NE(d.reason.find("a spread re-slice fell behind the camera"), std::string::npos) << d.reason;
  EXPECT_TRUE(d.atOnce);
  EXPECT_TRUE(d.outrun);
  // A request restarts it whatever the camera.
  requestReslice(s.scheduler, "forced", false);
  EXPECT_EQ(s.decide(orbit(20.0f)).reason, "forced");
}

// A camera moving steadily: a spread re-slice that would take more frames than the error allows is
// not started (a re-slice at once instead), while a mesh a few slices long is spread.
TEST(ResliceScheduler, SteadyMotionOutrunsALongSpread) {
  for (const uint32_t triangles : {1000u, 10000000u}) {
    SchedulerScene s(triangles);
    s.spread = true;
    s.fixedSlice = 1024;
    s.step(orbit(0.0f));
    ResliceDecision d;
    float yaw = 0.0f;
    for (int frame = 0; frame < 200 && d.reason.empty(); ++frame) d = s.step(orbit(yaw += 0.05f));
    ASSERT_FALSE(d.reason.empty()) << triangles << " triangles: no re-slice in 10 degrees";
    const bool outrun = d.reason.rfind("a spread re-slice would fall behind the camera", 0) == 0;
    EXPECT_EQ(outrun, triangles > 1000u) << d.reason;
    EXPECT_EQ(d.atOnce, outrun) << d.reason;
  }
}

// The mesh part cuts a GPU-order triangle run at its chunks' borders.
TEST(LayerMeshParts, RunsAreCutAtChunkBorders) {
  std::vector<MeshChunk> chunks(3);
  uint64_t first = 0;
  for (uint32_t i = 0; i < 3; ++i) {
    chunks[i].firstTriangle = first;
    chunks[i].triangleCount = 100 * (i + 1);
    first += chunks[i].triangleCount;
  }
  std::vector<ChunkPart> parts;
  appendRunParts(chunks, 50, 400, 0.5f, 2, &parts);  // triangles 50..449: chunks 0, 1 and 2
  ASSERT_EQ(parts.size(), 3u);
  EXPECT_EQ(parts[0].chunk, 0u);
  EXPECT_EQ(parts[0].firstTriangle, 50u);
  EXPECT_EQ(parts[0].triangleCount, 50u);
  EXPECT_EQ(parts[1].chunk, 1u);
  EXPECT_EQ(parts[1].firstTriangle, 0u);
  EXPECT_EQ(parts[1].triangleCount, 200u);
  EXPECT_EQ(parts[2].chunk, 2u);
  EXPECT_EQ(parts[2].firstTriangle, 0u);
  EXPECT_EQ(parts[2].triangleCount, 150u);
  for (const ChunkPart& p : parts) {
    EXPECT_EQ(p.weight, 0.5f);
    EXPECT_EQ(p.level, 2u);
  }
  parts.clear();
  appendRunParts(chunks, 590, 100, 1.0f, 0, &parts);  // past the end: only what exists
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_EQ(parts[0].triangleCount, 10u);
}

// The placement part's footprint: the box as the camera sees it, clamped, whole when behind.
TEST(LayerPlacementParts, FootprintOfTheBox) {
  const LayerView v = orbit(0.0f);
  const VkRect2D r = projectedFootprint({v.proj * v.view}, kMin, kMax, kWidth, kHeight);
  EXPECT_GT(r.extent.width, 0u);
  EXPECT_GT(r.extent.height, 0u);
  EXPECT_LE(uint32_t(r.offset.x) + r.extent.width, kWidth);
  EXPECT_LE(uint32_t(r.offset.y) + r.extent.height, kHeight);
  // The box fills most of the height the orbit frames it in, not the whole target.
  EXPECT_LT(r.extent.width, kWidth);
  // A camera inside the box sees a corner behind it: the whole target.
  LayerView inside = v;
  inside.view = glm::lookAt(glm::vec3(0.0f, 1.0f, 0.0f), glm::vec3(0.0f, 1.0f, -1.0f), glm::vec3(0.0f, 1.0f, 0.0f));
  const VkRect2D all = projectedFootprint({inside.proj * inside.view}, kMin, kMax, kWidth, kHeight);
  EXPECT_EQ(all.extent.width, kWidth);
  EXPECT_EQ(all.extent.height, kHeight);
}

}  // namespace
}  // namespace canopy
