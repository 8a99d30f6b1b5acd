// The per-vertex wind baseline (seed 004, Habel IV-VI; render/per_vertex.h): the bend of every
// vertex read back from the GPU (shaders/per_vertex_tips.comp writes the motion table, then
// shaders/per_vertex_probe.comp runs the vertex shader's chain walk and bendApply) against the same
// header evaluated on the CPU (bendPosition: the tips synthesised in place); zero wind moves
// nothing, exactly; the trunk's root never moves; displacement grows with the hierarchy level;
// deterministic for a seed and a time; the fallback for models without a hierarchy; the mode
// through the public API (images, switching back, reverse-Z) and its refusals. Validation and
// synchronization validation are on (GpuTest).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/packing.hpp>

#include "engine/pipeline.h"
#include "engine/transfer.h"
#include "render/canopy.h"
#include "render/leaf_roots.h"
#include "render/material_split.h"
#include "render/per_vertex.h"
#include "tests/gpu_test.h"
#include "tests/test_host.h"
#include "tools/leaf_cloud.h"
#include "tools/test_shaders.h"
#include "tools/scene_generator.h"

using namespace canopy;
using canopy::test::GpuTest;

namespace {

VegetationModel treeWithHierarchy(uint64_t faces, SceneKind kind = SceneKind::TreeCrown) {
  SceneDesc d;
  d.kind = kind;
  d.faces = faces;
  d.hierarchy = true;
  d.threads = 1;
  VegetationModel m;
  Status s = generateScene(d, &m);
  EXPECT_TRUE(s.ok()) << s.message();
  return m;
}

// The rest vertices as the probe reads them: position, normal, model-wide leaf and its root (the
// leaf roots the layers compute). `leaves`: how many leaves the model has.
std::vector<gpu::BendProbeVertex> probeVertices(const VegetationModel& m, uint32_t* leaves = nullptr) {
  MaterialSplit split;
  EXPECT_TRUE(splitMaterials(m, {}, &split).ok());
  std::vector<uint8_t> foliage(m.triangleCount());
  for (size_t t = 0; t < foliage.size(); ++t) foliage[t] = split.role[m.triangleMaterial[t]] == MaterialRole::Foliage;
  LeafRoots roots;
  EXPECT_TRUE(computeLeafRoots(m, foliage, {}, &roots).ok());
  if (leaves) *leaves = roots.leafCount();
  std::vector<gpu::BendProbeVertex> v(m.positions.size());
  for (size_t i = 0; i < v.size(); ++i) {
    v[i].position = m.positions[i];
    v[i].normal = m.normals[i];
    v[i].leaf = roots.leafOfVertex[i] == kNoLeaf ? BEND_NO_LEAF : roots.leafOfVertex[i];
    v[i].leafRoot = v[i].leaf == BEND_NO_LEAF ? m.positions[i] : m.positions[roots.leafRoot[v[i].leaf]];
  }
  return v;
}

gpu::BendFrame windFrame(const VegetationModel& m, float strength, float t, uint32_t seed = 1,
                         PerVertexWind model = PerVertexWind::KaimalField) {
  PerVertexParams p;
  p.seed = seed;
  p.wind = model;
  WindParams w;
  w.strength = strength;
  w.frequency = 0.5f;
  w.modulation = 0.8f;
  w.gust = 0.3f;
  SimulationPlane plane;  // wind from the left blows towards +x
  gpu::BendFrame f = makeBendFrame(p, w, plane, m.boundsMin, m.boundsMax, t, t);
  f.flags = m.bend.empty() ? 0u : BEND_FLAG_HIERARCHY;
  return f;
}

glm::vec3 cpuBend(const gpu::BendFrame& f, const VegetationModel& m, const gpu::BendProbeVertex& v, size_t i) {
  const gpu::BendVertex bv = (f.flags & BEND_FLAG_HIERARCHY) ? m.bend[i] : gpu::BendVertex{BEND_NO_BRANCH, 0};
  glm::vec3 n = v.normal;
  return gpu::bendPosition(f, bendChainOf(m.branches, bv.branch), bv, v.leaf != BEND_NO_LEAF, v.leafRoot, v.leaf,
                           v.position, f.time, n);
}

class PerVertexTest : public GpuTest {
 protected:
  // Runs the motion kernel (the table of tip bends) and then the probe kernel (the vertex shader's
  // bend from the table) over the model's vertices for frame `frame`.
  std::vector<glm::vec3> gpuBend(const VegetationModel& m, const std::vector<gpu::BendProbeVertex>& in,
                                 const gpu::BendFrame& given) {
    uint32_t leaves = 0;
    for (const gpu::BendProbeVertex& v : in)
      if (v.leaf != BEND_NO_LEAF) leaves = std::max(leaves, v.leaf + 1);
    gpu::BendFrame f = given;
    f.branchCount = uint32_t(m.branches.size());
    f.tipCount = f.branchCount + leaves;
    f.copyCount = 1;  // one copy at the model's origin
    f.trunkCount = 1;  // the model's own fallback trunk (render/per_vertex.cpp's single species)
    const gpu::BendTrunk trunk{f.root, f.up};
    gpu::LayerInstance origin{};
    origin.model = glm::mat4(1.0f);
    origin.normalColumn0 = glm::vec4(1, 0, 0, 0);
    origin.normalColumn1 = glm::vec4(0, 1, 0, 0);
    origin.normalColumn2 = glm::vec4(0, 0, 1, 0);
    origin.tint = glm::vec4(1, 1, 1, 0);
    ComputePipeline pipe, tipsPipe;
    Status s = createComputePipeline(dev, {"per_vertex_probe.comp", sizeof(uint32_t), {}, false, &canopy_test::findEmbeddedShader}, &pipe);
    if (s.ok()) s = createComputePipeline(dev, {"per_vertex_tips.comp", 0}, &tipsPipe);
    EXPECT_TRUE(s.ok()) << s.message();
    const VkBufferUsageFlags usage =
        VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
    Buffer frame, branches, bend, input, output, tips, copies, trunks;
    const rg::State read = rg::stateOf(rg::Use::ComputeStorageRead), write = rg::stateOf(rg::Use::ComputeStorageWrite);
    std::vector<gpu::BendBranch> table = m.branches;
    if (table.empty()) table.push_back(gpu::BendBranch{});
    std::vector<gpu::BendVertex> perVertex = m.bend;
    if (perVertex.empty()) perVertex.push_back(gpu::BendVertex{});
    auto make = [&](Buffer& b, const void* data, size_t bytes, const char* name) {
      if (s.ok()) s = createBuffer(dev, bytes, usage, MemoryUsage::DeviceLocal, &b, name);
      if (s.ok() && data) s = uploadBuffer(dev, nullptr, b, data, bytes, read);
    };
    make(frame, &f, sizeof f, "probe frame");
    make(branches, table.data(), table.size() * sizeof(gpu::BendBranch), "probe branches");
    make(bend, perVertex.data(), perVertex.size() * sizeof(gpu::BendVertex), "probe bend");
    make(input, in.data(), in.size() * sizeof(gpu::BendProbeVertex), "probe input");
    make(output, nullptr, in.size() * sizeof(glm::vec4), "probe output");
    make(tips, nullptr, std::max<size_t>(f.tipCount, 1) * sizeof(glm::vec3), "probe motion table");
    make(copies, &origin, sizeof origin, "probe copies");
    make(trunks, &trunk, sizeof trunk, "probe trunks");
    // Each leaf's root, as render/per_vertex.cpp uploads it (the wind field's sample point).
    std::vector<glm::vec4> leafRoots(std::max<uint32_t>(leaves, 1), glm::vec4(0.0f));
    for (const gpu::BendProbeVertex& v : in)
      if (v.leaf != BEND_NO_LEAF) leafRoots[v.leaf] = glm::vec4(v.leafRoot, 1.0f);
    Buffer leafBuf;
    make(leafBuf, leafRoots.data(), leafRoots.size() * sizeof(glm::vec4), "probe leaf roots");
    std::vector<glm::vec4> out(in.size());
    if (s.ok()) {
      rg::RenderGraph g;
      const auto id = g.importBuffer("probe output", output.size, {}, write);
      const auto table = g.importBuffer("probe motion table", tips.size, {}, read);
      const uint32_t count = uint32_t(in.size());
      g.addPass("motion table", [&](rg::PassContext& c) {
         return dispatch(dev, c.cmd, tipsPipe, f.tipCount, 1, 1,
                         {bindBuffer(frame.buffer), bindBuffer(branches.buffer), bindBuffer(c.buffer(table)), bindBuffer(copies.buffer),
                          bindBuffer(leafBuf.buffer)},
                         nullptr, 0);
       }).write(table, rg::Use::ComputeStorageWrite);
      g.addPass("probe", [&](rg::PassContext& c) {
         return dispatch(dev, c.cmd, pipe, count, 1, 1,
                         {bindBuffer(frame.buffer), bindBuffer(branches.buffer), bindBuffer(bend.buffer),
                          bindBuffer(c.buffer(table)), bindBuffer(trunks.buffer), bindBuffer(input.buffer), bindBuffer(c.buffer(id))},
                         count);
       })
          .read(table, rg::Use::ComputeStorageRead)
          .write(id, rg::Use::ComputeStorageWrite);
      s = g.compile();
      if (s.ok()) s = g.realize(dev);
      if (s.ok()) s = g.bindBuffer(id, output.buffer);
      if (s.ok()) s = g.bindBuffer(table, tips.buffer);
      if (s.ok()) s = submitAndWait(dev, [&](VkCommandBuffer cmd) { return g.record(cmd); });
      if (s.ok()) s = readbackBuffer(dev, output, out.data(), out.size() * sizeof(glm::vec4), write);
    }
    EXPECT_TRUE(s.ok()) << s.message();
    for (Buffer* b : {&frame, &branches, &bend, &input, &output, &tips, &copies, &leafBuf, &trunks}) destroyBuffer(dev, *b);
    destroyComputePipeline(dev, pipe);
    destroyComputePipeline(dev, tipsPipe);
    std::vector<glm::vec3> p;
    for (const glm::vec4& v : out) p.push_back(glm::vec3(v));
    return p;
  }
};

float extent(const VegetationModel& m) { return glm::length(m.boundsMax - m.boundsMin); }

// A context description in the per-vertex mode, no wind yet.
CanopyDesc perVertexDesc(uint32_t w, uint32_t h, VkFormat color) {
  CanopyDesc desc;
  desc.width = w;
  desc.height = h;
  desc.colorFormat = color;
  desc.allowPerVertex = true;
  desc.params.animation = AnimationMode::PerVertex;
  desc.params.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  desc.params.simulation.wind.strength = 0.0f;
  return desc;
}

}  // namespace

