// The embedding contract (docs/design.md, "Embedding contract"): frames in flight without waits,
// reverse-Z and standard-Z hosts, depth-stencil targets whose stencil Canopy never touches, sRGB
// and HDR colour targets with an exposure factor against the CPU reference, two contexts sharing
// one simulation (and one destroyed while the other renders), and the refusal of a device created
// without Canopy's features. Validation and synchronization validation are on (GpuTest).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include <glm/gtc/packing.hpp>

#include <canopy/canopy_graph.h>

#include "engine/transfer.h"
#include "render/canopy.h"
#include "render/composite_reference.h"
#include "tests/gpu_test.h"
#include "tests/host_device.h"
#include "tools/leaf_cloud.h"

using namespace canopy;
using canopy::test::GpuTest;

namespace {

const glm::vec4 kSky(0.45f, 0.6f, 0.8f, 1.0f);
constexpr uint8_t kStencil = 0x5a;

// A host with its own colour and depth-(stencil) targets and its own command buffers and fences:
// `frames` recorded frames, at most `inFlight` submitted and not yet waited for.
struct Host {
  Device* dev = nullptr;
  uint32_t w = 96, h = 64;
  VkFormat colorFormat = VK_FORMAT_R16G16B16A16_SFLOAT, depthFormat = VK_FORMAT_D32_SFLOAT;
  bool reverse = false;
  Image color, depth;
  VkImageView depthOnly = VK_NULL_HANDLE;  // the depth aspect of a depth-stencil target
  VkCommandPool pool = VK_NULL_HANDLE;
  std::vector<VkCommandBuffer> cmds;
  std::vector<VkFence> fences;
  std::vector<bool> pending;
  bool first = true;  // the targets hold nothing yet (UNDEFINED)
  // Canopy as one pass of the host's graph (<canopy/canopy_graph.h>) instead of recordCanopy.
  bool passGroup = false;

