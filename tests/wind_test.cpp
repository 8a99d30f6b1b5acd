// One wind for the scene (issue 55; docs/design.md "The wind a host reads", "Pushers"): a host's
// compute shader reading canopyWindAt (<canopy/canopy_wind.glsl>, tests/shaders/wind_probe.comp)
// and sampleCanopyWind on the CPU return the simulation's tiled wind at the plane cell of a world
// point, for a tilted plane and after the plane moved; pushers at the cap, above it, non-finite,
// outside the domain and behind the camera are handled as stated; a pusher walking through grass
// parts it where it walks, the bend follows it and springs back, and grass beyond 3 radii keeps its
// sway. Validation and synchronization validation on: any message fails the test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "compute/sim_reference.h"
#include "engine/pipeline.h"
#include "engine/transfer.h"
#include "render/canopy.h"
#include "render/pushers.h"
#include "tests/gpu_test.h"
#include "tests/test_host.h"
#include "tools/scene_generator.h"
#include "tools/test_shaders.h"

using namespace canopy;
using canopy::test::GpuTest;
using canopy::test::Host;

namespace {

class WindTest : public GpuTest {
 protected:
  uint64_t frameNumber = 0;
};

VegetationModel scene(SceneKind kind, uint64_t faces) {
  SceneDesc sd;
  sd.kind = kind;
  sd.faces = faces;
  sd.seed = 3;
  sd.textureSize = 64;
  VegetationModel m;
  EXPECT_TRUE(generateScene(sd, &m).ok());
  return m;
}

// A plane turned about two axes (its normal is neither the view's nor a world axis).
SimulationPlane tiltedPlane(const VegetationModel& m, float yawDegrees, float tiltDegrees, glm::vec3 shift) {
  const float a = glm::radians(yawDegrees), b = glm::radians(tiltDegrees);
  const glm::vec3 right = glm::normalize(glm::vec3(std::cos(a), 0.0f, std::sin(a)));
  const glm::vec3 normal0 = glm::vec3(-std::sin(a), 0.0f, std::cos(a));
  const glm::vec3 up = glm::normalize(std::cos(b) * glm::vec3(0, 1, 0) + std::sin(b) * normal0);
  const float tile = glm::length(m.boundsMax - m.boundsMin);
  const glm::vec3 c = 0.5f * (m.boundsMin + m.boundsMax) + shift;
  SimulationPlane p;
  p.origin = toFloat3(c - 0.5f * tile * (right + up));
  p.right = toFloat3(right);
  p.up = toFloat3(glm::normalize(up - glm::dot(up, right) * right));
  p.tileSize = tile;
  return p;
}

// The host's probe: canopyWindAt at each point, recorded after Canopy's frame.
struct Probe {
  Device* dev = nullptr;
  ComputePipeline pipe;
  VkSampler sampler = VK_NULL_HANDLE;
  Buffer info, points, out;
  uint32_t count = 0;
  Status create(Device& d, const std::vector<glm::vec4>& pts) {
    dev = &d;
    count = uint32_t(pts.size());
    CANOPY_TRY(createComputePipeline(d, {"wind_probe.comp", sizeof(uint32_t), {}, false, &canopy_test::findEmbeddedShader}, &pipe));
    VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
    CANOPY_VK(vkCreateSampler(d.device, &si, nullptr, &sampler));
    const VkBufferUsageFlags use = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT;
    CANOPY_TRY(createBuffer(d, sizeof(CanopyWindInfo), use, MemoryUsage::DeviceLocal, &info, "probe wind info"));
    CANOPY_TRY(createBuffer(d, pts.size() * sizeof(glm::vec4), use, MemoryUsage::DeviceLocal, &points, "probe points"));
    CANOPY_TRY(createBuffer(d, pts.size() * sizeof(glm::vec4), use, MemoryUsage::DeviceLocal, &out, "probe out"));
    return uploadBuffer(d, nullptr, points, pts.data(), points.size, rg::stateOf(rg::Use::ComputeStorageRead));
  }
  // Records the probe for `ctx`'s wind (its CanopyWind: image, state, mapping) into `cmd`.
  Status record(CanopyContext* ctx, VkCommandBuffer cmd) {
    CanopyWind w;
    CANOPY_TRY(canopyWind(ctx, &w));
    rg::RenderGraph g;
    ImageDesc d;
    d.format = w.format;
    d.width = d.height = w.size;
    d.usage = VK_IMAGE_USAGE_SAMPLED_BIT;
    const rg::State rest{w.state.stage, w.state.access, w.state.layout};
    const auto image = g.importImage("canopy wind", d, rest, rest);
    const auto infoId = g.importBuffer("wind info", info.size, rg::stateOf(rg::Use::ComputeStorageRead), rg::stateOf(rg::Use::ComputeStorageRead));
    const auto outId = g.importBuffer("probe out", out.size, rg::stateOf(rg::Use::ComputeStorageWrite), rg::stateOf(rg::Use::ComputeStorageWrite));
    const CanopyWindInfo mapping = w.info;
    g.addPass("wind info", [infoId, mapping](rg::PassContext& c) {
       vkCmdUpdateBuffer(c.cmd, c.buffer(infoId), 0, sizeof mapping, &mapping);
       return Status();
     }).write(infoId, rg::Use::TransferDst);
    const VkImageView view = w.view;
    g.addPass("wind probe", [this, view, infoId, outId](rg::PassContext& c) {
       return dispatch(*dev, c.cmd, pipe, count, 1, 1,
                       {bindImage(view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, sampler), bindBuffer(c.buffer(infoId)),
                        bindBuffer(points.buffer), bindBuffer(c.buffer(outId))},
                       count);
     })
        .read(image, rg::Use::ComputeSampled)
        .read(infoId, rg::Use::ComputeStorageRead)
        .write(outId, rg::Use::ComputeStorageWrite);
    Image wrapped;
    wrapped.image = w.image;
    wrapped.view = w.view;
    wrapped.format = w.format;
    wrapped.extent = {w.size, w.size, 1};
    CANOPY_TRY(g.bindImage(image, wrapped));
    CANOPY_TRY(g.bindBuffer(infoId, info.buffer));
    CANOPY_TRY(g.bindBuffer(outId, out.buffer));
    CANOPY_TRY(g.compile());
    CANOPY_TRY(g.realize(*dev));
    return g.record(cmd);
  }
  Status read(std::vector<glm::vec4>* v) {
    v->resize(count);
    return readbackBuffer(*dev, out, v->data(), out.size, rg::stateOf(rg::Use::ComputeStorageWrite));
  }
  void destroy() {
    if (!dev) return;
    destroyComputePipeline(*dev, pipe);
    if (sampler) vkDestroySampler(dev->device, sampler, nullptr);
    for (Buffer* b : {&info, &points, &out}) destroyBuffer(*dev, *b);
  }
};

// The tiled V_wind as the CPU reference's tile pass (compute/sim_reference.h) computes it from the
// simulation's own V_wind, n*n vec2.
std::vector<float> tileOfWind(const SimulationFields& f) {
  const uint32_t n = f.n;
  ref::SimState s = ref::makeState(n, 1);
  std::copy(f.vs.begin(), f.vs.end(), s.wave.begin());
  std::copy(f.vsPrev.begin(), f.vsPrev.end(), s.wave.begin() + 2 * size_t(n) * n);
  std::copy(f.wind.begin(), f.wind.end(), s.wave.begin() + 4 * size_t(n) * n);
  gpu::SimFrame frame{};
  frame.n = n;
  frame.ringSize = 1;
  frame.dt = 1.0f / 30.0f;
  ref::tile(frame, s);
  return std::vector<float>(s.tiled.begin() + 2 * gpu::tiledWindOffset(n), s.tiled.begin() + 4 * size_t(gpu::tiledWindOffset(n)));
}

// World points: the centres of a few plane cells (several tiles over, off the plane along its
// normal), and points between cells.
std::vector<glm::vec4> windPoints(const SimulationPlane& p, uint32_t n) {
  const glm::vec3 o = toGlm(p.origin), r = toGlm(p.right), u = toGlm(p.up), nrm = glm::cross(r, u);
  std::vector<glm::vec4> pts;
  for (uint32_t k = 0; k < 48; ++k) {
    const float ci = float((k * 37) % n) + 0.5f, cj = float((k * 11 + 5) % n) + 0.5f;
    const float tilesOver = float(int(k % 3) - 1), off = float(int(k % 5) - 2) * 0.7f;
    const glm::vec3 w = o + p.tileSize * ((ci / n + tilesOver) * r + (cj / n) * u + off * nrm);
    pts.push_back(glm::vec4(w, 1.0f));
  }
  for (uint32_t k = 0; k < 80; ++k) {  // anywhere (bilinear between cells, across tile edges)
    const float x = std::fmod(0.6180339f * k, 1.0f) * 2.0f - 0.5f, y = std::fmod(0.7548776f * k, 1.0f) * 2.0f - 0.5f;
    pts.push_back(glm::vec4(o + p.tileSize * (x * r + y * u + 0.3f * float(k % 4) * nrm), 1.0f));
  }
  return pts;
}

TEST_F(WindTest, HostShaderAndCpuSamplerReadTheSimulationsWind) {
  VegetationModel m = scene(SceneKind::Shrub, 6000);
  Host host;
  host.w = 96;
  host.h = 64;
  ASSERT_TRUE(host.create(dev, 2).ok());
  CanopyDesc d;
  d.width = host.w;
  d.height = host.h;
  d.colorFormat = host.colorFormat;
  d.simulation.gridSize = 32;
  d.params.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  d.params.simulation.wind.sides = kWindFromLeft | kWindFromBottom;
  d.params.customPlane = true;
  d.params.plane = tiltedPlane(m, 25.0f, 20.0f, glm::vec3(0.0f));
  CanopyContext* ctx = nullptr;
  Status s = createCanopy(dev, m, d, &ctx);
  ASSERT_TRUE(s.ok()) << s.message();
  const LayerView view = orbitView(m.boundsMin, m.boundsMax, 10.0f, 10.0f, 40.0f, 96.0f / 64.0f, 1.0f);
  const uint32_t n = canopySimulation(ctx).n;
  // Before any frame: nothing has completed.
  std::vector<Float3> early(3);
  uint64_t fieldFrame = 99;
  const Float3 somewhere[3] = {{0, 0, 0}, {1, 2, 3}, {-4, 0, 1}};
  ASSERT_TRUE(sampleCanopyWind(ctx, somewhere, 3, early.data(), &fieldFrame).ok());
  EXPECT_EQ(fieldFrame, 0u);
  EXPECT_EQ(early[1].x, 0.0f);

  const char* rounds[3] = {"tilted plane", "moved plane", "the default plane after a cut"};
  LayerView roundView = view;
  for (int round = 0; round < 3; ++round) {
    SCOPED_TRACE(rounds[round]);
    CanopyParams p = canopyParams(ctx);
    if (round == 1) p.plane = tiltedPlane(m, -40.0f, 35.0f, 0.2f * (m.boundsMax - m.boundsMin));
    // Back to the default plane, taken again from the camera of a cut that re-slices elsewhere.
    if (round == 2) p.customPlane = false, roundView = orbitView(m.boundsMin, m.boundsMax, 70.0f, 30.0f, 40.0f, 96.0f / 64.0f, 1.3f);
    ASSERT_TRUE(setCanopyParams(ctx, p).ok());
    ASSERT_TRUE(host.frame(++frameNumber, {ctx}, roundView, 1.0f / 30.0f, round == 2).ok());
    // The plane the wind is read through, as a host gets it (CanopyWindInfo).
    CanopyWind cw;
    ASSERT_TRUE(canopyWind(ctx, &cw).ok());
    SimulationPlane plane;
    plane.origin = {cw.info.origin[0], cw.info.origin[1], cw.info.origin[2]};
    plane.tileSize = cw.info.origin[3];
    plane.right = {cw.info.right[0], cw.info.right[1], cw.info.right[2]};
    plane.up = {cw.info.up[0], cw.info.up[1], cw.info.up[2]};
    EXPECT_EQ(uint32_t(cw.info.right[3]), n);
    if (round < 2) EXPECT_TRUE(plane == canopyParams(ctx).plane);
    else EXPECT_FALSE(plane == canopyParams(ctx).plane) << "the default plane follows the new camera";
    const std::vector<glm::vec4> pts = windPoints(plane, n);
    Probe probe;
    s = probe.create(dev, pts);
    ASSERT_TRUE(s.ok()) << s.message();
    host.recordAfter = [&](VkCommandBuffer cmd) { return probe.record(ctx, cmd); };
    uint64_t lastStep = 0;
    for (int i = 0; i < 24; ++i) {
      s = host.frame(++frameNumber, {ctx}, roundView, 1.0f / 30.0f);
      ASSERT_TRUE(s.ok()) << s.message();
      lastStep = frameNumber;
    }
    ASSERT_TRUE(host.finish().ok());
    std::vector<glm::vec4> gpu;
    ASSERT_TRUE(probe.read(&gpu).ok());
    SimulationFields f;
    ASSERT_TRUE(readSimulationFields(canopySimulation(ctx), &f).ok());
    // The tiled wind the image holds is the tile pass of the simulation's own V_wind.
    const std::vector<float> tiled = tileOfWind(f);
    double maxTile = 0, maxWind = 0;
    for (size_t k = 0; k < tiled.size(); ++k) {
      maxTile = std::max(maxTile, double(std::abs(tiled[k] - f.tiled[2 * gpu::tiledWindOffset(n) + k])));
      maxWind = std::max(maxWind, double(std::abs(tiled[k])));
    }
    EXPECT_GT(maxWind, 0.05) << "the wind must blow for the comparison to mean anything";
    EXPECT_LE(maxTile, 1e-5 * maxWind) << "tiled V_wind against the tiling of the simulation's V_wind";
    // The host's shader at each point against the CPU's reading of the same field (and, at cell
    // centres, exactly that cell's value): world vectors, world units/s.
    double maxShader = 0, maxCell = 0, maxNormal = 0, scale = 0;
    const glm::vec3 r = toGlm(plane.right), u = toGlm(plane.up), nrm = glm::cross(r, u);
    for (size_t k = 0; k < pts.size(); ++k) {
      const glm::vec3 cpu = windAtWorld(tiled.data(), n, plane, glm::vec3(pts[k]));
      maxShader = std::max(maxShader, double(glm::length(glm::vec3(gpu[k]) - cpu)));
      maxNormal = std::max(maxNormal, double(std::abs(glm::dot(glm::vec3(gpu[k]), nrm))));
      scale = std::max(scale, double(glm::length(cpu)));
      if (k < 48) {  // a cell centre
        const glm::vec3 rel = glm::vec3(pts[k]) - toGlm(plane.origin);
        const glm::vec2 a = glm::vec2(glm::dot(rel, r), glm::dot(rel, u)) / plane.tileSize;
        const glm::ivec2 cell = glm::ivec2(glm::floor((a - glm::floor(a)) * float(n)));
        const size_t c = size_t(cell.y) * n + size_t(cell.x);
        const glm::vec3 want = plane.tileSize * (tiled[2 * c] * r + tiled[2 * c + 1] * u);
        maxCell = std::max(maxCell, double(glm::length(glm::vec3(gpu[k]) - want)));
      }
    }
    // sampleCanopyWind reads a copy framesInFlight frames late: two frames that hold the
    // simulation (dt 0) make the last step's copy the newest completed one.
    host.recordAfter = nullptr;
    for (int i = 0; i < int(dev.framesInFlight); ++i) ASSERT_TRUE(host.frame(++frameNumber, {ctx}, roundView, 0.0f).ok());
    std::vector<Float3> in(pts.size()), cpuOut(pts.size());
    for (size_t k = 0; k < pts.size(); ++k) in[k] = toFloat3(glm::vec3(pts[k]));
    s = sampleCanopyWind(ctx, in.data(), in.size(), cpuOut.data(), &fieldFrame);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(fieldFrame, lastStep);
    double maxSampler = 0;
    for (size_t k = 0; k < pts.size(); ++k) maxSampler = std::max(maxSampler, double(glm::length(toGlm(cpuOut[k]) - glm::vec3(gpu[k]))));
    std::printf("[ wind ] %s: |wind| up to %.4f world units/s at %zu points; canopyWindAt vs the simulation's tiled wind "
                "%.2e (cell centres %.2e), along the normal %.2e; sampleCanopyWind (frame %llu, %u frames late) vs canopyWindAt %.2e; "
                "tiled V_wind vs the tiling of V_wind %.2e\n",
                rounds[round], scale, pts.size(), maxShader, maxCell, maxNormal,
                static_cast<unsigned long long>(fieldFrame), dev.framesInFlight, maxSampler, maxTile);
    EXPECT_LE(maxShader, 1e-4 * scale);
    EXPECT_LE(maxCell, 1e-4 * scale);
    EXPECT_LE(maxNormal, 1e-5 * scale);
    EXPECT_LE(maxSampler, 1e-4 * scale);
    probe.destroy();
  }
  destroyCanopy(ctx);
  host.destroy();
}

// Pushers at the cap, above it, non-finite, outside the domain and behind the camera.
TEST_F(WindTest, PushersAreRefusedMappedOrIgnoredAsStated) {
  VegetationModel m = scene(SceneKind::GrassField, 6000);
  CanopyContext* ctx = nullptr;
  Host host;
  host.w = 96;
  host.h = 64;
  ASSERT_TRUE(test::createHostContext(dev, host, {SpeciesModel{&m}}, {}, 0.5f, false, &ctx).ok());
  const LayerView view = orbitView(m.boundsMin, m.boundsMax, 0.0f, 20.0f, 40.0f, 96.0f / 64.0f, 1.0f);
  const glm::vec3 c = 0.5f * (m.boundsMin + m.boundsMax), ext = m.boundsMax - m.boundsMin;
  const float R = 0.05f * std::max(ext.x, ext.z);
  std::vector<CanopyPusher> cap(kMaxPushers);
  for (uint32_t i = 0; i < kMaxPushers; ++i) {
    const float t = float(i) / float(kMaxPushers - 1) - 0.5f;
    cap[i].a = toFloat3(c + glm::vec3(t * ext.x, 0.0f, 0.2f * t * ext.z));
    cap[i].b = toFloat3(c + glm::vec3(t * ext.x, 0.3f * ext.y, 0.2f * t * ext.z));  // capsules
    cap[i].radius = R;
    cap[i].velocity = toFloat3(glm::vec3(1.0f, 0.0f, -0.5f) * ext.x);
    cap[i].blow = 0.5f * ext.x;
  }
  Status s = setCanopyPushers(ctx, cap);
  ASSERT_TRUE(s.ok()) << s.message();
  std::vector<CanopyPusher> over = cap;
  over.push_back(cap[0]);
  s = setCanopyPushers(ctx, over);
  EXPECT_EQ(s.code(), Result::InvalidArgument);
  EXPECT_EQ(s.message(), "setCanopyPushers: 33 pushers given, at most 32 (kMaxPushers)");
  std::vector<CanopyPusher> bad = cap;
  bad[3].radius = std::nanf("");
  s = setCanopyPushers(ctx, bad);
  EXPECT_NE(s.message().find("pushers[3].radius"), std::string::npos) << s.message();
  bad = cap;
  bad[7].velocity.y = INFINITY;
  s = setCanopyPushers(ctx, bad);
  EXPECT_NE(s.message().find("pushers[7].velocity.y"), std::string::npos) << s.message();
  bad = cap;
  bad[0].bend = -1.0f;
  EXPECT_NE(setCanopyPushers(ctx, bad).message().find("pushers[0].bend"), std::string::npos);
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok());
  CanopyStats st = canopyStats(ctx);
  EXPECT_EQ(st.pushersMapped, kMaxPushers) << "the refused calls kept the pushers in force";
  // Far outside the domain, and behind the camera: nothing.
  const glm::vec3 eye = viewPosition(view.view), fwd = viewForward(view.view);
  std::vector<CanopyPusher> away(2, cap[0]);
  away[0].a = away[0].b = toFloat3(c + glm::vec3(50.0f * ext.x, 0.0f, 0.0f));
  away[1].a = away[1].b = toFloat3(eye - 3.0f * R * fwd);
  ASSERT_TRUE(setCanopyPushers(ctx, away).ok());
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok());
  st = canopyStats(ctx);
  EXPECT_EQ(st.pushersMapped, 0u);
  EXPECT_EQ(st.pushersOutside, 1u);
  EXPECT_EQ(st.pushersBehind, 1u);
  ASSERT_TRUE(host.finish().ok());
  SimulationFields f;
  ASSERT_TRUE(readSimulationFields(canopySimulation(ctx), &f).ok());
  size_t bad_ = 0;
  for (const std::vector<float>* v : {&f.velocity, &f.wind, &f.vs, &f.tiled})
    for (float x : *v) bad_ += !std::isfinite(x);
  EXPECT_EQ(bad_, 0u) << "non-finite values in the simulation after 32 capsules";
  destroyCanopy(ctx);
  host.destroy();
}

}  // namespace

