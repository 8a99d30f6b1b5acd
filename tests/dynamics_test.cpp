// Layer dynamics (paper 3.4-3.6): projection eq. 1-2, layer delay eq. 3-5 (exact and approximate,
// the sign flip, the clamp to existing history) and displacement eq. 6-7, on the device against
// closed forms and against the CPU reference.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/gtc/matrix_transform.hpp>

#include "compute/dynamics.h"
#include "compute/dynamics_reference.h"
#include "engine/transfer.h"
#include "tests/gpu_test.h"

using namespace canopy;
using canopy::test::GpuTest;

namespace {

constexpr uint32_t kW = 96, kH = 64, kCell = 8;

LayerView frontView() {
  LayerView v;
  v.view[3][2] = -10.0f;
  v.proj = perspectiveVulkan(glm::radians(40.0f), float(kW) / float(kH), 1.0f, 30.0f);
  return v;
}

DynamicsFrameDesc frameDesc(uint32_t n, uint32_t ring, float time, std::vector<float> distances) {
  DynamicsFrameDesc d;
  d.view = frontView();
  d.plane = simulationPlaneFromView(d.view, 10.0f);
  for (float L : distances) d.layers.push_back({10.0f + L, L, float(kH), float(kH)});
  d.width = kW;
  d.height = kH;
  d.simSize = n;
  d.ringSize = ring;
  d.time = time;
  return d;
}

// Runs the displacement pass on the device with the given fields.
class DynamicsTest : public GpuTest {
 protected:
  std::vector<glm::vec2> run(const gpu::AnimFrame& f, const std::vector<glm::vec2>& tiled,
                             const std::vector<glm::vec2>& ring, const std::vector<float>& times) {
    LayerDynamics x;
    Status s = createLayerDynamics(dev, kW, kH, kCell, CANOPY_MAX_LAYERS, &x);
    EXPECT_TRUE(s.ok()) << s.message();
    x.current = f;
    const rg::State read = rg::stateOf(rg::Use::ComputeStorageRead);
    Buffer b[3];
    const void* data[3] = {tiled.data(), ring.data(), times.data()};
    const size_t bytes[3] = {tiled.size() * 8, ring.size() * 8, times.size() * 4};
    for (int i = 0; i < 3; ++i) {
      EXPECT_TRUE(createBuffer(dev, bytes[i], VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                               MemoryUsage::DeviceLocal, &b[i]).ok());
      EXPECT_TRUE(uploadBuffer(dev, nullptr, b[i], data[i], bytes[i], read).ok());
    }
    rg::RenderGraph g;
    rg::ResourceId ids[3];
    for (int i = 0; i < 3; ++i) {
      ids[i] = g.importBuffer("field", bytes[i], read, read);
      EXPECT_TRUE(g.bindBuffer(ids[i], b[i].buffer).ok());
    }
    rg::ResourceId disp;
    s = addDynamicsPasses(x, g, ids[0], ids[1], ids[2], &disp);
    if (s.ok()) s = g.compile();
    if (s.ok()) s = g.realize(dev);
    if (s.ok()) s = submitAndWait(dev, [&](VkCommandBuffer cmd) { return g.record(cmd); });
    EXPECT_TRUE(s.ok()) << s.message();
    std::vector<glm::vec2> out(size_t(f.gridX) * f.gridY * f.layerCount);
    s = readbackBuffer(dev, x.displacement, out.data(), out.size() * 8, read);
    EXPECT_TRUE(s.ok()) << s.message();
    g.release(dev);
    for (Buffer& buf : b) destroyBuffer(dev, buf);
    destroyLayerDynamics(x);
    return out;
  }
};

// Plain reading of d: everything moves, no attenuation, lambda = 1, dt = 1 -> d = (Vx, -Vy).
DynamicsParams identityParams(DelayMode mode, float vd) {
  DynamicsParams p;
  p.delay = mode;
  p.vd = vd;
  p.lambda = {1.0f, 1.0f, 0.0f};
  p.everyPartMoves = true;
  p.depthAttenuation = 0.0f;
  p.dt = 1.0f;
  p.cellSize = kCell;
  // The paper's formulas in the units these tests state them in: L_i in world units, lambda in pixels.
  p.delayUnits = DelayDistanceUnits::World;
  p.lambdaUnits = LambdaUnits::Pixels;
  return p;
}

}  // namespace

