// The embedding contract (docs/design.md, "Embedding contract"): frames in flight without waits,
// reverse-Z and standard-Z hosts, depth-stencil targets whose stencil Canopy never touches, sRGB
// and HDR colour targets with an exposure factor against the CPU reference, two contexts sharing
// one simulation (and one destroyed while the other renders), and the refusal of a device created
// without Canopy's features. Validation and synchronization validation are on (GpuTest).
#include <gtest/gtest.h>

#include <functional>

#include <cmath>
#include <cstring>

#include <glm/gtc/packing.hpp>

#include <canopy/canopy_graph.h>

#include "engine/transfer.h"
#include "render/canopy.h"
#include "render/composite_reference.h"
#include "tests/gpu_test.h"
#include "tests/host_device.h"
#include "tests/test_host.h"
#include "tools/leaf_cloud.h"
#include "tools/scene_generator.h"

using namespace canopy;
using canopy::test::GpuTest;
using canopy::test::Host;
using canopy::test::differing;
using canopy::test::kSky;
using canopy::test::kStencil;

namespace {

class EmbeddingTest : public GpuTest {
 protected:
  // As a host's device: 3 frames in flight, uploads recorded into the first frame, not submitted.
  void configure(DeviceDesc& d) override {
    d.framesInFlight = 3;
    d.deferUploads = true;
  }
  VegetationModel model = makeLeafCloud(3000, 5, true);
  uint64_t frameNumber = 0;  // the host's counter: never decreases over the whole device
  Device* target = &dev;     // the device render() uses: Canopy's own, or one the test made
  LayerView view = orbitView(model.boundsMin, model.boundsMax, 20.0f, 10.0f, 40.0f, 96.0f / 64.0f, 1.05f);
  // The rigid parts as the layers' still background (the CPU reference composites it), not drawn
  // every frame with the foliage (the default the other tests embed).
  bool stillBackground = false;

  CanopyContext* make(const Host& host, float wind, CanopyContext* share = nullptr, float exposure = 1.0f) {
    CanopyDesc d;
    d.width = host.w;
    d.height = host.h;
    d.colorFormat = host.colorFormat;
    d.depthFormat = host.depthFormat;
    d.depthConvention = host.reverse ? DepthConvention::Reverse : DepthConvention::Standard;
    d.params.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    d.params.simulation.wind.strength = wind;
    d.params.composite.exposure = exposure;
    if (stillBackground) d.params.layers.rigidMotion = RigidMotion::Still;
    d.shareSimulationWith = share;
    CanopyContext* ctx = nullptr;
    Status s = createCanopy(*target, model, d, &ctx);
    EXPECT_TRUE(s.ok()) << s.message();
    return ctx;
  }
  // `frames` frames of one context, with `inFlight` submissions outstanding; the last one read back.
  void render(Host& host, uint32_t inFlight, int frames, std::vector<glm::vec4>* rgba, std::vector<float>* z,
              std::vector<uint8_t>* stencil = nullptr, float exposure = 1.0f, CanopyContext** keep = nullptr) {
    Status made = host.create(*target, inFlight);
    ASSERT_TRUE(made.ok()) << made.message();
    CanopyContext* ctx = make(host, 1.5f, nullptr, exposure);
    ASSERT_NE(ctx, nullptr);
    for (int i = 1; i <= frames; ++i) {
      Status s = host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f);
      ASSERT_TRUE(s.ok()) << s.message();
    }
    Status s = host.read(rgba, z, stencil);
    ASSERT_TRUE(s.ok()) << s.message();
    if (keep) *keep = ctx;
    else destroyCanopy(ctx);
    host.destroy();
  }
};