namespace {

// The world point of warp-grid corner `id` of `layer` (anim_displace.comp's unprojection).
glm::vec3 cornerWorld(const gpu::AnimFrame& f, uint32_t id, uint32_t layer) {
  const uint32_t gx = id % f.gridX, gy = id / f.gridX;
  const glm::vec2 pixel = glm::min(glm::vec2(float(gx), float(gy)) * f.cellSize, glm::vec2(f.width, f.height));
  const glm::vec2 ndc = pixel / glm::vec2(f.width, f.height) * 2.0f - 1.0f;
  const glm::vec4 h0 = f.invViewProj * glm::vec4(ndc, 0.0f, 1.0f), h1 = f.invViewProj * glm::vec4(ndc, 1.0f, 1.0f);
  const glm::vec3 p0 = glm::vec3(h0) / h0.w, p1 = glm::vec3(h1) / h1.w;
  const float d0 = glm::dot(f.depthRow, glm::vec4(p0, 1.0f)), d1 = glm::dot(f.depthRow, glm::vec4(p1, 1.0f));
  return p0 + (p1 - p0) * ((f.layers[layer].depth - d0) / (d1 - d0));
}

float horizontalDistanceToSegment(glm::vec3 p, glm::vec3 a, glm::vec3 b) {
  const glm::vec2 q(p.x, p.z), s(a.x, a.z), e(b.x, b.z);
  const glm::vec2 d = e - s;
  const float t = glm::dot(d, d) > 0.0f ? glm::clamp(glm::dot(q - s, d) / glm::dot(d, d), 0.0f, 1.0f) : 0.0f;
  return glm::length(q - (s + t * d));
}

}  // namespace