TEST(DynamicsProjection, Eq1TiltedSimulationPlane) {
  for (float theta : {0.0f, 0.3f, 0.9f, 1.5707963f, 2.4f}) {
    DynamicsFrameDesc d = frameDesc(8, 1, 0, {0});
    d.plane.right = {1, 0, 0};
    d.plane.up = {0, std::sin(theta), std::cos(theta)};
    gpu::AnimFrame f;
    ASSERT_TRUE(makeAnimFrame(DynamicsParams{}, d, &f).ok());
    for (glm::vec2 vs : {glm::vec2(1, 0), glm::vec2(0, 1), glm::vec2(0.3f, -0.7f)}) {
      const glm::vec3 v0 = gpu::simToView(f, vs);  // the view is the world here
      EXPECT_NEAR(v0.x, vs.x, 1e-6f);
      EXPECT_NEAR(v0.y, vs.y * std::sin(theta), 1e-6f) << theta;
      EXPECT_NEAR(v0.z, vs.y * std::cos(theta), 1e-6f) << theta;
    }
  }
}

TEST(DynamicsProjection, Eq2YawedView) {
  // The view turned by alpha in the XZ plane. The extracted eq. 2 reads V0z = Wx sin a + Wz cos a;
  // with V0x = Wx cos a + Wz sin a that map is not a rotation (it scales vectors), so the
  // orthonormal reading V0z = -Wx sin a + Wz cos a is the one reproduced (docs/design.md: eq. 1-2 are
  // special cases of the general rotation).
  const float theta = 0.7f;
  for (float alpha : {-1.0f, -0.2f, 0.0f, 0.4f, 1.2f}) {
    DynamicsFrameDesc d = frameDesc(8, 1, 0, {0});
    d.plane.right = {1, 0, 0};
    d.plane.up = {0, std::sin(theta), std::cos(theta)};
    d.view.view = glm::mat4(1.0f);
    d.view.view[0][0] = std::cos(alpha);
    d.view.view[2][0] = std::sin(alpha);
    d.view.view[0][2] = -std::sin(alpha);
    d.view.view[2][2] = std::cos(alpha);
    d.view.view[3][2] = -10.0f;
    gpu::AnimFrame f;
    ASSERT_TRUE(makeAnimFrame(DynamicsParams{}, d, &f).ok());
    const glm::vec2 vs(0.6f, -0.4f);
    const glm::vec3 w(vs.x, vs.y * std::sin(theta), vs.y * std::cos(theta));  // eq. 1
    const glm::vec3 v0 = gpu::simToView(f, vs);
    EXPECT_NEAR(v0.x, w.x * std::cos(alpha) + w.z * std::sin(alpha), 1e-6f) << alpha;
    EXPECT_NEAR(v0.y, w.y, 1e-6f) << alpha;
    EXPECT_NEAR(v0.z, -w.x * std::sin(alpha) + w.z * std::cos(alpha), 1e-6f) << alpha;
  }
}

TEST(DynamicsProjection, IdentityWhenTheViewIsTheSimulationPlane) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1, 1);
  for (int k = 0; k < 20; ++k) {
    DynamicsFrameDesc d = frameDesc(8, 1, 0, {0});
    d.view.view = glm::lookAtRH(glm::vec3(u(rng), u(rng), u(rng)) * 5.0f, glm::vec3(0), glm::normalize(glm::vec3(u(rng), 1, u(rng))));
    d.plane = simulationPlaneFromView(d.view, 4.0f);
    gpu::AnimFrame f;
    ASSERT_TRUE(makeAnimFrame(DynamicsParams{}, d, &f).ok());
    const glm::vec2 vs(u(rng), u(rng));
    const glm::vec3 v0 = gpu::simToView(f, vs);
    EXPECT_NEAR(v0.x, vs.x, 1e-5f);
    EXPECT_NEAR(v0.y, vs.y, 1e-5f);
    EXPECT_NEAR(v0.z, 0.0f, 1e-5f);
  }
}