TEST_F(PerVertexTest, TheGpuBendMatchesTheCpuAndZeroWindMovesNothingExactly) {
  const VegetationModel m = treeWithHierarchy(20000);
  ASSERT_FALSE(m.branches.empty());
  const std::vector<gpu::BendProbeVertex> in = probeVertices(m);
  // With wind: the GPU's sin/cos/pow/tanh against the CPU's, within 1e-5 of the model's size, for
  // the wind field (default) and the uniform wind of before 0.7.
  for (PerVertexWind model : {PerVertexWind::KaimalField, PerVertexWind::UniformNoise})
  for (float t : {0.7f, 2.3f}) {
    SCOPED_TRACE(model == PerVertexWind::KaimalField ? "Kaimal field" : "uniform noise");
    const gpu::BendFrame f = windFrame(m, 2.0f, t, 1, model);
    const std::vector<glm::vec3> gpu = gpuBend(m, in, f);
    ASSERT_EQ(gpu.size(), in.size());
    float worst = 0.0f, moved = 0.0f;
    for (size_t i = 0; i < in.size(); ++i) {
      worst = std::max(worst, glm::length(gpu[i] - cpuBend(f, m, in[i], i)));
      moved = std::max(moved, glm::length(gpu[i] - in[i].position));
    }
    EXPECT_LE(worst, 1e-5f * extent(m)) << "t = " << t;
    EXPECT_GT(moved, 1e-2f * extent(m)) << "t = " << t << ": the wind moved nothing";
  }
  // Zero wind, and wind with no source side: every vertex where it was, bit for bit.
  for (const auto& [strength, sides] : {std::pair<float, uint32_t>{0.0f, kWindFromLeft}, {3.0f, 0u}}) {
    PerVertexParams p;
    WindParams w;
    w.strength = strength;
    w.sides = sides;
    w.gust = 1.0f;
    gpu::BendFrame f = makeBendFrame(p, w, SimulationPlane{}, m.boundsMin, m.boundsMax, 1.7f, 1.7f);
    f.flags = BEND_FLAG_HIERARCHY;
    const std::vector<glm::vec3> gpu = gpuBend(m, in, f);
    size_t differ = 0;
    for (size_t i = 0; i < in.size(); ++i) differ += std::memcmp(&gpu[i], &in[i].position, sizeof(glm::vec3)) != 0;
    EXPECT_EQ(differ, 0u) << "strength " << strength << ", sides " << sides;
  }
}