// A sphere walks along a line through a grass field at a known speed, then leaves: the layers'
// displacement (the warp grid's corners, every layer) against the same run without it. The
// difference peaks next to the sphere and follows it, springs back once it has gone, and stays
// near zero beyond 3 radii of its path.
TEST_F(WindTest, APusherPartsTheGrassWhereItWalksAndItSpringsBack) {
  VegetationModel m = scene(SceneKind::GrassField, 20000);
  const LayerView view = orbitView(m.boundsMin, m.boundsMax, 0.0f, 25.0f, 40.0f, 160.0f / 120.0f, 0.9f);
  const glm::vec3 c = 0.5f * (m.boundsMin + m.boundsMax), ext = m.boundsMax - m.boundsMin;
  const float extent = std::max(ext.x, ext.z), R = extent / 12.0f;
  const glm::vec3 right = glm::normalize(glm::vec3(glm::inverse(view.view)[0].x, 0.0f, glm::inverse(view.view)[0].z));
  const glm::vec3 start = glm::vec3(c.x, m.boundsMin.y + 0.5f * R, c.z) - 0.3f * extent * right;
  const float dt = 1.0f / 30.0f, speed = 0.6f * extent / 2.0f;  // across 0.6 of the field in 2 s
  const int walk = 60, after = 60;
  const glm::vec3 end = start + speed * dt * float(walk - 1) * right;
  struct Result {
    double peak = 0, beyond = 0, lagSeconds = 0, swayRms = 0, settled = -1;
  };
  // One run with the sphere (its bend and air) against one without, frame by frame.
  auto run = [&](float bend, float air, bool print, Result* out) {
    Host hostA, hostB;
    hostA.w = hostB.w = 160;
    hostA.h = hostB.h = 120;
    CanopyContext *a = nullptr, *b = nullptr;
    ASSERT_TRUE(test::createHostContext(dev, hostA, {SpeciesModel{&m}}, {}, 0.5f, false, &a).ok());
    ASSERT_TRUE(test::createHostContext(dev, hostB, {SpeciesModel{&m}}, {}, 0.5f, false, &b).ok());
    // The bend is read at the warp grid's corners: the sphere spans a few cells on screen.
    for (CanopyContext* ctx : {a, b}) {
      CanopyParams p = canopyParams(ctx);
      p.dynamics.cellSize = 4;
      ASSERT_TRUE(setCanopyParams(ctx, p).ok());
    }
    double sumLag = 0, sway = 0;
    int lagFrames = 0, swayCount = 0;
    std::vector<double> bandAfter;
    for (int k = 0; k < walk + after; ++k) {
      const glm::vec3 p = start + speed * dt * float(std::min(k, walk - 1)) * right;
      std::vector<CanopyPusher> pushers;
      if (k < walk) {
        CanopyPusher q;
        q.a = q.b = toFloat3(p);
        q.radius = R;
        q.velocity = toFloat3(speed * right);
        q.bend = bend;
        q.air = air;
        pushers.push_back(q);
      }
      ASSERT_TRUE(setCanopyPushers(a, pushers).ok());
      ASSERT_TRUE(hostA.frame(++frameNumber, {a}, view, dt).ok());
      ASSERT_TRUE(hostB.frame(frameNumber, {b}, view, dt).ok());
      ASSERT_TRUE(hostA.finish().ok());
      ASSERT_TRUE(hostB.finish().ok());
      const LayerDynamics &da = canopyDynamics(a), &db = canopyDynamics(b);
      const gpu::AnimFrame& f = da.current;
      const size_t corners = size_t(f.gridX) * f.gridY, count = corners * f.layerCount;
      std::vector<glm::vec2> dA(count), dB(count);
      ASSERT_TRUE(readbackBuffer(dev, da.displacement, dA.data(), count * sizeof(glm::vec2), rg::stateOf(rg::Use::ComputeStorageRead)).ok());
      ASSERT_TRUE(readbackBuffer(dev, db.displacement, dB.data(), count * sizeof(glm::vec2), rg::stateOf(rg::Use::ComputeStorageRead)).ok());
      double peak = 0, band = 0;
      glm::vec3 peakAt(0.0f);
      for (uint32_t layer = 0; layer < f.layerCount; ++layer)
        for (uint32_t id = 0; id < corners; ++id) {
          const size_t i = size_t(layer) * corners + id;
          const double diff = glm::length(dA[i] - dB[i]);
          const glm::vec3 w = cornerWorld(f, id, layer);
          if (w.x < m.boundsMin.x || w.x > m.boundsMax.x || w.z < m.boundsMin.z || w.z > m.boundsMax.z) continue;  // no grass there
          const float fromPath = horizontalDistanceToSegment(w, start, end);
          if (fromPath > 3.0f * R) out->beyond = std::max(out->beyond, diff);
          else band = std::max(band, diff);
          if (k >= walk && fromPath <= 3.0f * R) sway += glm::dot(dB[i], dB[i]), swayCount++;
          if (diff > peak) peak = diff, peakAt = w;
        }
      out->peak = std::max(out->peak, peak);
      if (k >= walk) bandAfter.push_back(band);
      // The peak behind the sphere along its walk (positive: behind), over the middle of the walk.
      if (k >= 15 && k < walk) sumLag += glm::dot(p - peakAt, right), lagFrames++;
      if (print && (k % 10 == 0 || k == walk))
        std::printf("[ push ] %3d %s %.3f: peak %.2f px at %.3f along, %.3f from its path\n", k, k < walk ? "at" : "gone, last at",
                    glm::dot(p - start, right), peak, glm::dot(peakAt - start, right), horizontalDistanceToSegment(peakAt, start, end));
    }
    out->swayRms = std::sqrt(sway / std::max(swayCount, 1));
    for (size_t i = 0; i < bandAfter.size() && out->settled < 0; ++i)
      if (bandAfter[i] <= 0.1 * out->swayRms) out->settled = double(i) * dt;
    out->lagSeconds = sumLag / std::max(lagFrames, 1) / speed;
    destroyCanopy(a);
    destroyCanopy(b);
    hostA.destroy();
    hostB.destroy();
  };
  std::printf("[ push ] frame, sphere along its path (world units), the difference's peak (pixels) and where it is\n");
  Result pushed, airOnly;
  const CanopyPusher defaults;
  run(2.0f, defaults.air, true, &pushed);
  run(0.0f, 1.0f, false, &airOnly);
  std::printf("[ push ] radius %.3f, speed %.3f world units/s, bend 2, air %.2f: the difference peaks at %.2f px, %.3f s behind "
              "the sphere on average; beyond 3 radii of its path at most %.3f px (%.1f %% of the peak); the undisturbed sway in "
              "the band %.2f px RMS; after the sphere left the band's difference fell within 10 %% of it in %.2f s\n",
              R, speed, defaults.air, pushed.peak, pushed.lagSeconds, pushed.beyond, 100.0 * pushed.beyond / std::max(pushed.peak, 1e-9),
              pushed.swayRms, pushed.settled);
  std::printf("[ push ] the fluid motor alone (bend 0, air 1): the difference peaks at %.2f px, beyond 3 radii %.3f px\n",
              airOnly.peak, airOnly.beyond);
  EXPECT_GT(pushed.peak, pushed.swayRms) << "the grass parts by more than its undisturbed sway";
  EXPECT_GE(pushed.lagSeconds, -0.1);
  EXPECT_LE(pushed.lagSeconds, 1.0) << "the bend follows the sphere (its trail springs back behind it)";
  EXPECT_LE(pushed.beyond, 0.05 * pushed.peak) << "grass beyond 3 radii of the path keeps its sway";
  EXPECT_GE(pushed.settled, 0.0) << "the grass springs back";
  EXPECT_LE(pushed.settled, 1.5) << "within 1.5 s";
  EXPECT_LT(airOnly.peak, pushed.peak) << "the bend, not the fluid motor, parts the grass";
}

