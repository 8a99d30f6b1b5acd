// Parameter fuzzing through the public API (issue "Reliability"): every frame one field of
// CanopyParams, or the frame's dt or camera, or (now and then) the context's size gets a random
// value from a hostile list (NaN, +-inf, huge, negative, zero, denormals, every enum value and one
// past it). Each value must be refused with a message naming the field, leaving the context as it
// was, or applied; every frame is read back from an RGBA16F target (which can hold NaN) and must
// be finite; validation and synchronization validation stay clean (GpuTest). Frames:
// CANOPY_PARAM_FUZZ_FRAMES (default 1500); the seed is fixed, so a failure replays.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <random>

#include "tests/gpu_test.h"
#include "tests/test_host.h"
#include "tools/leaf_cloud.h"

using namespace canopy;
using canopy::test::GpuTest;
using canopy::test::Host;

namespace {

const float kNaN = std::numeric_limits<float>::quiet_NaN(), kInf = std::numeric_limits<float>::infinity();
const float kFloats[] = {kNaN, kInf, -kInf, 0.0f, -0.0f, -1.0f, 1e-40f, 1e-45f, FLT_MAX, -FLT_MAX, 1e30f, 0.5f, 2.0f, 100.0f, 1e4f};
const uint32_t kUints[] = {0, 1, 2, 3, 4, 5, 7, 16, 33, 255, 1024, 65535, 0x7fffffffu, 0xffffffffu};

struct Field {
  const char* name;  // what a refusal must mention
  std::function<void(CanopyParams&, float, uint32_t)> set;
};

std::vector<Field> fields() {
  return {
      {"layout", [](CanopyParams& p, float, uint32_t u) { p.layers.layout.region[0] = u; }},
      {"layout", [](CanopyParams& p, float, uint32_t u) { p.layers.layout.region[1] = u; }},
      {"layout", [](CanopyParams& p, float, uint32_t u) { p.layers.layout.region[2] = u; }},
      {"region split", [](CanopyParams& p, float f, uint32_t) { p.layers.regions.nearEnd = f; }},
      {"region split", [](CanopyParams& p, float f, uint32_t u) { p.layers.regions.farStart = f, p.layers.regions.absolute = u & 1; }},
      {"slice", [](CanopyParams& p, float, uint32_t u) { p.layers.slice = SliceMode(u); }},
      {"draw", [](CanopyParams& p, float, uint32_t u) { p.layers.draw = LayerDrawMode(u); }},
      {"policy", [](CanopyParams& p, float, uint32_t u) { p.layers.policy = ReslicePolicy(u); }},
      {"errorThresholdPixels", [](CanopyParams& p, float f, uint32_t) { p.layers.errorThresholdPixels = f; }},
      {"turnThresholdDegrees", [](CanopyParams& p, float f, uint32_t) { p.layers.turnThresholdDegrees = f; }},
      {"lightDirection", [](CanopyParams& p, float f, uint32_t) { p.layers.lightDirection.x = f; }},
      {"lightColor", [](CanopyParams& p, float f, uint32_t) { p.layers.lightColor.y = f; }},
      {"ambient", [](CanopyParams& p, float f, uint32_t) { p.layers.ambient = f; }},
      {"leafRefractiveIndex", [](CanopyParams& p, float f, uint32_t) { p.layers.leafRefractiveIndex = f; }},
      {"leafRoughness", [](CanopyParams& p, float f, uint32_t) { p.layers.leafRoughness = f; }},
      {"leafTransmission", [](CanopyParams& p, float f, uint32_t) { p.layers.leafTransmission = f; }},
      {"impostors.mode", [](CanopyParams& p, float, uint32_t u) { p.layers.impostors.mode = ImpostorMode(u); }},
      {"impostors.switchPixels", [](CanopyParams& p, float f, uint32_t) { p.layers.impostors.switchPixels = f; }},
      {"impostors.band", [](CanopyParams& p, float f, uint32_t u) { p.layers.impostors.band = f, p.layers.impostors.debugView = u & 1; }},
      {"wind.sides", [](CanopyParams& p, float, uint32_t u) { p.simulation.wind.sides = u; }},
      {"wind.strength", [](CanopyParams& p, float f, uint32_t) { p.simulation.wind.strength = f; }},
      {"wind.frequency", [](CanopyParams& p, float f, uint32_t) { p.simulation.wind.frequency = f; }},
      {"wind.baseline", [](CanopyParams& p, float f, uint32_t) { p.simulation.wind.baseline = f; }},
      {"wind.modulation", [](CanopyParams& p, float f, uint32_t) { p.simulation.wind.modulation = f; }},
      {"wind.gust", [](CanopyParams& p, float f, uint32_t) { p.simulation.wind.gust = f; }},
      {"wind.gustScale", [](CanopyParams& p, float f, uint32_t) { p.simulation.wind.gustScale = f; }},
      {"wind.gustSpeed", [](CanopyParams& p, float f, uint32_t u) { p.simulation.wind.gustSpeed = f, p.simulation.wind.seed = u; }},
      {"fluid.scheme", [](CanopyParams& p, float, uint32_t u) { p.simulation.fluid.scheme = FluidScheme(u); }},
      {"fluid.boundary", [](CanopyParams& p, float, uint32_t u) { p.simulation.fluid.boundary = FluidBoundary(u); }},
      {"fluid.viscosity", [](CanopyParams& p, float f, uint32_t) { p.simulation.fluid.viscosity = f; }},
      {"fluid.iterations", [](CanopyParams& p, float, uint32_t u) { p.simulation.fluid.iterations = u; }},
      {"fluid.multigridCycles", [](CanopyParams& p, float, uint32_t u) { p.simulation.fluid.multigridCycles = u; }},
      {"wave.stiffness", [](CanopyParams& p, float f, uint32_t) { p.simulation.wave.stiffness = f; }},
      {"wave.speed", [](CanopyParams& p, float f, uint32_t) { p.simulation.wave.speed = f; }},
      {"wave.damping", [](CanopyParams& p, float f, uint32_t) { p.simulation.wave.damping = f; }},
      {"wave.gain", [](CanopyParams& p, float f, uint32_t) { p.simulation.wave.gain = f; }},
      {"wave.maxSubsteps", [](CanopyParams& p, float, uint32_t u) { p.simulation.wave.maxSubsteps = u; }},
      {"motors", [](CanopyParams& p, float f, uint32_t u) {
         p.simulation.motors.assign(u % 12, Motor{});
         if (!p.simulation.motors.empty()) p.simulation.motors[u % p.simulation.motors.size()].strength = f;
       }},
      {"motors", [](CanopyParams& p, float f, uint32_t) { p.simulation.motors = {Motor{f, 0.5f, 0.1f, 1.0f}}; }},
      {"motors", [](CanopyParams& p, float f, uint32_t) { p.simulation.motors = {Motor{0.5f, 0.5f, f, 1.0f}}; }},
      {"delay", [](CanopyParams& p, float, uint32_t u) { p.dynamics.delay = DelayMode(u); }},
      {"vd", [](CanopyParams& p, float f, uint32_t) { p.dynamics.vd = f; }},
      {"propagationSpeed", [](CanopyParams& p, float f, uint32_t) { p.dynamics.propagationSpeed = f; }},
      {"lambda", [](CanopyParams& p, float f, uint32_t) { p.dynamics.lambda.x = f; }},
      {"lambda", [](CanopyParams& p, float f, uint32_t) { p.dynamics.lambda.z = f; }},
      {"rigidity", [](CanopyParams& p, float f, uint32_t u) { p.dynamics.rigidity = f, p.dynamics.everyPartMoves = u & 1; }},
      {"depthAttenuation", [](CanopyParams& p, float f, uint32_t) { p.dynamics.depthAttenuation = f; }},
      {"dt", [](CanopyParams& p, float f, uint32_t) { p.dynamics.dt = f; }},
      {"cellSize", [](CanopyParams& p, float, uint32_t u) { p.dynamics.cellSize = u; }},
      {"maxDelay", [](CanopyParams& p, float f, uint32_t) { p.dynamics.maxDelay = f; }},
      {"depthAlpha", [](CanopyParams& p, float f, uint32_t u) { p.composite.depthAlpha = f, p.composite.earlyExit = u & 1; }},
      {"exposure", [](CanopyParams& p, float f, uint32_t u) { p.composite.exposure = f, p.composite.bilinear = u & 1; }},
      {"debugView", [](CanopyParams& p, float, uint32_t u) { p.composite.debugView = CompositeDebugView(u); }},
      {"debugVelocityScale", [](CanopyParams& p, float f, uint32_t u) { p.composite.debugVelocityScale = f, p.composite.skipEmptyTiles = u & 1; }},
      {"plane", [](CanopyParams& p, float f, uint32_t) { p.customPlane = true, p.plane.tileSize = f; }},
      {"plane", [](CanopyParams& p, float f, uint32_t) { p.customPlane = true, p.plane.right.x = f; }},
      {"animation", [](CanopyParams& p, float, uint32_t u) { p.animation = AnimationMode(u); }},
      {"perVertex.flexibility", [](CanopyParams& p, float f, uint32_t u) { p.animation = AnimationMode(u & 1), p.perVertex.flexibility[u % 4] = f; }},
      {"perVertex.frequency", [](CanopyParams& p, float f, uint32_t u) { p.animation = AnimationMode(u & 1), p.perVertex.frequency[u % 4] = f; }},
      {"perVertex.leafFlexibility", [](CanopyParams& p, float f, uint32_t u) { p.animation = AnimationMode(u & 1), p.perVertex.leafFlexibility = f; }},
      {"perVertex.leafFrequency", [](CanopyParams& p, float f, uint32_t u) { p.animation = AnimationMode(u & 1), p.perVertex.leafFrequency = f; }},
      {"perVertex.referenceSpeed", [](CanopyParams& p, float f, uint32_t u) { p.animation = AnimationMode(u & 1), p.perVertex.referenceSpeed = f; }},
      {"perVertex.lateral", [](CanopyParams& p, float f, uint32_t u) { p.animation = AnimationMode(u & 1), p.perVertex.lateral = f; }},
      {"perVertex.maxAngle", [](CanopyParams& p, float f, uint32_t u) { p.animation = AnimationMode(u & 1), p.perVertex.maxAngle = f; }},
      {"perVertex.taper", [](CanopyParams& p, float f, uint32_t u) { p.animation = AnimationMode(u & 1), p.perVertex.taper = f, p.perVertex.seed = u; }},
  };
}

bool finite(const std::vector<glm::vec4>& rgba, const std::vector<float>& z) {
  for (const glm::vec4& c : rgba)
    if (std::isnan(c.x) || std::isnan(c.y) || std::isnan(c.z) || std::isnan(c.w)) return false;
  for (float d : z)
    if (!std::isfinite(d)) return false;
  return true;
}

}  // namespace