TEST_F(PerVertexTest, TheTrunkRootNeverMovesAndTheBendIsDeterministic) {
  const VegetationModel m = treeWithHierarchy(20000);
  const std::vector<gpu::BendProbeVertex> in = probeVertices(m);
  // The trunk's base ring: on branch 0 (the trunk) at w = 0.
  std::vector<size_t> root;
  for (size_t i = 0; i < m.bend.size(); ++i)
    if (m.bend[i].branch == 0 && (m.bend[i].w & 255u) == 0 && in[i].leaf == BEND_NO_LEAF) root.push_back(i);
  ASSERT_GE(root.size(), 3u);
  std::vector<glm::vec3> first;
  for (float t : {0.3f, 1.1f, 4.9f}) {
    const std::vector<glm::vec3> gpu = gpuBend(m, in, windFrame(m, 6.0f, t));
    for (size_t i : root) EXPECT_EQ(std::memcmp(&gpu[i], &in[i].position, sizeof(glm::vec3)), 0) << "vertex " << i << ", t " << t;
    if (first.empty()) first = gpu;
  }
  // The same seed and time give the same bits; another seed other phases.
  const std::vector<glm::vec3> again = gpuBend(m, in, windFrame(m, 6.0f, 0.3f));
  EXPECT_EQ(std::memcmp(again.data(), first.data(), again.size() * sizeof(glm::vec3)), 0);
  const std::vector<glm::vec3> other = gpuBend(m, in, windFrame(m, 6.0f, 0.3f, 7));
  EXPECT_NE(std::memcmp(other.data(), first.data(), other.size() * sizeof(glm::vec3)), 0);
}

TEST_F(PerVertexTest, DisplacementGrowsWithTheHierarchyLevel) {
  const VegetationModel m = treeWithHierarchy(20000);
  const std::vector<gpu::BendProbeVertex> in = probeVertices(m);
  // Mean displacement of the wood by its innermost branch's level, and of the leaves, over a few
  // seconds of the same wind.
  double sum[BEND_LEVELS + 1] = {}, count[BEND_LEVELS + 1] = {};
  for (float t = 0.25f; t < 4.0f; t += 0.5f) {
    const std::vector<glm::vec3> gpu = gpuBend(m, in, windFrame(m, 2.0f, t));
    for (size_t i = 0; i < in.size(); ++i) {
      if (m.bend[i].branch >= BEND_LEAF_ONLY) continue;
      const uint32_t level = in[i].leaf != BEND_NO_LEAF ? BEND_LEVELS : m.branches[m.bend[i].branch].level;
      sum[level] += glm::length(gpu[i] - in[i].position);
      count[level] += 1;
    }
  }
  double mean[BEND_LEVELS + 1];
  for (uint32_t l = 0; l <= BEND_LEVELS; ++l) {
    ASSERT_GT(count[l], 0) << "level " << l;
    mean[l] = sum[l] / count[l];
  }
  for (uint32_t l = 1; l < BEND_LEVELS; ++l)
    EXPECT_GT(mean[l], mean[l - 1]) << "wood of level " << l << " against level " << l - 1;
  EXPECT_GT(mean[BEND_LEVELS], mean[1]) << "leaves against level-1 wood";
}

TEST_F(PerVertexTest, AModelWithoutHierarchyBendsFromItsTrunkAxis) {
  const VegetationModel m = makeLeafCloud(6000, 3, true);
  ASSERT_TRUE(m.bend.empty());
  const std::vector<gpu::BendProbeVertex> in = probeVertices(m);
  const gpu::BendFrame still = windFrame(m, 0.0f, 1.0f);
  const std::vector<glm::vec3> rest = gpuBend(m, in, still);
  for (size_t i = 0; i < in.size(); ++i) ASSERT_EQ(std::memcmp(&rest[i], &in[i].position, sizeof(glm::vec3)), 0) << i;
  const gpu::BendFrame f = windFrame(m, 2.0f, 1.3f);
  const std::vector<glm::vec3> gpu = gpuBend(m, in, f);
  const float h = m.boundsMax.y - m.boundsMin.y;
  double low = 0, high = 0, nLow = 0, nHigh = 0;
  float worst = 0.0f;
  for (size_t i = 0; i < in.size(); ++i) {
    worst = std::max(worst, glm::length(gpu[i] - cpuBend(f, m, in[i], i)));
    const float y = (in[i].position.y - m.boundsMin.y) / h;
    const double d = glm::length(gpu[i] - in[i].position);
    if (y < 0.2f) low += d, nLow += 1;
    if (y > 0.8f) high += d, nHigh += 1;
  }
  EXPECT_LE(worst, 1e-5f * extent(m));
  ASSERT_GT(nLow, 0);
  ASSERT_GT(nHigh, 0);
  EXPECT_GT(high / nHigh, 3.0 * low / nLow) << "the top of the crown sways more than its base";
}

namespace {

struct Frames {
  std::vector<std::vector<glm::vec4>> color;
};

// Fraction of pixels more than 2/255 apart.
double differing(const std::vector<glm::vec4>& a, const std::vector<glm::vec4>& b) {
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const glm::vec4 d = glm::abs(a[i] - b[i]);
    n += std::max(std::max(d.x, d.y), d.z) > 2.0f / 255.0f;
  }
  return double(n) / double(a.size());
}

}  // namespace