TEST(DynamicsParamsCheck, RefusesOutOfRangeValues) {
  DynamicsParams p;
  p.rigidity = 11;
  EXPECT_NE(validateDynamicsParams(p).message().find("rigidity"), std::string::npos);
  p = {};
  p.depthAttenuation = -0.1f;
  EXPECT_NE(validateDynamicsParams(p).message().find("depthAttenuation"), std::string::npos);
  p = {};
  p.cellSize = 1;
  EXPECT_NE(validateDynamicsParams(p).message().find("cellSize"), std::string::npos);
  p = {};
  p.dt = -0.01f;  // 0 is the simulation's nominal step
  EXPECT_FALSE(validateDynamicsParams(p).ok());
  p = {};
  p.vdJitter = -1.0f;
  EXPECT_NE(validateDynamicsParams(p).message().find("vdJitter"), std::string::npos);
  DynamicsFrameDesc d = frameDesc(8, 1, 0, {0});
  d.plane.up = {0, 0.5f, 0};
  gpu::AnimFrame f;
  EXPECT_FALSE(makeAnimFrame(DynamicsParams{}, d, &f).ok());
}

// Uniform fields with c(tau) = 0.5 + 5 tau at the ring times 0.1 (k + 1), stored in rotated slots.
TEST_F(DynamicsTest, ExactDelaySamplesTheHistoryAtTMinusGamma) {
  const uint32_t n = 8, H = 16;
  std::vector<glm::vec2> ring(size_t(H) * n * n), tiled(size_t(n) * n);
  std::vector<float> times(H);
  auto c = [](float tau) { return 0.5f + 5.0f * tau; };
  for (uint32_t s = 0; s < H; ++s) {
    const uint32_t k = (s + 5) % H;
    times[s] = 0.1f * float(k + 1);
    for (uint32_t i = 0; i < n * n; ++i) ring[size_t(s) * n * n + i] = glm::vec2(c(times[s]), 0.0f);
  }
  for (auto& v : tiled) v = glm::vec2(c(1.6f), 0.0f);
  // V_D = 4, view = simulation plane (V0z = 0): gamma = L / 4 = 0, 0.25, 0.5, 2.5 (clamped to the oldest).
  gpu::AnimFrame f;
  ASSERT_TRUE(makeAnimFrame(identityParams(DelayMode::Exact, 4.0f), frameDesc(n, H, 1.6f, {0, 1, 2, 10}), &f).ok());
  const std::vector<glm::vec2> d = run(f, tiled, ring, times);
  const uint32_t corners = f.gridX * f.gridY;
  const float want[4] = {c(1.6f), c(1.35f), c(1.1f), c(0.1f)};
  for (uint32_t l = 0; l < 4; ++l)
    for (uint32_t k = 0; k < corners; ++k) {
      ASSERT_NEAR(d[l * corners + k].x, want[l], 1e-4f) << "layer " << l << " corner " << k;
      ASSERT_NEAR(d[l * corners + k].y, 0.0f, 1e-6f);
    }
  // 1.35 lies between the slots of 1.3 and 1.4: the nearest slot would give 7.0 or 7.5, not 7.25.
  EXPECT_NEAR(want[1], 7.25f, 1e-6f);
  // gamma < 0 (V_D < 0: wind from back to front) asks for the future: clamped to the newest field.
  ASSERT_TRUE(makeAnimFrame(identityParams(DelayMode::Exact, -4.0f), frameDesc(n, H, 1.6f, {0, 1, 2}), &f).ok());
  const std::vector<glm::vec2> e = run(f, tiled, ring, times);
  for (const glm::vec2& v : e) ASSERT_NEAR(v.x, c(1.6f), 1e-4f);
}