TEST_F(EmbeddingTest, ThreeFramesInFlightGiveTheImageOfSerialFrames) {
  std::vector<glm::vec4> serial, overlapped;
  std::vector<float> zs, zo;
  Host a, b;
  render(a, 1, 32, &serial, &zs);
  render(b, 3, 32, &overlapped, &zo);
  // Same simulation steps, same view: the frames must agree (golden tolerance: <= 0.5 % of pixels
  // off by more than 3/255).
  EXPECT_LE(differing(serial, overlapped, 3.0f / 255.0f), 0.005);
  size_t vegetation = 0;
  for (float z : zs) vegetation += z < 1.0f;
  EXPECT_GT(vegetation, serial.size() / 20) << "the crown must cover part of the frame";
}

// The host owns the device: the test creates instance and device itself (not Canopy's
// createDevice), with its own validation and synchronization validation reporting into this
// test, and adopts it. 32 frames with 3 in flight must give the image of today's path (Canopy's
// own device, serial frames) within the golden tolerance.
TEST_F(EmbeddingTest, AHostOwnedDeviceWithThreeFramesInFlightGivesTheImageOfCanopysOwnDevice) {
  std::vector<glm::vec4> own, hosted;
  std::vector<float> zo, zh;
  Host a, b;
  render(a, 1, 32, &own, &zo);
  canopy::test::HostDevice hd;
  hd.sink = [this](bool error, const char* id, const char* msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    messages_.push_back({id, msg, error});
  };
  Status s = createHostDevice(3, &hd);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_NE(hd.device, dev.device);
  target = hd.adopted;
  render(b, 3, 32, &hosted, &zh);
  target = &dev;
  destroyHostDevice(hd);
  EXPECT_LE(differing(own, hosted, 3.0f / 255.0f), 0.005);
  size_t off = 0;
  for (size_t i = 0; i < zo.size(); ++i) off += std::abs(zo[i] - zh[i]) > 1e-4f;
  EXPECT_LE(double(off) / double(zo.size()), 0.005);
}

// Canopy as one pass of the host's render graph (<canopy/canopy_graph.h>): the host's graph places
// the barriers into and out of the declared uses; the frame equals recordCanopy's, sync-clean.
TEST_F(EmbeddingTest, APassGroupInTheHostsGraphGivesTheImageOfRecordCanopy) {
  std::vector<glm::vec4> direct, grouped;
  std::vector<float> zd, zg;
  Host a, b;
  b.passGroup = true;
  render(a, 3, 12, &direct, &zd);
  render(b, 3, 12, &grouped, &zg);
  EXPECT_LE(differing(direct, grouped, 3.0f / 255.0f), 0.005);
  size_t vegetation = 0;
  for (float z : zg) vegetation += z < 1.0f;
  EXPECT_GT(vegetation, grouped.size() / 20);

  Host h;
  CanopyContext* ctx = make(h, 1.0f);
  ASSERT_NE(ctx, nullptr);
  std::vector<CanopyTargetUse> uses;
  ASSERT_TRUE(canopyPassGroupUses(ctx, &uses).ok());
  ASSERT_EQ(uses.size(), 2u);  // colour and depth; no motion target
  EXPECT_EQ(uses[0].target, CanopyTarget::Color);
  EXPECT_EQ(uses[0].state.layout, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL);
  EXPECT_TRUE(uses[1].writes);
  EXPECT_TRUE(uses[1].state.stage & VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT) << "the scene depth is sampled by compute";
  destroyCanopy(ctx);
}

// A host rendering into its swapchain images hands Canopy a different target each frame: the
// compiled graphs are kept per set of images, so three images cost three builds, not one a frame.
TEST_F(EmbeddingTest, CyclingThroughThreeTargetsBuildsThreeGraphs) {
  Host hosts[3];
  for (Host& h : hosts) ASSERT_TRUE(h.create(dev, 1).ok());
  CanopyContext* ctx = make(hosts[0], 1.0f);
  ASSERT_NE(ctx, nullptr);
  for (int i = 0; i < 12; ++i) {
    Status s = hosts[i % 3].frame(++frameNumber, {ctx}, view, 1.0f / 30.0f);
    ASSERT_TRUE(s.ok()) << s.message();
  }
  EXPECT_EQ(canopyStats(ctx).internalGraphBuilds, 3u);
  std::vector<glm::vec4> last;
  std::vector<float> z;
  ASSERT_TRUE(hosts[2].read(&last, &z).ok());
  size_t vegetation = 0;
  for (float d : z) vegetation += d < 1.0f;
  EXPECT_GT(vegetation, z.size() / 20);
  for (Host& h : hosts) ASSERT_TRUE(h.finish().ok());
  destroyCanopy(ctx);
  for (Host& h : hosts) h.destroy();
}