TEST_F(PerVertexTest, TheModeRendersThroughThePublicApiAndSwitchesBack) {
  const VegetationModel m = treeWithHierarchy(8000);
  uint64_t frame = 1;  // the device's frame numbers never decrease
  for (bool reverse : {false, true}) {
    SCOPED_TRACE(reverse ? "reverse-Z" : "standard depth");
    test::Host host;
    host.w = 96;
    host.h = 72;
    host.reverse = reverse;
    ASSERT_TRUE(host.create(dev, 2).ok());
    CanopyDesc desc = perVertexDesc(host.w, host.h, host.colorFormat);
    desc.depthConvention = reverse ? DepthConvention::Reverse : DepthConvention::Standard;
    CanopyContext* ctx = nullptr;
    Status s = createCanopy(dev, m, desc, &ctx);
    ASSERT_TRUE(s.ok()) << s.message();
    const LayerView view = orbitView(m.boundsMin, m.boundsMax, 20.0f, 10.0f, 40.0f, 96.0f / 72.0f, 1.0f);
    std::vector<glm::vec4> a, b, c;
    std::vector<float> z;
    auto run = [&](int frames, std::vector<glm::vec4>* out) {
      for (int i = 0; i < frames && s.ok(); ++i) s = host.frame(frame++, {ctx}, view, 0.4f);
      if (s.ok()) s = host.read(out, &z);
      EXPECT_TRUE(s.ok()) << s.message();
    };
    run(1, &a);
    run(3, &b);  // 1.2 s later, still no wind: the same image
    EXPECT_EQ(differing(a, b), 0.0) << "zero wind moved the plant";
    size_t drawn = 0;
    for (const glm::vec4& p : a) drawn += glm::length(glm::vec3(p) - glm::vec3(test::kSky)) > 0.05f;
    EXPECT_GT(drawn, a.size() / 20) << "the plant covers the frame";
    CanopyParams p = canopyParams(ctx);
    p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    p.simulation.wind.strength = 3.0f;
    ASSERT_TRUE(setCanopyParams(ctx, p).ok());
    run(2, &c);
    EXPECT_GT(differing(a, c), 0.01) << "wind bends the plant";
    EXPECT_EQ(canopyStats(ctx).layers.rebuilds, 0u) << "the baseline never slices layers";
    // Back to the 2D method on the same context: it re-slices at once and animates.
    p.animation = AnimationMode::Layers2D;
    ASSERT_TRUE(setCanopyParams(ctx, p).ok());
    run(2, &c);
    EXPECT_GE(canopyStats(ctx).layers.rebuilds, 1u);
    host.destroy();
    destroyCanopy(ctx);
    waitIdle();
  }
}

TEST_F(PerVertexTest, WhatTheModeNeedsIsRefusedWithTheReason) {
  const VegetationModel m = treeWithHierarchy(4000);
  CanopyDesc desc;
  desc.width = 64;
  desc.height = 48;
  CanopyContext* ctx = nullptr;
  Status s = createCanopy(dev, m, desc, &ctx);
  ASSERT_TRUE(s.ok()) << s.message();
  CanopyParams p = canopyParams(ctx);
  p.animation = AnimationMode::PerVertex;
  s = setCanopyParams(ctx, p);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("allowPerVertex"), std::string::npos) << s.message();
  destroyCanopy(ctx);
  desc.allowPerVertex = true;
  ASSERT_TRUE(createCanopy(dev, m, desc, &ctx).ok());
  p = canopyParams(ctx);
  p.perVertex.taper = 9.0f;
  s = setCanopyParams(ctx, p);
  EXPECT_NE(s.message().find("perVertex.taper"), std::string::npos) << s.message();
  p = canopyParams(ctx);
  p.perVertex.maxAngle = 0.0f;
  s = setCanopyParams(ctx, p);
  EXPECT_NE(s.message().find("perVertex.maxAngle"), std::string::npos) << s.message();
  destroyCanopy(ctx);
  // A hierarchy whose branch comes before its parent, or a vertex naming a missing branch.
  VegetationModel bad = m;
  bad.branches[1].parent = 5;
  s = createCanopy(dev, bad, desc, &ctx);
  EXPECT_EQ(s.code(), Result::InvalidModel);
  EXPECT_NE(s.message().find("branch 1"), std::string::npos) << s.message();
  bad = m;
  bad.bend[10].branch = uint32_t(m.branches.size()) + 3;
  s = createCanopy(dev, bad, desc, &ctx);
  EXPECT_NE(s.message().find("vertex 10"), std::string::npos) << s.message();
  // The baseline draws the whole mesh every frame: a budget that would stream it is refused.
  const VegetationModel big = treeWithHierarchy(200000);
  desc.deviceMemoryBudget = 8ull << 20;
  s = createCanopy(dev, big, desc, &ctx);
  EXPECT_FALSE(s.ok());
  if (s.ok()) destroyCanopy(ctx);
  EXPECT_NE(s.message().find("resident"), std::string::npos) << s.message();
  waitIdle();
}