// A pattern V = (0.5 + 0.2 sin(2 pi a_x), 0) with eq. 5's old offset: approximate mode returns V
// at B = A + gamma s V(A), and at A - |gamma| s V(A) when gamma < 0.
TEST_F(DynamicsTest, ApproximateDelayLooksUpB) {
  const uint32_t n = 64;
  std::vector<glm::vec2> tiled(size_t(n) * n), ring = tiled;
  std::vector<float> times = {1.0f};
  auto field = [](float ax) { return 0.5f + 0.2f * std::sin(6.2831853f * ax); };
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i < n; ++i) tiled[j * n + i] = glm::vec2(field((float(i) + 0.5f) / float(n)), 0.0f);
  for (float vd : {2.0f, -2.0f}) {
    DynamicsParams p = identityParams(DelayMode::Approximate, vd);
    p.propagationSpeed = 0.5f;
    p.approximateOffset = ApproximateOffset::Velocity;  // before 0.7: B = A + gamma s V
    gpu::AnimFrame f;
    ASSERT_TRUE(makeAnimFrame(p, frameDesc(n, 1, 1.0f, {0, 0.4f}), &f).ok());
    const std::vector<glm::vec2> d = run(f, tiled, ring, times);
    const uint32_t corners = f.gridX * f.gridY;
    const float gamma = 0.4f / vd;
    double maxErr = 0, maxShift = 0;
    for (uint32_t k = 0; k < corners; ++k) {
      const glm::vec2 a = cornerSimCoord(f, 1, k % f.gridX, k / f.gridX);
      const float va = field(a.x);
      const float b = a.x + gamma * 0.5f * va;
      maxErr = std::max<double>(maxErr, std::abs(d[corners + k].x - field(b)));
      maxShift = std::max<double>(maxShift, std::abs(field(b) - va));
    }
    // Bilinear sampling of the sine on 64 cells errs by < 0.2 (2 pi / 64)^2 / 8 = 2.4e-4.
    EXPECT_LT(maxErr, 1e-3) << "V_D = " << vd;
    EXPECT_GT(maxShift, 0.02) << "the lookup must land visibly away from A";
  }
}

TEST_F(DynamicsTest, DisplacementMatchesTheCpuReference) {
  const uint32_t n = 32, H = 12;
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<glm::vec2> ring(size_t(H) * n * n), tiled(size_t(n) * n);
  std::vector<float> times(H);
  for (uint32_t s = 0; s < H; ++s) {
    times[s] = 0.05f * float((s + 7) % H);
    const float px = u(rng), py = u(rng);
    for (uint32_t j = 0; j < n; ++j)
      for (uint32_t i = 0; i < n; ++i)
        ring[size_t(s) * n * n + j * n + i] = glm::vec2(std::sin(6.283f * (float(i) / n + px)), std::cos(6.283f * (float(j) / n + py)));
  }
  const uint32_t newest = uint32_t(std::max_element(times.begin(), times.end()) - times.begin());
  std::copy(ring.begin() + size_t(newest) * n * n, ring.begin() + size_t(newest + 1) * n * n, tiled.begin());
  // The exact delay both ways: searching every slot, and by binary search in step order (the ring
  // above is a rotation: slot s holds step (s + 7) % H, the newest at `newest`).
  struct Case {
    DelayMode mode;
    bool ordered;
  };
  for (Case c : {Case{DelayMode::Exact, false}, Case{DelayMode::Exact, true}, Case{DelayMode::Approximate, false}}) {
    const DelayMode mode = c.mode;
    SCOPED_TRACE(c.ordered ? "ring in step order (binary search)" : "ring searched slot by slot");
    DynamicsParams p;
    p.delay = mode;
    p.vd = 1.5f;
    p.vdJitter = 0.4f;  // each layer's own V_D (eq. 4, "a small random number")
    p.lambda = {30, 20, 10};
    p.rigidity = 2.0f;
    p.depthAttenuation = 0.4f;
    p.cellSize = kCell;
    DynamicsFrameDesc desc = frameDesc(n, H, times[newest], {0, 0.7f, 1.9f});
    desc.plane = simulationPlaneFromView(desc.view, 10.0f);
    // A view turned against the simulation plane, so V0z and the delay vary per corner.
    desc.view.view = glm::lookAtRH(glm::vec3(4, 2, 9), glm::vec3(0, 0, 0), glm::vec3(0, 1, 0));
    for (auto& l : desc.layers) l.rootLineY = 0.75f * kH, l.height = 0.6f * kH;
    if (c.ordered) desc.newestSlot = newest;
    gpu::AnimFrame f;
    ASSERT_TRUE(makeAnimFrame(p, desc, &f).ok());
    const std::vector<glm::vec2> gpu = run(f, tiled, ring, times);
    const std::vector<glm::vec2> cpu = referenceDisplacement(f, tiled, ring, times);
    ASSERT_EQ(gpu.size(), cpu.size());
    double maxAbs = 0, maxDiff = 0;
    for (size_t i = 0; i < cpu.size(); ++i) {
      maxAbs = std::max<double>(maxAbs, glm::length(cpu[i]));
      maxDiff = std::max<double>(maxDiff, glm::length(gpu[i] - cpu[i]));
    }
    EXPECT_GT(maxAbs, 0.1);
    EXPECT_LE(maxDiff, 1e-4 * maxAbs) << (mode == DelayMode::Exact ? "exact" : "approximate");
    // Eq. 7 with r > 0: nothing at or below the root line moves.
    const uint32_t corners = f.gridX * f.gridY;
    for (uint32_t l = 0; l < 3; ++l)
      for (uint32_t k = 0; k < corners; ++k)
        if (float(k / f.gridX) * kCell >= 0.75f * kH) ASSERT_EQ(gpu[l * corners + k], glm::vec2(0.0f)) << k;
  }
}