class ParamFuzzTest : public GpuTest {};

TEST_F(ParamFuzzTest, HostileValuesAreRefusedNamingTheFieldOrAppliedAndFramesStayFinite) {
  const char* env = std::getenv("CANOPY_PARAM_FUZZ_FRAMES");
  const int frames = env ? std::atoi(env) : 1500;
  const VegetationModel model = makeLeafCloud(600, 3, true);
  Host host;
  host.w = 48;
  host.h = 32;
  ASSERT_TRUE(host.create(dev, 2).ok());
  CanopyDesc desc;
  desc.width = host.w;
  desc.height = host.h;
  desc.colorFormat = host.colorFormat;  // RGBA16F: a NaN would survive into the readback
  desc.depthFormat = host.depthFormat;
  desc.maxLayers = 8;
  desc.allowPerVertex = true;  // the baseline's parameters and mode switches are fuzzed too
  desc.impostors.enable = true;  // and the impostors' (a leaf cloud: k-d boxes)
  CanopyContext* ctx = nullptr;
  Status made = createCanopy(dev, model, desc, &ctx);
  ASSERT_TRUE(made.ok()) << made.message();

  std::mt19937 rng(20261128u);
  auto pick = [&](size_t n) { return size_t(rng() % n); };
  const std::vector<Field> table = fields();
  const CanopyParams defaults = canopyParams(ctx);
  CanopyParams accepted = defaults;
  int applied = 0, refused = 0, dtRefused = 0, cameraRefused = 0, resizes = 0, resizeRefused = 0, checked = 0;
  uint64_t number = 0;
  for (int i = 0; i < frames; ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    // One field away from the defaults (so one bad value cannot hide behind another).
    const Field& f = table[pick(table.size())];
    const float fv = kFloats[pick(std::size(kFloats))];
    const uint32_t uv = kUints[pick(std::size(kUints))];
    CanopyParams p = defaults;
    f.set(p, fv, uv);
    Status s = setCanopyParams(ctx, p);
    if (s.ok()) {
      ++applied;
      accepted = p;
    } else {
      ++refused;
      EXPECT_NE(s.message().find(f.name), std::string::npos) << "refusal must name " << f.name << ": " << s.message();
      EXPECT_TRUE(canopyParams(ctx).layers == accepted.layers) << "a refused value changed the context";
      EXPECT_EQ(canopyParams(ctx).composite.exposure, accepted.composite.exposure);
    }
    // The context's size, now and then (the host's targets follow an accepted size).
    if (i % 150 == 149) {
      const uint32_t sizes[] = {0, 1, 17, 48, 64, 16385, 0xffffffffu};
      const uint32_t w = sizes[pick(std::size(sizes))], h = sizes[pick(std::size(sizes))];
      Status r = resizeCanopy(ctx, w, h);
      ++resizes;
      const bool valid = w >= 1 && w <= 16384 && h >= 1 && h <= 16384;
      EXPECT_EQ(r.ok(), valid) << w << "x" << h << ": " << r.message();
      if (!r.ok()) {
        ++resizeRefused;
        EXPECT_TRUE(r.message().find("width") != std::string::npos || r.message().find("height") != std::string::npos) << r.message();
      } else if (w != host.w || h != host.h) {
        ASSERT_TRUE(host.finish().ok());
        host.destroy();
        host = Host();
        host.w = w;
        host.h = h;
        ASSERT_TRUE(host.create(dev, 2).ok());
      }
    }
    // The frame's own inputs: mostly sane, sometimes hostile.
    const float dts[] = {1.0f / 30.0f, 1.0f / 30.0f, 1.0f / 60.0f, 0.0f, 1e-40f, kNaN, -1.0f, 11.0f, kInf};
    const float dt = (i % 5 == 4) ? dts[pick(std::size(dts))] : 1.0f / 30.0f;
    const LayerView view = orbitView(model.boundsMin, model.boundsMax, 20.0f + 0.5f * float(i % 40), 10.0f, 40.0f,
                                     float(host.w) / float(host.h), 1.05f);
    CanopyCamera camera = toCamera(view);
    bool badCamera = false;
    if (i % 37 == 36) {
      badCamera = true;
      const float bad[] = {kNaN, kInf, 0.0f};
      const float b = bad[pick(3)];
      if (b == 0.0f) camera.proj = Float4x4{{0}};
      else camera.view.m[pick(16)] = b;
    }
    const bool badDt = !(std::isfinite(dt) && dt >= 0.0f && dt <= 10.0f);
    Status refusal;
    Status fs = host.frame(++number, {ctx}, view, dt, false, &camera, &refusal);
    ASSERT_TRUE(fs.ok()) << fs.message();
    if (badDt || badCamera) {
      EXPECT_FALSE(refusal.ok()) << "dt " << dt << (badCamera ? ", bad camera" : "") << " was accepted";
      if (badDt) {
        ++dtRefused;
        EXPECT_NE(refusal.message().find("dt"), std::string::npos) << refusal.message();
      } else {
        ++cameraRefused;
        EXPECT_NE(refusal.message().find("camera"), std::string::npos) << refusal.message();
      }
    } else {
      EXPECT_TRUE(refusal.ok()) << refusal.message();
    }
    std::vector<glm::vec4> rgba;
    std::vector<float> z;
    ASSERT_TRUE(host.read(&rgba, &z).ok());
    ++checked;
    ASSERT_TRUE(finite(rgba, z)) << "NaN in the frame after " << f.name << " = " << fv << " / " << uv;
  }
  std::printf("  %d frames: %d parameter values applied, %d refused naming the field; dt refused %d, camera refused %d; "
              "%d resizes (%d refused); %d frames read back, no NaN\n",
              frames, applied, refused, dtRefused, cameraRefused, resizes, resizeRefused, checked);
  destroyCanopy(ctx);
  host.destroy();
}