// With a motion target (CanopyDesc.motionFormat) the baseline also bends at last frame's time and
// writes the difference in pixels: zero with no wind, non-zero and finite with wind.
TEST_F(PerVertexTest, MotionVectorsFollowTheBend) {
  const VegetationModel m = treeWithHierarchy(6000);
  const uint32_t w = 80, h = 60;
  Image color, depth, motion;
  ImageDesc c;
  c.width = w;
  c.height = h;
  c.format = VK_FORMAT_R16G16B16A16_SFLOAT;
  c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  ASSERT_TRUE(createImage(dev, c, &color, "host colour").ok());
  c.format = VK_FORMAT_R16G16_SFLOAT;
  ASSERT_TRUE(createImage(dev, c, &motion, "host motion").ok());
  c.format = VK_FORMAT_D32_SFLOAT;
  c.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT |
            VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
  ASSERT_TRUE(createImage(dev, c, &depth, "host depth").ok());
  CanopyDesc desc = perVertexDesc(w, h, VK_FORMAT_R16G16B16A16_SFLOAT);
  desc.motionFormat = VK_FORMAT_R16G16_SFLOAT;
  CanopyContext* ctx = nullptr;
  Status s = createCanopy(dev, m, desc, &ctx);
  ASSERT_TRUE(s.ok()) << s.message();
  LayerView view = orbitView(m.boundsMin, m.boundsMax, 20.0f, 10.0f, 40.0f, float(w) / float(h), 1.0f);
  std::vector<glm::vec2> motionPx(size_t(w) * h);
  std::vector<float> depthPx(size_t(w) * h);
  const rg::State colorRW = rg::stateOf(rg::Use::ColorAttachmentReadWrite), depthW = rg::stateOf(rg::Use::DepthAttachmentWrite),
                  src = rg::stateOf(rg::Use::TransferSrc);
  uint64_t number = 0;
  // One frame: the host clears its three images (its own graph), then Canopy; the largest motion.
  auto frame = [&](float* largest) {
    rg::RenderGraph g;
    const rg::State before = number == 0 ? rg::State{} : src;
    const auto ci = g.importImage("colour", descOf(color), before, colorRW);
    const auto mi = g.importImage("motion", descOf(motion), before, colorRW);
    const auto di = g.importImage("depth", descOf(depth), number == 0 ? rg::State{} : depthW, depthW);
    g.addPass("host clear", [&](rg::PassContext& x) {
       VkClearColorValue cv{};
       const VkImageSubresourceRange cr{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}, dr{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
       vkCmdClearColorImage(x.cmd, x.image(ci).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &cv, 1, &cr);
       vkCmdClearColorImage(x.cmd, x.image(mi).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &cv, 1, &cr);
       VkClearDepthStencilValue dv{1.0f, 0};
       vkCmdClearDepthStencilImage(x.cmd, x.image(di).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &dv, 1, &dr);
       return Status();
     })
        .write(ci, rg::Use::TransferDst)
        .write(mi, rg::Use::TransferDst)
        .write(di, rg::Use::TransferDst);
    s = g.bindImage(ci, color);
    if (s.ok()) s = g.bindImage(mi, motion);
    if (s.ok()) s = g.bindImage(di, depth);
    if (s.ok()) s = g.compile();
    if (s.ok()) s = g.realize(dev);
    CanopyFrameInputs in;
    in.frame = makeCanopyFrame(view, 0.1f, ++number);
    const VkImageUsageFlags colorUsage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    in.color = canopyImage(color.image, color.view, colorUsage, VK_FORMAT_R16G16B16A16_SFLOAT, colorRW, src);
    in.motion = canopyImage(motion.image, motion.view, colorUsage, VK_FORMAT_R16G16_SFLOAT, colorRW, src);
    in.depth = canopyImage(depth.image, depth.view, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                           VK_FORMAT_D32_SFLOAT, depthW, depthW);
    if (s.ok()) s = submitAndWait(dev, [&](VkCommandBuffer cmd) -> Status {
      CANOPY_TRY(g.record(cmd));
      return recordCanopy(ctx, cmd, in);
    });
    g.release(dev);
    std::vector<uint32_t> px(size_t(w) * h);
    if (s.ok()) s = readbackImage(dev, motion, 0, 4, px.data(), src);
    if (s.ok()) s = readbackImage(dev, depth, 0, 4, depthPx.data(), depthW);
    ASSERT_TRUE(s.ok()) << s.message();
    *largest = 0.0f;
    for (size_t i = 0; i < px.size(); ++i) {
      const glm::vec2 mv = glm::unpackHalf2x16(px[i]);
      ASSERT_TRUE(std::isfinite(mv.x) && std::isfinite(mv.y));
      motionPx[i] = mv;
      *largest = std::max(*largest, glm::length(mv));
    }
  };
  float still = -1.0f, windy = -1.0f;
  frame(&still);
  frame(&still);
  EXPECT_EQ(still, 0.0f) << "no wind, no motion";
  CanopyParams p = canopyParams(ctx);
  p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  p.simulation.wind.strength = 4.0f;
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  frame(&windy);
  frame(&windy);
  EXPECT_GT(windy, 0.05f) << "the bend moves pixels between frames";
  EXPECT_LT(windy, float(w)) << "and by less than the frame";
  // Issue 34: the camera's motion. No wind, the camera orbits: each covered pixel's motion
  // (10 degrees) is where its surface point is now minus where the previous camera showed it (the point from
  // this frame's depth through the inverse of this frame's camera). Vertex motion interpolated over
  // a triangle differs from the per-pixel value by the perspective of the triangle's span: bounds
  // 0.05 px (median) and 0.3 px (90th percentile), against a motion of over a pixel.
  p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  p.simulation.wind.strength = 0.0f;
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  float turning = -1.0f;
  frame(&still);
  frame(&still);
  EXPECT_EQ(still, 0.0f) << "no wind, a still camera: no motion";
  const glm::mat4 before = view.proj * view.view;
  view = orbitView(m.boundsMin, m.boundsMax, 30.0f, 10.0f, 40.0f, float(w) / float(h), 1.0f);
  frame(&turning);
  const glm::mat4 now = view.proj * view.view, back = glm::inverse(now);
  std::vector<float> err;
  float meanMotion = 0.0f;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      if (depthPx[i] >= 1.0f) continue;
      const glm::vec4 ndc((float(x) + 0.5f) / float(w) * 2.0f - 1.0f, (float(y) + 0.5f) / float(h) * 2.0f - 1.0f, depthPx[i], 1.0f);
      glm::vec4 world = back * ndc;
      world /= world.w;
      const glm::vec4 c0 = before * world;
      const glm::vec2 expect = (glm::vec2(ndc) - glm::vec2(c0) / c0.w) * 0.5f * glm::vec2(float(w), float(h));
      err.push_back(glm::length(motionPx[i] - expect));
      meanMotion += glm::length(expect);
    }
  ASSERT_GT(err.size(), 100u);
  meanMotion /= float(err.size());
  EXPECT_GT(meanMotion, 1.0f) << "the orbit moves the plant on screen";
  std::sort(err.begin(), err.end());
  EXPECT_LE(err[err.size() / 2], 0.05f) << "median motion error, px";
  EXPECT_LE(err[err.size() * 9 / 10], 0.3f) << "90th percentile motion error, px";
  destroyCanopy(ctx);
  waitIdle();
  destroyImage(dev, color);
  destroyImage(dev, depth);
  destroyImage(dev, motion);
}

