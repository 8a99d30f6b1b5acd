// Instances (issue 35; docs/design.md "Instances"): a plant placed by a transform renders as the
// same plant with the transform baked into its vertices, and 100 placed copies render as the same
// copies merged into one mesh, within the golden tolerance, with the mesh stored once. Through the
// public API (createCanopy, setCanopyInstances), validation and synchronization validation on.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "tests/gpu_test.h"
#include "tests/test_host.h"
#include "tools/leaf_cloud.h"

using namespace canopy;
using canopy::test::GpuTest;
using canopy::test::Host;
using canopy::test::differing;
using canopy::test::createHostContext;
using canopy::test::renderHostFrames;

namespace {

// `m` with `t` applied to its vertices (normals by the inverse transpose) and its materials' base
// colour multiplied by `tint`.
VegetationModel baked(const VegetationModel& m, const glm::mat4& t, const glm::vec3& tint = glm::vec3(1.0f)) {
  VegetationModel b = m;
  const glm::mat3 n = glm::transpose(glm::inverse(glm::mat3(t)));
  b.boundsMin = glm::vec3(INFINITY);
  b.boundsMax = glm::vec3(-INFINITY);
  for (size_t i = 0; i < b.positions.size(); ++i) {
    b.positions[i] = glm::vec3(t * glm::vec4(m.positions[i], 1.0f));
    b.normals[i] = glm::normalize(n * m.normals[i]);
    b.boundsMin = glm::min(b.boundsMin, b.positions[i]);
    b.boundsMax = glm::max(b.boundsMax, b.positions[i]);
  }
  for (ModelMaterial& mat : b.materials) mat.baseColorFactor *= glm::vec4(tint, 1.0f);
  b.bend.clear();
  b.branches.clear();
  b.boxParent.clear();
  b.triangleBox.clear();
  return b;
}

// The copies of `m` under `transforms` as one mesh (each copy's leaves its own).
VegetationModel merged(const VegetationModel& m, const std::vector<glm::mat4>& transforms) {
  VegetationModel out = baked(m, transforms[0]);
  out.trianglePlant.assign(out.triangleCount(), 0u);  // each copy a plant, as instances are (eq. 7 per plant)
  for (size_t k = 1; k < transforms.size(); ++k) {
    const VegetationModel c = baked(m, transforms[k]);
    const uint32_t base = uint32_t(out.positions.size());
    out.positions.insert(out.positions.end(), c.positions.begin(), c.positions.end());
    out.normals.insert(out.normals.end(), c.normals.begin(), c.normals.end());
    out.uvs.insert(out.uvs.end(), c.uvs.begin(), c.uvs.end());
    for (uint32_t i : c.indices) out.indices.push_back(base + i);
    out.triangleMaterial.insert(out.triangleMaterial.end(), c.triangleMaterial.begin(), c.triangleMaterial.end());
    out.trianglePlant.resize(out.triangleMaterial.size(), uint32_t(k));
    out.boundsMin = glm::min(out.boundsMin, c.boundsMin);
    out.boundsMax = glm::max(out.boundsMax, c.boundsMax);
  }
  return out;
}

CanopyInstance instanceOf(const glm::mat4& t, const glm::vec3& tint = glm::vec3(1.0f)) {
  CanopyInstance i;
  i.transform = toFloat4x4(t);
  i.tint = toFloat3(tint);
  return i;
}

class InstancesTest : public GpuTest {
 protected:
  uint64_t frameNumber = 0;  // never decreases on the device
  // A 160x120 host and a context on `model` with `instances` (wind 1) for it; `perVertex`: the
  // per-vertex baseline draws it.
  void make(Host& host, const VegetationModel& model, const std::vector<CanopyInstance>& instances, CanopyContext** ctx,
            bool perVertex = false, float wind = 1.0f) {
    host.w = 160;
    host.h = 120;
    const Status made = createHostContext(dev, host, {SpeciesModel{&model}}, instances, wind, perVertex, ctx);
    ASSERT_TRUE(made.ok()) << made.message();
  }
  // `frames` frames of a context on `model` (with `instances`) seen by `view`, read back.
  void render(const VegetationModel& model, const std::vector<CanopyInstance>& instances, const LayerView& view, int frames,
              std::vector<glm::vec4>* color, std::vector<float>* depth, CanopyStats* stats = nullptr, bool perVertex = false,
              float wind = 1.0f) {
    const Status s = renderHostFrames(dev, frameNumber, {SpeciesModel{&model}}, instances, view, frames, color, depth, stats, perVertex, wind);
    ASSERT_TRUE(s.ok()) << s.message();
  }
};

// A rotation about a slanted axis, a non-uniform scale with a mirror (z negated) and a translation,
// and a tint: the same frames as the plant with all of it baked into its vertices and materials.
TEST_F(InstancesTest, ATransformedPlantRendersAsThePlantWithTheTransformBakedIn) {
  const VegetationModel plant = makeLeafCloud(3000, 5, true);
  const glm::mat4 t = glm::translate(glm::mat4(1.0f), glm::vec3(3.0f, 0.5f, -2.0f)) *
                      glm::rotate(glm::mat4(1.0f), glm::radians(35.0f), glm::normalize(glm::vec3(0.3f, 1.0f, 0.2f))) *
                      glm::scale(glm::mat4(1.0f), glm::vec3(1.3f, 0.8f, -1.1f));
  const glm::vec3 tint(0.6f, 1.0f, 0.8f);
  const VegetationModel bakedPlant = baked(plant, t, tint);
  const LayerView view = orbitView(bakedPlant.boundsMin, bakedPlant.boundsMax, 20.0f, 10.0f, 40.0f, 160.0f / 120.0f, 1.05f);
  std::vector<glm::vec4> placed, reference;
  std::vector<float> zPlaced, zReference;
  render(plant, {instanceOf(t, tint)}, view, 6, &placed, &zPlaced);
  render(bakedPlant, {}, view, 6, &reference, &zReference);
  size_t vegetation = 0, depthOff = 0;
  for (size_t i = 0; i < zReference.size(); ++i) {
    vegetation += zReference[i] < 1.0f;
    depthOff += std::abs(zPlaced[i] - zReference[i]) > 1e-4f;
  }
  EXPECT_GT(vegetation, zReference.size() / 20) << "the plant is in view";
  EXPECT_LE(differing(placed, reference, 3.0f / 255.0f), 0.005) << "golden tolerance: <= 0.5 % of pixels off by > 3/255";
  EXPECT_LE(double(depthOff) / zReference.size(), 0.005) << "depth";
}

// 100 copies on a 10 x 10 grid, each turned and scaled its own way: the same frames as the copies
// merged into one mesh, with one copy's mesh on the device (plus the 128-byte transforms). Each is
// turned by a quarter turn times 0..3: eq. 7's plant rects are projected from a plant's box, a
// copy's the model's box turned with it, a merged copy's its own axis-aligned box; at other angles
// the two boxes differ (up to sqrt 2 wider), and so do the rects and the sway about them.
TEST_F(InstancesTest, HundredInstancesRenderAsTheCopiesMergedIntoOneMesh) {
  const VegetationModel plant = makeLeafCloud(300, 9, true);
  const glm::vec3 size = plant.boundsMax - plant.boundsMin;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<glm::mat4> transforms;
  std::vector<CanopyInstance> instances;
  for (int z = 0; z < 10; ++z)
    for (int x = 0; x < 10; ++x) {
      const glm::mat4 t = glm::translate(glm::mat4(1.0f), glm::vec3(x * 1.1f * size.x, 0.0f, z * 1.1f * size.z)) *
                          glm::rotate(glm::mat4(1.0f), std::floor(u(rng) * 4.0f) * 1.5707963f, glm::vec3(0, 1, 0)) *
                          glm::scale(glm::mat4(1.0f), glm::vec3(0.8f + 0.4f * u(rng)));
      transforms.push_back(t);
      instances.push_back(instanceOf(t));
    }
  const VegetationModel field = merged(plant, transforms);
  const LayerView view = orbitView(field.boundsMin, field.boundsMax, 30.0f, 25.0f, 40.0f, 160.0f / 120.0f, 0.7f);
  std::vector<glm::vec4> placed, reference;
  std::vector<float> zPlaced, zReference;
  CanopyStats one, many, mergedStats;
  render(plant, instances, view, 6, &placed, &zPlaced, &many);
  render(field, {}, view, 6, &reference, &zReference, &mergedStats);
  std::vector<glm::vec4> single;
  std::vector<float> zSingle;
  render(plant, {}, view, 1, &single, &zSingle, &one);
  size_t vegetation = 0;
  for (float z : zReference) vegetation += z < 1.0f;
  EXPECT_GT(vegetation, zReference.size() / 5) << "the field is in view";
  const double off = differing(placed, reference, 3.0f / 255.0f);
  EXPECT_LE(off, 0.005) << "golden tolerance";
  // Mesh device memory <= 1.1 x one copy's plus the transforms: the same compact mesh, and a table.
  EXPECT_EQ(many.layers.meshBytes, one.layers.meshBytes) << "the mesh is stored once";
  EXPECT_GT(mergedStats.layers.meshBytes, 50 * one.layers.meshBytes) << "what merging costs";
  std::printf("100 instances: %.3f %% of pixels off by > 3/255 (%zu covered); mesh %llu bytes (one copy's) + transforms %zu bytes; "
              "the merged mesh %llu bytes\n",
              100.0 * off, vegetation, (unsigned long long)many.layers.meshBytes, instances.size() * sizeof(gpu::LayerInstance),
              (unsigned long long)mergedStats.layers.meshBytes);
}

// Placed copies changed at run time re-slice at once and render as a context created with them;
// copies outside the view are not drawn.
TEST_F(InstancesTest, InstancesSetLaterReSliceAndCopiesOutOfViewAreCulled) {
  const VegetationModel plant = makeLeafCloud(2000, 3, true);
  const glm::vec3 size = plant.boundsMax - plant.boundsMin;
  const glm::mat4 t = glm::translate(glm::mat4(1.0f), glm::vec3(0.5f * size.x, 0.0f, 0.0f)) *
                      glm::rotate(glm::mat4(1.0f), glm::radians(70.0f), glm::vec3(0, 1, 0));
  // A second copy far behind the camera.
  const LayerView view = orbitView(plant.boundsMin + glm::vec3(0.5f * size.x, 0, 0), plant.boundsMax + glm::vec3(0.5f * size.x, 0, 0),
                                   20.0f, 10.0f, 40.0f, 160.0f / 120.0f, 1.05f);
  const glm::vec3 eye = viewPosition(view.view), forward = viewForward(view.view);
  const glm::mat4 behind = glm::translate(glm::mat4(1.0f), eye - 4.0f * glm::length(size) * forward);
  std::vector<glm::vec4> created, changed;
  std::vector<float> zCreated, zChanged;
  render(plant, {instanceOf(t), instanceOf(behind)}, view, 6, &created, &zCreated);
  Host host;
  CanopyContext* ctx = nullptr;
  make(host, plant, {}, &ctx);
  ASSERT_NE(ctx, nullptr);
  ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok());
  const uint64_t rebuilds = canopyStats(ctx).layers.rebuilds;
  const Status s = setCanopyInstances(ctx, {instanceOf(t), instanceOf(behind)});
  ASSERT_TRUE(s.ok()) << s.message();
  for (int i = 1; i < 6; ++i) ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok());
  const CanopyStats st = canopyStats(ctx);
  EXPECT_EQ(st.layers.rebuilds, rebuilds + 1);
  EXPECT_EQ(st.layers.lastRebuildReason, "instances changed");
  EXPECT_EQ(st.layers.instances, 2u);
  EXPECT_EQ(st.layers.lastVisibleInstances, 1u) << "the copy behind the camera is culled";
  ASSERT_TRUE(host.read(&changed, &zChanged).ok());
  EXPECT_LE(differing(changed, created, 3.0f / 255.0f), 0.005) << "as a context created with them";
  // Refusals name the instance.
  CanopyInstance bad = instanceOf(glm::scale(glm::mat4(1.0f), glm::vec3(1.0f, 0.0f, 1.0f)));
  const Status r = setCanopyInstances(ctx, {instanceOf(t), bad});
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.message().find("CanopyInstance #1.transform"), std::string::npos) << r.message();
  EXPECT_FALSE(setCanopyInstances(ctx, {}).ok()) << "at least one";
  destroyCanopy(ctx);
  host.destroy();
}