  Status create(Device& d, uint32_t inFlight) {
    dev = &d;
    ImageDesc c;
    c.format = colorFormat;
    c.width = w;
    c.height = h;
    c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    CANOPY_TRY(createImage(d, c, &color, "host colour"));
    c.format = depthFormat;
    c.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
              VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    CANOPY_TRY(createImage(d, c, &depth, "host depth"));
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = depth.image;
    vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
    vi.format = depthFormat;
    vi.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
    CANOPY_VK(vkCreateImageView(d.device, &vi, nullptr, &depthOnly));
    VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pci.queueFamilyIndex = d.queueFamily;
    CANOPY_VK(vkCreateCommandPool(d.device, &pci, nullptr, &pool));
    cmds.resize(inFlight);
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandPool = pool;
    ai.commandBufferCount = inFlight;
    CANOPY_VK(vkAllocateCommandBuffers(d.device, &ai, cmds.data()));
    fences.resize(inFlight);
    pending.assign(inFlight, false);
    for (VkFence& f : fences) {
      VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
      CANOPY_VK(vkCreateFence(d.device, &fci, nullptr, &f));
    }
    return Status();
  }
  void destroy() {
    (void)finish();  // best effort: destroy() runs after failures too
    for (VkFence f : fences) vkDestroyFence(dev->device, f, nullptr);
    if (pool) vkDestroyCommandPool(dev->device, pool, nullptr);
    if (depthOnly) vkDestroyImageView(dev->device, depthOnly, nullptr);
    destroyImage(*dev, color);
    destroyImage(*dev, depth);
  }
  Status wait(size_t slot) {
    if (!pending[slot]) return Status();
    CANOPY_VK(vkWaitForFences(dev->device, 1, &fences[slot], VK_TRUE, UINT64_MAX));
    CANOPY_VK(vkResetFences(dev->device, 1, &fences[slot]));
    pending[slot] = false;
    return Status();
  }
  Status finish() {
    for (size_t i = 0; i < fences.size(); ++i) CANOPY_TRY(wait(i));
    return Status();
  }
  // One host frame: clear colour, depth (far) and stencil, then every context, no wait.
  Status frame(uint64_t number, const std::vector<CanopyContext*>& contexts, const LayerView& view, float dt,
               bool cut = false) {
    const size_t slot = number % cmds.size();
    CANOPY_TRY(wait(slot));
    VkCommandBuffer cmd = cmds[slot];
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    CANOPY_VK(vkBeginCommandBuffer(cmd, &bi));
    const rg::State colorRW = rg::stateOf(rg::Use::ColorAttachmentReadWrite), depthW = rg::stateOf(rg::Use::DepthAttachmentWrite),
                    src = rg::stateOf(rg::Use::TransferSrc), dst = rg::stateOf(rg::Use::TransferDst);
    rg::RenderGraph g;  // the host's own clear, its barriers from a graph too
    const rg::State before = first ? rg::State{} : src;  // as the previous frame left them
    first = false;
    std::vector<CanopyFrameInputs> inputs(contexts.size());
    for (size_t i = 0; i < contexts.size(); ++i) {
      CanopyFrameInputs& in = inputs[i];
      in.frame = makeCanopyFrame(view, dt, number);
      in.frame.cameraCut = cut;
      if (reverse) {
        glm::mat4 mirror(1.0f);  // the same camera as a reverse-Z host writes it
        mirror[2][2] = -1.0f;
        mirror[3][2] = 1.0f;
        in.frame.camera.proj = toFloat4x4(mirror * view.proj);
      }
      const bool last = i + 1 == contexts.size();
      in.color = {color.image, color.view, i ? colorRW : dst, last ? src : colorRW};
      in.depth = {depth.image, depthOnly, i ? depthW : dst, last ? src : depthW};
    }
    const auto c = g.importImage("host colour", descOf(color), before, passGroup ? src : dst);
    const auto d = g.importImage("host depth", descOf(depth), before, passGroup ? src : dst);
    g.addPass("host clear", [&](rg::PassContext& x) {
       VkClearColorValue cv{};
       std::memcpy(cv.float32, &kSky, sizeof kSky);
       const VkImageSubresourceRange cr{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
       const VkImageSubresourceRange dr{aspectOf(depthFormat), 0, 1, 0, 1};
       vkCmdClearColorImage(x.cmd, x.image(c).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &cv, 1, &cr);
       VkClearDepthStencilValue dv{reverse ? 0.0f : 1.0f, kStencil};
       vkCmdClearDepthStencilImage(x.cmd, x.image(d).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &dv, 1, &dr);
       return Status();
     })
        .write(c, rg::Use::TransferDst)
        .write(d, rg::Use::TransferDst);
    for (size_t i = 0; passGroup && i < contexts.size(); ++i) {
      // Each context one pass of the host's graph, declared with the uses Canopy reports.
      std::vector<CanopyTargetUse> uses;
      CANOPY_TRY(canopyPassGroupUses(contexts[i], &uses));
      CanopyContext* ctx = contexts[i];
      const CanopyFrameInputs* in = &inputs[i];
      auto pass = g.addPass("canopy", [ctx, in](rg::PassContext& x) { return recordCanopyPassGroup(ctx, x.cmd, *in); });
      for (const CanopyTargetUse& u : uses) {
        if (u.target == CanopyTarget::Motion) return Status::error("the test host has no motion target");
        pass.access(u.target == CanopyTarget::Color ? c : d, u.state);
      }
    }
    CANOPY_TRY(g.bindImage(c, color));
    CANOPY_TRY(g.bindImage(d, depth));
    CANOPY_TRY(g.compile());
    CANOPY_TRY(g.realize(*dev));  // no transients: nothing to release
    CANOPY_TRY(g.record(cmd));
    for (size_t i = 0; !passGroup && i < contexts.size(); ++i) CANOPY_TRY(recordCanopy(contexts[i], cmd, inputs[i]));
    CANOPY_VK(vkEndCommandBuffer(cmd));
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 1;
    si.pCommandBuffers = &cmd;
    CANOPY_VK(vkQueueSubmit(dev->queue, 1, &si, fences[slot]));
    pending[slot] = true;
    return Status();
  }
  // After finish(): colour as linear float, depth as float, stencil bytes (depth-stencil formats).
  Status read(std::vector<glm::vec4>* rgba, std::vector<float>* z, std::vector<uint8_t>* stencil = nullptr) {
    CANOPY_TRY(finish());
    const rg::State src = rg::stateOf(rg::Use::TransferSrc);
    const size_t n = size_t(w) * h;
    rgba->clear();
    if (colorFormat == VK_FORMAT_R16G16B16A16_SFLOAT) {
      std::vector<uint64_t> half(n);
      CANOPY_TRY(readbackImage(*dev, color, 0, 8, half.data(), src));
      for (uint64_t v : half) rgba->push_back(glm::unpackHalf4x16(v));
    } else if (colorFormat == VK_FORMAT_B10G11R11_UFLOAT_PACK32) {  // no alpha channel: reads as 1
      std::vector<uint32_t> packed(n);
      CANOPY_TRY(readbackImage(*dev, color, 0, 4, packed.data(), src));
      for (uint32_t v : packed) rgba->push_back(glm::vec4(glm::unpackF2x11_1x10(v), 1.0f));
    } else {  // 8-bit sRGB: decoded to linear
      std::vector<uint8_t> b(n * 4);
      CANOPY_TRY(readbackImage(*dev, color, 0, 4, b.data(), src));
      auto lin = [](uint8_t v) {
        const float c = v / 255.0f;
        return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
      };
      for (size_t i = 0; i < n; ++i) rgba->push_back({lin(b[4 * i]), lin(b[4 * i + 1]), lin(b[4 * i + 2]), b[4 * i + 3] / 255.0f});
    }
    Image depthAspect = depth;
    depthAspect.aspect = VK_IMAGE_ASPECT_DEPTH_BIT;
    std::vector<uint32_t> raw(n);
    CANOPY_TRY(readbackImage(*dev, depthAspect, 0, 4, raw.data(), src));
    z->resize(n);
    for (size_t i = 0; i < n; ++i) {
      if (depthFormat == VK_FORMAT_D24_UNORM_S8_UINT) (*z)[i] = float(raw[i] & 0xffffff) / float(0xffffff);
      else std::memcpy(&(*z)[i], &raw[i], 4);
    }
    if (stencil) {
      Image s = depth;
      s.aspect = VK_IMAGE_ASPECT_STENCIL_BIT;
      stencil->resize(n);
      CANOPY_TRY(readbackImage(*dev, s, 0, 1, stencil->data(), src));
    }
    return Status();
  }
};

float maxDiff(const glm::vec4& a, const glm::vec4& b) {
  const glm::vec4 d = glm::abs(a - b);
  return std::max(std::max(d.x, d.y), std::max(d.z, d.w));
}

// Share of pixels whose colour differs by more than `tol` (any channel).
double differing(const std::vector<glm::vec4>& a, const std::vector<glm::vec4>& b, float tol) {
  if (a.empty() || a.size() != b.size()) return 1.0;
  size_t n = 0;
  for (size_t i = 0; i < a.size(); ++i) n += maxDiff(a[i], b[i]) > tol;
  return double(n) / double(a.size());
}

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

  CanopyContext* make(const Host& host, float wind, CanopyContext* share = nullptr, float exposure = 1.0f) {
    CanopyDesc d;
    d.width = host.w;
    d.height = host.h;
    d.colorFormat = host.colorFormat;
    d.depthFormat = host.depthFormat;
    d.depthConvention = host.reverse ? DepthConvention::Reverse : DepthConvention::Standard;
    d.params.simulation.wind.strength = wind;
    d.params.composite.exposure = exposure;
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

}  // namespace