// A host's own mesh carries its hierarchy through MeshDesc (vertexBranches, vertexW, branches): the
// generator's hierarchy passed that way arrives as the generator made it; inconsistent inputs are
// refused naming the field.
TEST(PerVertexHierarchy, AHostMeshCarriesItsHierarchyThroughMeshDesc) {
  const VegetationModel m = treeWithHierarchy(4000);
  std::vector<float> positions, uvs, w;
  for (const glm::vec3& p : m.positions) positions.insert(positions.end(), {p.x, p.y, p.z});
  for (const glm::vec2& t : m.uvs) uvs.insert(uvs.end(), {t.x, t.y});
  std::vector<uint32_t> vertexBranches;
  for (const gpu::BendVertex& b : m.bend) {
    vertexBranches.push_back(b.branch == BEND_LEAF_ONLY ? kNoBranch : b.branch);
    for (uint32_t k = 0; k < 4; ++k) w.push_back(float((b.w >> (8 * k)) & 255u) / 255.0f);
  }
  std::vector<MeshBranch> branches;
  for (const gpu::BendBranch& b : m.branches)
    branches.push_back(MeshBranch{toFloat3(b.origin), toFloat3(b.axis), b.parent, b.level});
  MeshDesc d;
  d.positions = positions.data();
  d.uvs = uvs.data();
  d.vertexCount = uint32_t(m.positions.size());
  d.indices = m.indices.data();
  d.indexCount = m.indices.size();
  d.vertexBranches = vertexBranches.data();
  d.vertexW = w.data();
  d.branches = branches.data();
  d.branchCount = uint32_t(branches.size());
  Model* model = nullptr;
  Status s = createModel(d, &model);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(model->data.bend.size(), m.bend.size());
  EXPECT_EQ(std::memcmp(model->data.bend.data(), m.bend.data(), m.bend.size() * sizeof(gpu::BendVertex)), 0);
  ASSERT_EQ(model->data.branches.size(), m.branches.size());
  EXPECT_EQ(std::memcmp(model->data.branches.data(), m.branches.data(), m.branches.size() * sizeof(gpu::BendBranch)), 0);
  destroyModel(model);
  w[4 * 7 + 2] = 1.5f;
  s = createModel(d, &model);
  EXPECT_EQ(s.code(), Result::InvalidModel);
  EXPECT_NE(s.message().find("vertexW[30]"), std::string::npos) << s.message();
  d.vertexW = nullptr;
  s = createModel(d, &model);
  EXPECT_NE(s.message().find("vertexBranches, vertexW and branches"), std::string::npos) << s.message();
}

// The wind field of the per-vertex baseline (shared/bend.h bendFieldResponse; docs/design.md
// "Per-vertex wind baseline"), evaluated on the CPU: the GPU runs the same header
// (PerVertexTest.TheGpuBendMatchesTheCpuAndZeroWindMovesNothingExactly).
namespace {

gpu::BendFrame fieldFrame(float meanSpeed, float gust = 0.3f) {
  PerVertexParams p;
  WindParams w;
  w.strength = meanSpeed;
  w.baseline = 1.0f;
  w.modulation = 0.0f;
  w.gust = gust;
  SimulationPlane plane;
  plane.tileSize = 2.0f;  // two world units a domain unit
  return makeBendFrame(p, w, plane, glm::vec3(-1, 0, -1), glm::vec3(1, 2, 1), 0.0f, 0.0f);
}

// Pearson correlation of two series.
double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  double ma = 0, mb = 0;
  for (size_t i = 0; i < a.size(); ++i) ma += a[i], mb += b[i];
  ma /= double(a.size()), mb /= double(b.size());
  double sab = 0, saa = 0, sbb = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

}  // namespace

TEST(PerVertexWindField, AGustReachesTheLeeSideLaterByTheDistanceOverTheMeanSpeed) {
  // Taylor's frozen turbulence: the field at a point d downwind is the field here d / U earlier.
  const gpu::BendFrame f = fieldFrame(1.5f);
  const glm::vec3 wind = glm::vec3(f.wind), p(0.1f, 0.8f, -0.2f);
  const float dWorld = 0.6f, dDomain = dWorld / f.fieldOrigin.w, lag = dDomain / f.wind.w;
  std::vector<double> here, lee, leeLagged;
  double worst = 0;
  for (float t = 0.0f; t < 60.0f; t += 0.05f) {
    const double a = gpu::bendFieldResponse(f, p, t, 1e6f, 1.0f, 0u);
    const double b = gpu::bendFieldResponse(f, p + dWorld * wind, t + lag, 1e6f, 1.0f, 0u);
    worst = std::max(worst, std::abs(a - b));
    here.push_back(a);
    lee.push_back(gpu::bendFieldResponse(f, p + dWorld * wind, t, 1e6f, 1.0f, 0u));
  }
  const double sameTime = correlation(here, lee);
  std::printf("gust %.2f world units downwind: arrives %.3f s later (|difference| at that lag %.2e); correlation at the same time %.3f\n",
              dWorld, lag, worst, sameTime);
  EXPECT_LT(worst, 1e-3);
  EXPECT_LT(sameTime, 0.95) << "the lee side sways with the windward side: the field does not travel";
}

TEST(PerVertexWindField, TheFieldDecorrelatesAcrossThePlant) {
  // Across the wind nearby points feel nearly the same wind, points a quarter of a domain unit and
  // more apart clearly less alike.
  const gpu::BendFrame f = fieldFrame(1.5f);
  const glm::vec3 across = glm::vec3(f.lateral), p(0.0f, 0.5f, 0.0f);
  std::vector<double> base;
  std::vector<std::vector<double>> at(3);
  const float offsets[3] = {0.02f, 0.5f, 2.0f};  // world units (the frame: two a domain unit)
  for (float t = 0.0f; t < 200.0f; t += 0.05f) {
    base.push_back(gpu::bendFieldResponse(f, p, t, 1e6f, 1.0f, 1u));
    for (int k = 0; k < 3; ++k) at[k].push_back(gpu::bendFieldResponse(f, p + offsets[k] * across, t, 1e6f, 1.0f, 1u));
  }
  double c[3];
  for (int k = 0; k < 3; ++k) c[k] = correlation(base, at[k]);
  std::printf("v component across the wind: correlation %.3f at %.2f, %.3f at %.2f, %.3f at %.2f world units\n", c[0],
              offsets[0], c[1], offsets[1], c[2], offsets[2]);
  // Eight components: the slowest (wavelengths of several domain units) stay coherent over any
  // plant, so the correlation levels off instead of reaching 0 (stated bounds: > 0.98 at 1 % of a
  // domain unit, < 0.8 from a quarter of one).
  EXPECT_GT(c[0], 0.98);
  EXPECT_LT(c[1], 0.8);
  EXPECT_LT(c[2], 0.8);
}