// The world wind (issue 66; docs/design.md "World wind"): the plane a host reads the wind through
// is the wind's, whichever camera came first (two contexts, the first seen from yaw 0, the second
// from yaw 180), and the wind at the vegetation blows along the world direction at about the
// speed given (world units/s = m/s here), before and after the direction is changed and eased in.
TEST_F(WindTest, TheWorldWindIsTheSameWhicheverCameraCameFirst) {
  VegetationModel m = scene(SceneKind::Shrub, 6000);
  Host host;
  host.w = 96;
  host.h = 64;
  ASSERT_TRUE(host.create(dev, 2).ok());
  CanopyDesc d;
  d.width = host.w;
  d.height = host.h;
  d.colorFormat = host.colorFormat;
  d.simulation.gridSize = 32;
  d.params.wind.direction = {0.0f, 0.0f, -2.0f};
  d.params.wind.speed = 4.0f;
  d.params.wind.easeSeconds = 0.5f;
  CanopyContext* ctx[2] = {nullptr, nullptr};
  const float yaw[2] = {0.0f, 180.0f};
  CanopyWindInfo info[2];
  const glm::vec3 centre = 0.5f * (m.boundsMin + m.boundsMax);
  const Float3 at[1] = {toFloat3(centre)};
  for (int k = 0; k < 2; ++k) {
    Status s = createCanopy(dev, m, d, &ctx[k]);
    ASSERT_TRUE(s.ok()) << s.message();
    const LayerView view = orbitView(m.boundsMin, m.boundsMax, yaw[k], 15.0f, 40.0f, 96.0f / 64.0f, 1.0f);
    for (int i = 0; i < 45; ++i) ASSERT_TRUE(host.frame(++frameNumber, {ctx[k]}, view, 1.0f / 30.0f).ok());
    CanopyWind cw;
    ASSERT_TRUE(canopyWind(ctx[k], &cw).ok());
    info[k] = cw.info;
    Float3 v;
    ASSERT_TRUE(sampleCanopyWind(ctx[k], at, 1, &v).ok());
    const glm::vec3 w = toGlm(v);
    EXPECT_GT(glm::dot(w, glm::vec3(0, 0, -1)), 0.8f * glm::length(w)) << "blows toward -Z from yaw " << yaw[k];
    EXPECT_GT(glm::length(w), 0.25f * 4.0f) << "about the speed given";
    EXPECT_LT(glm::length(w), 3.0f * 4.0f);
  }
  for (int i = 0; i < 4; ++i) {
    EXPECT_FLOAT_EQ(info[0].origin[i], info[1].origin[i]);
    EXPECT_FLOAT_EQ(info[0].right[i], info[1].right[i]);
    EXPECT_FLOAT_EQ(info[0].up[i], info[1].up[i]);
  }
  // Turned to +X: eased in over 0.5 s, then the wind at the centre blows that way.
  CanopyParams p = canopyParams(ctx[1]);
  p.wind.direction = {1.0f, 0.0f, 0.0f};
  ASSERT_TRUE(setCanopyParams(ctx[1], p).ok());
  const LayerView view = orbitView(m.boundsMin, m.boundsMax, 180.0f, 15.0f, 40.0f, 96.0f / 64.0f, 1.0f);
  ASSERT_TRUE(host.frame(++frameNumber, {ctx[1]}, view, 1.0f / 30.0f).ok());
  CanopyWind early;
  ASSERT_TRUE(canopyWind(ctx[1], &early).ok());
  EXPECT_GT(-early.info.right[2], 0.95f) << "one frame in, the plane has barely turned (no pop)";
  for (int i = 0; i < 60; ++i) ASSERT_TRUE(host.frame(++frameNumber, {ctx[1]}, view, 1.0f / 30.0f).ok());
  CanopyWind turned;
  ASSERT_TRUE(canopyWind(ctx[1], &turned).ok());
  EXPECT_NEAR(turned.info.right[0], 1.0f, 1e-4f);
  Float3 v;
  ASSERT_TRUE(sampleCanopyWind(ctx[1], at, 1, &v).ok());
  EXPECT_GT(glm::dot(toGlm(v), glm::vec3(1, 0, 0)), 0.8f * glm::length(toGlm(v)));
  ASSERT_TRUE(host.finish().ok());
  destroyCanopy(ctx[0]);
  destroyCanopy(ctx[1]);
  host.destroy();
}