// The per-vertex baseline draws the copies too: a transformed copy (wind off) as the transform
// baked in, and a copy's wind phase as the same sway that many seconds later.
TEST_F(InstancesTest, ThePerVertexBaselineDrawsTransformedCopiesWithTheirWindPhase) {
  const VegetationModel plant = makeLeafCloud(3000, 5, true);
  const glm::mat4 t = glm::translate(glm::mat4(1.0f), glm::vec3(-1.0f, 0.2f, 0.5f)) *
                      glm::rotate(glm::mat4(1.0f), glm::radians(-50.0f), glm::vec3(0, 1, 0)) *
                      glm::scale(glm::mat4(1.0f), glm::vec3(0.9f, 1.2f, -1.0f));
  const VegetationModel bakedPlant = baked(plant, t);
  const LayerView view = orbitView(bakedPlant.boundsMin, bakedPlant.boundsMax, 20.0f, 10.0f, 40.0f, 160.0f / 120.0f, 1.05f);
  std::vector<glm::vec4> placed, reference;
  std::vector<float> zPlaced, zReference;
  render(plant, {instanceOf(t)}, view, 3, &placed, &zPlaced, nullptr, true, 0.0f);
  render(bakedPlant, {}, view, 3, &reference, &zReference, nullptr, true, 0.0f);
  size_t vegetation = 0;
  for (float z : zReference) vegetation += z < 1.0f;
  EXPECT_GT(vegetation, zReference.size() / 20);
  EXPECT_LE(differing(placed, reference, 3.0f / 255.0f), 0.005) << "a transformed copy, wind off";
  // A phase of 0.5 s after 10 frames of 1/30 s against no phase after 25 frames: the same sway.
  CanopyInstance phased = instanceOf(glm::mat4(1.0f));
  phased.windPhase = 0.5f;
  const LayerView near = orbitView(plant.boundsMin, plant.boundsMax, 20.0f, 10.0f, 40.0f, 160.0f / 120.0f, 1.05f);
  std::vector<glm::vec4> early, late, still;
  std::vector<float> zEarly, zLate, zStill;
  render(plant, {phased}, near, 10, &early, &zEarly, nullptr, true, 3.0f);
  render(plant, {instanceOf(glm::mat4(1.0f))}, near, 25, &late, &zLate, nullptr, true, 3.0f);
  render(plant, {instanceOf(glm::mat4(1.0f))}, near, 10, &still, &zStill, nullptr, true, 3.0f);
  const double samePhase = differing(early, late, 3.0f / 255.0f), otherPhase = differing(early, still, 3.0f / 255.0f);
  std::printf("wind phase 0.5 s at t = 1/3 s against no phase at t = 5/6 s: %.3f %% of pixels off; against t = 1/3 s: %.3f %%\n",
              100.0 * samePhase, 100.0 * otherPhase);
  EXPECT_LE(samePhase, 0.005) << "the phase is a time shift of the sway";
  EXPECT_GT(otherPhase, 0.02) << "and it changes the sway";
}

}  // namespace