TEST_F(EmbeddingTest, ReverseZAndStandardZGiveTheSameCompositeAndMirroredDepth) {
  std::vector<glm::vec4> cs, cr;
  std::vector<float> zs, zr;
  Host standard, reverse;
  reverse.reverse = true;
  render(standard, 2, 6, &cs, &zs);
  render(reverse, 2, 6, &cr, &zr);
  EXPECT_LE(differing(cs, cr, 3.0f / 255.0f), 0.005);
  size_t mirrored = 0, vegetation = 0;
  for (size_t i = 0; i < zs.size(); ++i) {
    vegetation += zs[i] < 1.0f;
    mirrored += std::abs((1.0f - zr[i]) - zs[i]) <= 1e-5f;
  }
  EXPECT_GT(vegetation, zs.size() / 20);
  EXPECT_GE(double(mirrored) / zs.size(), 0.995) << "reverse depth = 1 - standard depth";
}

TEST_F(EmbeddingTest, DepthStencilTargetsKeepTheirStencil) {
  for (VkFormat f : {VK_FORMAT_D24_UNORM_S8_UINT, VK_FORMAT_D32_SFLOAT_S8_UINT}) {
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(dev.physical, f, &fp);
    const VkFormatFeatureFlags need = VK_FORMAT_FEATURE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT;
    if ((fp.optimalTilingFeatures & need) != need) {
      std::printf("format %d is not a sampled depth-stencil attachment on this device; not tested\n", int(f));
      continue;
    }
    std::vector<glm::vec4> c, ref;
    std::vector<float> z, zref;
    std::vector<uint8_t> stencil;
    Host host, plain;
    host.depthFormat = f;
    render(host, 2, 6, &c, &z, &stencil);
    render(plain, 2, 6, &ref, &zref);
    size_t kept = 0;
    for (uint8_t s : stencil) kept += s == kStencil;
    EXPECT_EQ(kept, stencil.size()) << "format " << int(f) << ": Canopy changed the stencil";
    EXPECT_LE(differing(c, ref, 3.0f / 255.0f), 0.005) << "format " << int(f);
    size_t vegetation = 0, agree = 0;
    for (size_t i = 0; i < z.size(); ++i) {
      vegetation += zref[i] < 1.0f;
      agree += std::abs(z[i] - zref[i]) <= 1e-4f;
    }
    EXPECT_GT(vegetation, z.size() / 20);
    EXPECT_GE(double(agree) / z.size(), 0.995) << "format " << int(f);
  }
}