TEST_F(DynamicsTest, LastLayerIsAttenuatedByOneMinusM) {
  const uint32_t n = 8;
  std::vector<glm::vec2> tiled(size_t(n) * n, glm::vec2(0.3f, 0.2f)), ring = tiled;
  std::vector<float> times = {0.0f};
  DynamicsParams p = identityParams(DelayMode::Approximate, 2.0f);
  p.lambda = {10, 10, 0};
  p.depthAttenuation = 0.4f;
  gpu::AnimFrame f;
  ASSERT_TRUE(makeAnimFrame(p, frameDesc(n, 1, 0.0f, {0, 0.5f, 2.0f}), &f).ok());
  EXPECT_FLOAT_EQ(f.layers[0].attenuation, 1.0f);
  EXPECT_FLOAT_EQ(f.layers[1].attenuation, 1.0f - 0.4f * 0.0625f);
  EXPECT_FLOAT_EQ(f.layers[2].attenuation, 0.6f);
  const std::vector<glm::vec2> d = run(f, tiled, ring, times);
  const uint32_t corners = f.gridX * f.gridY;
  for (uint32_t k = 0; k < corners; ++k) {
    EXPECT_NEAR(d[k].x, 3.0f, 1e-5f);
    EXPECT_NEAR(d[k].y, -2.0f, 1e-5f);
    EXPECT_NEAR(d[2 * corners + k].x, 0.6f * 3.0f, 1e-5f);
    EXPECT_NEAR(d[2 * corners + k].y, 0.6f * -2.0f, 1e-5f);
  }
}

// Eq. 4's L_i in domain units (world distance over the plane's tile), eq. 6's lambda in warp-grid
// cells and its Delta t the simulation's nominal step; the old units stay reachable; V_D per layer
// is the constant plus a seeded number in [-vdJitter, vdJitter], the same on every call.
TEST(DynamicsUnits, DelaysInDomainUnitsLambdaInCellsDtTheNominalStep) {
  DynamicsFrameDesc d = frameDesc(8, 1, 0.0f, {0, 0.5f, 2.0f});
  d.nominalDt = 0.02f;
  const float tile = d.plane.tileSize;
  ASSERT_GT(tile, 1.0f);
  DynamicsParams p;
  p.cellSize = kCell;
  gpu::AnimFrame f;
  ASSERT_TRUE(makeAnimFrame(p, d, &f).ok());
  EXPECT_FLOAT_EQ(f.layers[2].distance, 2.0f / tile);
  EXPECT_FLOAT_EQ(f.lambda.x, p.lambda.x * float(kCell));
  EXPECT_FLOAT_EQ(f.lambda.z, p.lambda.z * float(kCell));
  EXPECT_FLOAT_EQ(f.lambda.w, 0.02f);  // dt = 0: the simulation's nominal step
  for (uint32_t i = 0; i < 3; ++i) EXPECT_EQ(f.layers[i].vd, p.vd);
  // The same plant and camera scaled by 100: the same delays (the plane's tile scales with them).
  DynamicsFrameDesc big = d;
  big.view.view[3] *= glm::vec4(100.0f, 100.0f, 100.0f, 1.0f);
  big.plane = simulationPlaneFromView(big.view, 1000.0f);
  for (auto& l : big.layers) l.depth *= 100.0f, l.distance *= 100.0f;
  gpu::AnimFrame g;
  ASSERT_TRUE(makeAnimFrame(p, big, &g).ok());
  for (uint32_t i = 0; i < 3; ++i) EXPECT_NEAR(g.layers[i].distance, f.layers[i].distance, 1e-6f);
  // The old units, and dt given.
  p.delayUnits = DelayDistanceUnits::World;
  p.lambdaUnits = LambdaUnits::Pixels;
  p.dt = 1.0f / 30.0f;
  ASSERT_TRUE(makeAnimFrame(p, big, &g).ok());
  EXPECT_FLOAT_EQ(g.layers[2].distance, 200.0f);
  EXPECT_FLOAT_EQ(g.lambda.x, p.lambda.x);
  EXPECT_FLOAT_EQ(g.lambda.w, 1.0f / 30.0f);
  // V_D per layer: seeded, inside the band, not all equal, the same again; another seed differs.
  p.vdJitter = 0.5f;
  ASSERT_TRUE(makeAnimFrame(p, d, &f).ok());
  ASSERT_TRUE(makeAnimFrame(p, d, &g).ok());
  bool differ = false;
  for (uint32_t i = 0; i < 3; ++i) {
    EXPECT_EQ(f.layers[i].vd, g.layers[i].vd);
    EXPECT_LE(std::abs(f.layers[i].vd - p.vd), 0.5f);
    differ = differ || f.layers[i].vd != f.layers[0].vd;
  }
  EXPECT_TRUE(differ);
  p.vdSeed = 2;
  ASSERT_TRUE(makeAnimFrame(p, d, &g).ok());
  EXPECT_NE(g.layers[1].vd, f.layers[1].vd);
}