TEST(PerVertexWindField, ItsVarianceIsKaimalsOverTheBand) {
  // Unit-variance field before the oscillator: the components' power (the mean of the square over a
  // long time, no oscillator: f0 far above the band) against the integral of Kaimal's S(f) / sigma^2
  // over [BEND_FIELD_LOW_HZ, BEND_FIELD_HIGH_HZ] (trapezoids on a log grid). One cosine per octave
  // band samples the spectrum coarsely: within 25 %.
  for (float U : {0.5f, 2.0f, 6.0f}) {
    const gpu::BendFrame f = fieldFrame(U);
    double power = 0;
    int n = 0;
    for (float t = 0.0f; t < 2000.0f; t += 0.013f, ++n) {
      const double r = gpu::bendFieldResponse(f, glm::vec3(0.3f, 0.4f, 0.1f), t, 1e6f, 1.0f, 0u);
      power += r * r;
    }
    power /= n;
    double integral = 0;
    const int steps = 4000;
    for (int i = 0; i < steps; ++i) {
      const double a = BEND_FIELD_LOW_HZ * std::pow(double(BEND_FIELD_HIGH_HZ / BEND_FIELD_LOW_HZ), double(i) / steps);
      const double b = BEND_FIELD_LOW_HZ * std::pow(double(BEND_FIELD_HIGH_HZ / BEND_FIELD_LOW_HZ), double(i + 1) / steps);
      integral += 0.5 * (gpu::bendKaimal(float(a), f.integralScale, U) + gpu::bendKaimal(float(b), f.integralScale, U)) * (b - a);
    }
    std::printf("mean speed %.1f: the field's variance %.3f, Kaimal's over the band %.3f (sigma^2 = 1 over all frequencies)\n", U,
                power, integral);
    EXPECT_NEAR(power, integral, 0.25 * integral) << "U = " << U;
  }
}

TEST(PerVertexWindField, EachLevelRespondsAsADampedOscillator) {
  // H(f) = 1 / (1 - r^2 + 2 i zeta r): static gain 1, 1 / (2 zeta) and a quarter period late at
  // resonance, falling as 1 / r^2 above it.
  for (float zeta : {0.05f, 0.2f, 0.6f}) {
    const glm::vec2 h0 = gpu::bendOscillator(0.0f, 1.3f, zeta), h1 = gpu::bendOscillator(1.3f, 1.3f, zeta),
                    h10 = gpu::bendOscillator(13.0f, 1.3f, zeta);
    EXPECT_NEAR(h0.x, 1.0f, 1e-6f);
    EXPECT_NEAR(h0.y, 0.0f, 1e-6f);
    EXPECT_NEAR(h1.x, 1.0f / (2.0f * zeta), 1e-4f);
    EXPECT_NEAR(h1.y, 1.5707963f, 1e-5f);
    EXPECT_NEAR(h10.x, 1.0f / std::sqrt(99.0f * 99.0f + 400.0f * zeta * zeta), 1e-6f);
  }
  // A lightly damped level sways at its own frequency: its response's zero crossings come at about
  // 2 f0 a second, and its variance exceeds a heavily damped one's.
  const gpu::BendFrame f = fieldFrame(2.0f);
  const glm::vec3 p(0.0f, 1.0f, 0.0f);
  for (float f0 : {0.8f, 2.6f}) {
    double varLight = 0, varHeavy = 0, last = 0;
    int crossings = 0, n = 0;
    const float T = 400.0f;
    for (float t = 0.0f; t < T; t += 0.01f, ++n) {
      const double light = gpu::bendFieldResponse(f, p, t, f0, 0.05f, 0u);
      const double heavy = gpu::bendFieldResponse(f, p, t, f0, 1.0f, 0u);
      varLight += light * light;
      varHeavy += heavy * heavy;
      if (n > 0 && (light > 0) != (last > 0)) crossings++;
      last = light;
    }
    const double rate = crossings / (2.0 * T);
    std::printf("f0 %.1f Hz: zeta 0.05 crosses zero at %.2f Hz (half-rate), variance %.3f; zeta 1.0 variance %.3f\n", f0, rate,
                varLight / n, varHeavy / n);
    EXPECT_NEAR(rate, f0, 0.25 * f0);
    EXPECT_GT(varLight, 2.0 * varHeavy);
  }
}

TEST(PerVertexWindField, TheBranchesOfOnePlantSwayApartAndTheUniformWindDoesNot) {
  // Two level-1 branches (and two leaves) on opposite sides of the crown (1.2 world units apart
  // across the wind): with the field their tips' along-wind bends decorrelate; the uniform wind of before 0.7 gives
  // each branch its own noise phases but one wind speed, so only the noise differs.
  gpu::BendFrame field = fieldFrame(2.0f);
  gpu::BendFrame uniform = field;
  uniform.windModel = BEND_WIND_UNIFORM;
  const glm::vec3 a = glm::vec3(field.lateral) * -0.6f + glm::vec3(0, 1.2f, 0), b = glm::vec3(field.lateral) * 0.6f + glm::vec3(0, 1.2f, 0);
  std::vector<double> fa, fb, ua, ub, la, lb;
  for (float t = 0.0f; t < 120.0f; t += 0.02f) {
    la.push_back(glm::dot(gpu::bendLeafTip(field, t, 5u, a), glm::vec3(field.wind)));
    lb.push_back(glm::dot(gpu::bendLeafTip(field, t, 5u, b), glm::vec3(field.wind)));
    fa.push_back(glm::dot(gpu::bendBranchTip(field, t, 1u, 3u, a), glm::vec3(field.wind)));
    fb.push_back(glm::dot(gpu::bendBranchTip(field, t, 1u, 3u, b), glm::vec3(field.wind)));
    ua.push_back(glm::dot(gpu::bendBranchTip(uniform, t, 1u, 3u, a), glm::vec3(field.wind)));
    ub.push_back(glm::dot(gpu::bendBranchTip(uniform, t, 1u, 3u, b), glm::vec3(field.wind)));
  }
  // The same branch id at two places: the field tells them apart, the uniform wind cannot.
  const double cf = correlation(fa, fb), cu = correlation(ua, ub), cl = correlation(la, lb);
  std::printf("one branch id at two places 1.2 world units apart: correlation %.3f with the field, %.3f with the uniform wind; "
              "a leaf there %.3f\n", cf, cu, cl);
  EXPECT_GT(cu, 0.999);
  EXPECT_LT(cf, 0.9);
  EXPECT_LT(cl, 0.9);  // leaves feel the field at their roots too
}