// The GPU frame against the CPU reference of the same frame, for HDR targets (RGBA16F and
// B10G11R11) with exposure 2 and an sRGB target (whose encoding the hardware applies on write).
TEST_F(EmbeddingTest, HdrWithExposureAndSrgbTargetsMatchTheCpuReference) {
  stillBackground = true;
  for (VkFormat f : {VK_FORMAT_R16G16B16A16_SFLOAT, VK_FORMAT_R8G8B8A8_SRGB, VK_FORMAT_B10G11R11_UFLOAT_PACK32}) {
    const bool packed = f == VK_FORMAT_B10G11R11_UFLOAT_PACK32;
    const float exposure = f == VK_FORMAT_R8G8B8A8_SRGB ? 1.0f : 2.0f;
    VkFormatProperties fp;
    vkGetPhysicalDeviceFormatProperties(dev.physical, f, &fp);
    const VkFormatFeatureFlags blend = VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BIT | VK_FORMAT_FEATURE_COLOR_ATTACHMENT_BLEND_BIT;
    if ((fp.optimalTilingFeatures & blend) != blend) {
      std::printf("format %d is not a blendable colour attachment on this device; not tested\n", int(f));
      continue;
    }
    Host host;
    host.colorFormat = f;
    std::vector<glm::vec4> c;
    std::vector<float> z;
    CanopyContext* ctx = nullptr;
    render(host, 2, 8, &c, &z, nullptr, exposure, &ctx);
    ASSERT_NE(ctx, nullptr);
    LayeredVegetation& lv = canopyLayers(ctx);
    const gpu::CompositePush push = canopyCompositor(ctx).push;
    EXPECT_EQ(push.exposure, exposure);
    CompositeReferenceInputs in;
    in.width = host.w;
    in.height = host.h;
    in.layers = push.layerCount;
    in.layerWidth = lv.desc.width;  // the guard band included
    in.layerHeight = lv.desc.height;
    for (uint32_t l = 0; l < in.layers; ++l) {
      std::vector<glm::vec4> lc;
      std::vector<float> lz;
      ASSERT_TRUE(readLayerColor(lv, l, &lc).ok());
      ASSERT_TRUE(readLayerDepth(lv, l, &lz).ok());
      in.layerColor.insert(in.layerColor.end(), lc.begin(), lc.end());
      in.layerDepth.insert(in.layerDepth.end(), lz.begin(), lz.end());
    }
    ASSERT_TRUE(readBackground(lv, &in.backgroundColor, &in.backgroundDepth).ok());
    in.sceneColor.assign(size_t(host.w) * host.h, kSky);
    in.sceneDepth.assign(size_t(host.w) * host.h, 1.0f);
    LayerDynamics& dyn = canopyDynamics(ctx);
    const size_t count = size_t(push.gridX) * push.gridY * push.layerCount;
    in.displacement.resize(count);
    in.previous.resize(count);
    const rg::State read = rg::stateOf(rg::Use::ComputeStorageRead);
    ASSERT_TRUE(readbackBuffer(dev, dyn.displacement, in.displacement.data(), count * 8, read).ok());
    ASSERT_TRUE(readbackBuffer(dev, dyn.previous, in.previous.data(), count * 8, read).ok());
    CompositeReferenceOutputs ref;
    compositeReference(push, in, &ref);
    // RGBA16F: half-float rounding; sRGB: 8-bit encoding (1/255 in sRGB is up to ~0.013 linear in
    // the brights); B10G11R11: 5-6 mantissa bits (~3 % of the value, values up to ~2 with exposure 2),
    // and no alpha channel, so only colour is compared.
    const float tol = f == VK_FORMAT_R16G16B16A16_SFLOAT ? 3.0f / 255.0f : packed ? 0.06f : 0.02f;
    if (packed)
      for (size_t i = 0; i < c.size(); ++i) c[i].a = ref.color[i].a;
    EXPECT_LE(differing(c, ref.color, tol), 0.005) << "format " << int(f);
    size_t brighter = 0;
    for (size_t i = 0; i < c.size(); ++i) brighter += ref.vegetationFront[i] && c[i].g > kSky.g;
    if (exposure > 1.0f) EXPECT_GT(brighter, 0u) << "exposure 2 should brighten some leaves above the sky";
    destroyCanopy(ctx);
  }
}