// Eq. 5 as the paper means it: on a steady wave travelling along V at speed s, the field at
// B = A + gamma s V/|V| now is the field at A gamma earlier, so the approximate delay equals the
// exact one up to sampling. s comes from the oscillator's c (DynamicsFrameDesc.waveSpeed) when
// DynamicsParams.propagationSpeed is 0. Bound: 1e-3 domain units/s, 0.5 % of the wave's amplitude
// (bilinear sampling of the sine on 64 cells errs by < 2.4e-4, the ring's linear time interpolation
// at 0.05 s by < 2.2e-4).
TEST_F(DynamicsTest, ApproximateAndExactDelayAgreeOnATravellingWave) {
  const uint32_t n = 64, H = 21;
  const float c = 0.3f, slot = 0.05f, now = 2.0f;
  auto wave = [&](float ax, float t) { return 0.5f + 0.2f * std::sin(6.2831853f * (ax - c * t)); };
  std::vector<glm::vec2> ring(size_t(H) * n * n), tiled(size_t(n) * n);
  std::vector<float> times(H);
  for (uint32_t k = 0; k < H; ++k) {
    times[k] = now - slot * float(k);
    for (uint32_t j = 0; j < n; ++j)
      for (uint32_t i = 0; i < n; ++i) ring[size_t(k) * n * n + j * n + i] = glm::vec2(wave((float(i) + 0.5f) / float(n), times[k]), 0.0f);
  }
  std::copy(ring.begin(), ring.begin() + size_t(n) * n, tiled.begin());
  std::vector<glm::vec2> out[2];
  for (int m = 0; m < 2; ++m) {
    DynamicsParams p = identityParams(m == 0 ? DelayMode::Exact : DelayMode::Approximate, 2.0f);
    p.propagationSpeed = 0.0f;  // s = c
    DynamicsFrameDesc d = frameDesc(n, H, now, {0, 0.4f, 0.9f});  // gamma = 0.2 s, 0.45 s
    d.waveSpeed = c;
    gpu::AnimFrame f;
    ASSERT_TRUE(makeAnimFrame(p, d, &f).ok());
    EXPECT_FLOAT_EQ(f.propagation, c);
    out[m] = run(f, tiled, ring, times);
    const std::vector<glm::vec2> cpu = referenceDisplacement(f, tiled, ring, times);
    for (size_t i = 0; i < cpu.size(); ++i) ASSERT_NEAR(glm::length(out[m][i] - cpu[i]), 0.0f, 1e-4f) << i;
  }
  double worst = 0, moved = 0;
  const size_t corners = out[0].size() / 3;
  for (size_t i = corners; i < out[0].size(); ++i) {
    worst = std::max<double>(worst, glm::length(out[0][i] - out[1][i]));
    moved = std::max<double>(moved, glm::length(out[0][i] - out[0][i % corners]));
  }
  std::printf("travelling wave c = %.2f domain units/s, gamma 0.2 and 0.45 s: exact vs approximate delay differ by at most %.2e "
              "domain units/s (the delayed layers differ from layer 0 by up to %.3f)\n", c, worst, moved);
  EXPECT_LE(worst, 1e-3);
  EXPECT_GT(moved, 0.1) << "the delays must matter on this wave";
}