// Issue 66, several species: a tree with its branch hierarchy and a leaf cloud without one (its own
// fallback trunk, BendTrunk), one copy of each side by side in one vegetation, in the wind. Each
// species bends as it does alone: the two-species frame is the two single-species frames laid
// together within the golden tolerance (uniform wind and still leaves, whose noise is seeded by the
// model-wide branch and leaf numbers, so both runs draw the same motion), and the wind moves both.
TEST_F(PerVertexTest, SeveralSpeciesEachBendThroughTheirOwnHierarchyOrTrunk) {
  const VegetationModel tree = treeWithHierarchy(6000);
  const VegetationModel cloud = makeLeafCloud(3000, 7, true);
  ASSERT_FALSE(tree.bend.empty());
  ASSERT_TRUE(cloud.bend.empty());
  // The cloud scaled to the tree's size, the two a little more than a size apart (model-space
  // centres moved to x = -+gap/2).
  const float size = extent(tree), gap = 0.7f * size;
  const float k = size / extent(cloud);
  const glm::vec3 tc = 0.5f * (tree.boundsMin + tree.boundsMax), cc = 0.5f * (cloud.boundsMin + cloud.boundsMax);
  const glm::mat4 left = glm::translate(glm::mat4(1.0f), glm::vec3(-0.5f * gap - tc.x, 0.0f, -tc.z));
  const glm::mat4 right = glm::translate(glm::mat4(1.0f), glm::vec3(0.5f * gap, 0.0f, 0.0f)) *
                          glm::scale(glm::mat4(1.0f), glm::vec3(k)) * glm::translate(glm::mat4(1.0f), glm::vec3(-cc.x, 0.0f, -cc.z));
  auto copyOf = [](const glm::mat4& t, uint32_t species) {
    CanopyInstance i;
    i.transform = toFloat4x4(t);
    i.species = species;
    return i;
  };
  const glm::vec3 lo = glm::min(glm::vec3(left * glm::vec4(tree.boundsMin, 1.0f)), glm::vec3(right * glm::vec4(cloud.boundsMin, 1.0f)));
  const glm::vec3 hi = glm::max(glm::vec3(left * glm::vec4(tree.boundsMax, 1.0f)), glm::vec3(right * glm::vec4(cloud.boundsMax, 1.0f)));
  const LayerView view = orbitView(lo, hi, 0.0f, 8.0f, 40.0f, 160.0f / 120.0f, 1.0f);
  uint64_t frame = 1;
  auto run = [&](const std::vector<SpeciesModel>& species, const std::vector<CanopyInstance>& copies, float wind,
                 std::vector<glm::vec4>* out) {
    test::Host host;
    host.w = 160;
    host.h = 120;
    CanopyContext* ctx = nullptr;
    Status s = test::createHostContext(dev, host, species, copies, wind, true, &ctx);
    ASSERT_TRUE(s.ok()) << s.message();
    CanopyParams p = canopyParams(ctx);
    p.perVertex.wind = PerVertexWind::UniformNoise;
    p.perVertex.leafFlexibility = 0.0f;
    ASSERT_TRUE(setCanopyParams(ctx, p).ok());
    std::vector<float> z;
    for (int i = 0; i < 8 && s.ok(); ++i) s = host.frame(frame++, {ctx}, view, 1.0f / 30.0f);
    if (s.ok()) s = host.read(out, &z);
    EXPECT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(canopyStats(ctx).layers.species, uint32_t(species.size()));
    destroyCanopy(ctx);
    host.destroy();
  };
  std::vector<glm::vec4> both, still, treeAlone, cloudAlone;
  run({{&tree}, {&cloud}}, {copyOf(left, 0), copyOf(right, 1)}, 3.0f, &both);
  run({{&tree}, {&cloud}}, {copyOf(left, 0), copyOf(right, 1)}, 0.0f, &still);
  run({{&tree}}, {copyOf(left, 0)}, 3.0f, &treeAlone);
  run({{&cloud}}, {copyOf(right, 0)}, 3.0f, &cloudAlone);
  ASSERT_EQ(both.size(), size_t(160 * 120));
  // The single-species frames laid together: the tree's where it drew, else the cloud's.
  auto sky = [](const glm::vec4& c) { return glm::length(glm::vec3(c) - glm::vec3(test::kSky)) < 1e-3f; };
  std::vector<glm::vec4> together(both.size());
  size_t treePixels = 0, cloudPixels = 0;
  for (size_t i = 0; i < both.size(); ++i) {
    together[i] = sky(treeAlone[i]) ? cloudAlone[i] : treeAlone[i];
    treePixels += !sky(treeAlone[i]);
    cloudPixels += !sky(cloudAlone[i]);
  }
  ASSERT_GT(treePixels, both.size() / 50) << "the tree is in view";
  ASSERT_GT(cloudPixels, both.size() / 50) << "the cloud is in view";
  // Moved by the wind, each half on its own.
  double movedLeft = 0, movedRight = 0;
  for (size_t y = 0; y < 120; ++y)
    for (size_t x = 0; x < 160; ++x) {
      const size_t i = y * 160 + x;
      const bool moved = test::maxDiff(both[i], still[i]) > 3.0f / 255.0f;
      (x < 80 ? movedLeft : movedRight) += moved;
    }
  const double off = test::differing(both, together, 3.0f / 255.0f);
  std::printf("  two species (tree with its hierarchy, leaf cloud on its own trunk): %.3f %% of pixels off the single-species "
              "frames laid together; the wind moved %.1f %% of the left half, %.1f %% of the right\n",
              100.0 * off, 100.0 * movedLeft / (80 * 120), 100.0 * movedRight / (80 * 120));
  EXPECT_LE(off, 0.005) << "golden tolerance: <= 0.5 % of pixels off by > 3/255";
  EXPECT_GT(movedLeft / (80 * 120), 0.01) << "the tree sways";
  EXPECT_GT(movedRight / (80 * 120), 0.01) << "the cloud sways";
}