TEST_F(EmbeddingTest, TwoContextsShareOneSimulationAndOneIsDestroyedWhileTheOtherRenders) {
  Host host;
  ASSERT_TRUE(host.create(dev, 3).ok());
  CanopyContext* a = make(host, 1.5f);
  CanopyContext* b = make(host, 1.5f, a);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(&canopySimulation(a), &canopySimulation(b));
  for (int i = 0; i < 10; ++i) {
    Status s = host.frame(++frameNumber, {a, b}, view, 1.0f / 30.0f);
    ASSERT_TRUE(s.ok()) << s.message();
  }
  // One wind over the scene: one step per host frame, not one per context.
  EXPECT_EQ(canopyStats(a).simulation.steps, 10u);
  EXPECT_EQ(canopyStats(b).simulation.steps, 10u);
  // Destroyed while its frames may still execute: its objects wait for them.
  destroyCanopy(a);
  EXPECT_GT(canopyStats(b).pendingReleases, 0u);
  for (int i = 0; i < 6; ++i) {
    Status s = host.frame(++frameNumber, {b}, view, 1.0f / 30.0f);
    ASSERT_TRUE(s.ok()) << s.message();
  }
  EXPECT_EQ(canopyStats(b).simulation.steps, 16u) << "the shared simulation outlives the context that created it";
  EXPECT_EQ(canopyStats(b).pendingReleases, 0u) << "released framesInFlight frames later";
  std::vector<glm::vec4> c;
  std::vector<float> z;
  ASSERT_TRUE(host.read(&c, &z).ok());
  size_t vegetation = 0;
  for (float v : z) vegetation += v < 1.0f;
  EXPECT_GT(vegetation, z.size() / 20);
  destroyCanopy(b);
  host.destroy();
}

TEST_F(EmbeddingTest, ADeviceWithoutTheRequiredFeaturesIsRefusedNamingThem) {
  // The same VkDevice, described as if created with no features and no extensions.
  VkDeviceCreateInfo bare{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
  AdoptDeviceDesc ad;
  ad.getInstanceProcAddr = vkGetInstanceProcAddr;
  ad.instance = dev.instance;
  ad.physicalDevice = dev.physical;
  ad.device = dev.device;
  ad.deviceCreateInfo = &bare;
  ad.queue = dev.queue;
  ad.queueFamily = dev.queueFamily;
  Device* adopted = nullptr;
  Status s = adoptDevice(ad, &adopted);
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(adopted, nullptr);
  EXPECT_EQ(s.code(), Result::UnsupportedDevice);
  for (const char* what : {"VK_KHR_push_descriptor", "scalarBlockLayout", "synchronization2", "dynamicRendering"})
    EXPECT_NE(s.message().find(what), std::string::npos) << what << " not named in: " << s.message();
  ad.framesInFlight = 4;
  s = adoptDevice(ad, &adopted);
  EXPECT_NE(s.message().find("framesInFlight = 4 is outside [1, 3]"), std::string::npos) << s.message();
}

}  // namespace

namespace {

TEST_F(EmbeddingTest, ACameraCutReslicesAtOnceAndDropsMotionVectors) {
  Host host;
  ASSERT_TRUE(host.create(dev, 2).ok());
  CanopyContext* ctx = make(host, 1.5f);
  ASSERT_NE(ctx, nullptr);
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok());
  EXPECT_FALSE(canopyStats(ctx).layersRebuilt) << "a still camera does not re-slice";
  EXPECT_NE(canopyCompositor(ctx).push.flags & COMPOSITE_MOTION_VALID, 0u);
  const uint64_t rebuilds = canopyStats(ctx).layers.rebuilds;
  // The same view, flagged as a cut: re-sliced now, no motion across it.
  ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f, true).ok());
  EXPECT_TRUE(canopyStats(ctx).layersRebuilt);
  EXPECT_EQ(canopyStats(ctx).layers.rebuilds, rebuilds + 1);
  EXPECT_EQ(canopyStats(ctx).layers.lastRebuildReason, "camera cut");
  EXPECT_EQ(canopyCompositor(ctx).push.flags & COMPOSITE_MOTION_VALID, 0u);
  // The next frame is ordinary again.
  ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok());
  EXPECT_FALSE(canopyStats(ctx).layersRebuilt);
  EXPECT_NE(canopyCompositor(ctx).push.flags & COMPOSITE_MOTION_VALID, 0u);
  ASSERT_TRUE(host.finish().ok());
  destroyCanopy(ctx);
  host.destroy();
}

// Embeds `model` three ways — serial frames, three frames in flight, one pass of the host's graph
// — on `target` with the description `configure` completes; `check` looks at each context after
// its 12 frames; the three images must agree and cover the sky.
void expectSameFramesThreeWays(Device& target, const VegetationModel& model, const LayerView& view, uint64_t& frameNumber,
                               const std::function<void(CanopyDesc&)>& configure,
                               const std::function<void(CanopyContext*)>& check) {
  std::vector<glm::vec4> images[3];
  std::vector<float> z;
  for (int variant = 0; variant < 3; ++variant) {
    SCOPED_TRACE(variant);
    Host host;
    host.passGroup = variant == 2;
    ASSERT_TRUE(host.create(target, variant == 0 ? 1 : 3).ok());
    CanopyDesc d;
    d.width = host.w;
    d.height = host.h;
    d.colorFormat = host.colorFormat;
    d.depthFormat = host.depthFormat;
    d.params.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    d.params.simulation.wind.strength = 2.0f;
    configure(d);
    CanopyContext* ctx = nullptr;
    Status s = createCanopy(target, model, d, &ctx);
    ASSERT_TRUE(s.ok()) << s.message();
    for (int i = 0; i < 12 && s.ok(); ++i) s = host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f);
    if (s.ok()) s = host.read(&images[variant], &z);
    EXPECT_TRUE(s.ok()) << s.message();
    check(ctx);
    destroyCanopy(ctx);
    host.destroy();
  }
  EXPECT_LE(differing(images[0], images[1], 3.0f / 255.0f), 0.005);
  EXPECT_LE(differing(images[0], images[2], 3.0f / 255.0f), 0.005);
  EXPECT_GT(differing(images[0], std::vector<glm::vec4>(images[0].size(), kSky), 0.05f), 0.05) << "the tree is drawn";
}

}  // namespace

// The per-vertex baseline embedded like the 2D method: on a device that records its uploads into
// the host's first frame (the branch table and motion table then share a command buffer with their
// readers), with three frames in flight and as one pass of the host's graph, sync-validation clean,
// each giving the image of serial frames.
TEST_F(EmbeddingTest, ThePerVertexBaselineEmbedsLikeThe2DMethod) {
  SceneDesc sd;
  sd.kind = SceneKind::TreeCrown;
  sd.faces = 6000;
  sd.hierarchy = true;
  sd.threads = 1;
  ASSERT_TRUE(generateScene(sd, &model).ok());
  view = orbitView(model.boundsMin, model.boundsMax, 20.0f, 10.0f, 40.0f, 96.0f / 64.0f, 1.05f);
  expectSameFramesThreeWays(
      *target, model, view, frameNumber,
      [](CanopyDesc& d) {
        d.allowPerVertex = true;
        d.params.animation = AnimationMode::PerVertex;
      },
      [](CanopyContext*) {});
}

// Impostors (issue 18) on a host's device: the bake is prepared work like the uploads (recorded
// into the host's first frame where it defers them), and the impostors' atlas, box table and list
// are declared to the graph, so serial, three frames in flight and the host's graph agree.
TEST_F(EmbeddingTest, ImpostorsEmbedLikeTheLayers) {
  SceneDesc sd;
  sd.kind = SceneKind::TreeCrown;
  sd.faces = 6000;
  sd.boxes = true;
  sd.threads = 1;
  ASSERT_TRUE(generateScene(sd, &model).ok());
  view = orbitView(model.boundsMin, model.boundsMax, 20.0f, 10.0f, 40.0f, 96.0f / 64.0f, 1.05f);
  expectSameFramesThreeWays(
      *target, model, view, frameNumber,
      [](CanopyDesc& d) {
        d.impostors.enable = true;
        d.params.layers.impostors.mode = ImpostorMode::ByProjectedSize;
        d.params.layers.impostors.switchPixels = 4096.0f;  // every box with views is an impostor
      },
      [](CanopyContext* ctx) {
        const CanopyStats st = canopyStats(ctx);
        EXPECT_GT(st.layers.lastImpostors, 0u);
        EXPECT_EQ(st.layers.lastDrawnTriangles, 0u) << "the tree is drawn as impostors only";
      });
}
