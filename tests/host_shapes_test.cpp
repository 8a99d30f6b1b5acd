// Hosts of the shapes that exist (issue 78; docs/embedding.md "12. Host shapes"): a classic VkRenderPass
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
#include <functional>

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

// A host's TAA jitter: each call the next frame's Halton (2, 3) point of 8 (*frame counts them).
std::function<void(CanopyCamera&)> haltonJitter(uint32_t* frame) {
  return [frame](CanopyCamera& c) {
    const glm::vec2 j = halton23((*frame)++ % 8);
    c.jitter[0] = j.x;
    c.jitter[1] = j.y;
  };
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
  host.adjustCamera = haltonJitter(&k);
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
      if (jittered) host.adjustCamera = haltonJitter(&k);
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

namespace {

// ---------------------------------------------------------------------------------------------
// A classic VkRenderPass host that pre-records (vkcube's shape; docs/embedding.md "12. Host shapes")

// Two "swapchain" images (colour ends each scene pass in PRESENT_SRC_KHR), one depth image, the
// scene pass pre-recorded once per image; Canopy recorded each frame into one of two per-frame
// command buffers (a resettable pool) and submitted after the image's scene pass in one submit.
struct RenderPassHost {
  Device* dev = nullptr;
  uint32_t w = 96, h = 64;
  VkFormat colorFormat = VK_FORMAT_R8G8B8A8_SRGB, depthFormat = VK_FORMAT_D32_SFLOAT;
  Image colors[2], depth;
  VkRenderPass pass = VK_NULL_HANDLE;
  VkFramebuffer framebuffers[2] = {};
  VkCommandPool scenePool = VK_NULL_HANDLE, framePool = VK_NULL_HANDLE;
  VkCommandBuffer scene[2] = {}, frame[2] = {};
  VkFence fences[2] = {};
  bool pending[2] = {false, false};
  // What the scene pass's outgoing dependency makes available, and the state Canopy gets as `current`.
  static constexpr canopy::ResourceState kColorAfterPass{VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                                                         VK_IMAGE_LAYOUT_PRESENT_SRC_KHR};
  static constexpr canopy::ResourceState kDepthAfterPass{VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT,
                                                         VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                                                         VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
  // Canopy leaves colour ready to present; the next scene pass waits for it at colour output (a
  // real host's acquire semaphore waits there too).
  static constexpr canopy::ResourceState kColorToPresent{VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_NONE,
                                                         VK_IMAGE_LAYOUT_PRESENT_SRC_KHR};

  Status create(Device& d) {
    dev = &d;
    ImageDesc c;
    c.width = w;
    c.height = h;
    c.format = colorFormat;
    c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    for (Image& i : colors) CANOPY_TRY(createImage(d, c, &i, "swapchain image"));
    c.format = depthFormat;
    c.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
    CANOPY_TRY(createImage(d, c, &depth, "host depth"));
    VkAttachmentDescription at[2] = {};
    at[0].format = colorFormat;
    at[0].samples = VK_SAMPLE_COUNT_1_BIT;
    at[0].loadOp = VK_ATTACHMENT_LOAD_OP_CLEAR;
    at[0].storeOp = VK_ATTACHMENT_STORE_OP_STORE;
    at[0].stencilLoadOp = VK_ATTACHMENT_LOAD_OP_DONT_CARE;
    at[0].stencilStoreOp = VK_ATTACHMENT_STORE_OP_DONT_CARE;
    at[0].initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
    at[0].finalLayout = VK_IMAGE_LAYOUT_PRESENT_SRC_KHR;
    at[1] = at[0];
    at[1].format = depthFormat;
    at[1].storeOp = VK_ATTACHMENT_STORE_OP_STORE;  // Canopy reads it: DONT_CARE would leave garbage on a tiler
    at[1].finalLayout = VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL;
    const VkAttachmentReference cref{0, VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL}, dref{1, VK_IMAGE_LAYOUT_DEPTH_STENCIL_ATTACHMENT_OPTIMAL};
    VkSubpassDescription sub{};
    sub.pipelineBindPoint = VK_PIPELINE_BIND_POINT_GRAPHICS;
    sub.colorAttachmentCount = 1;
    sub.pColorAttachments = &cref;
    sub.pDepthStencilAttachment = &dref;
    VkSubpassDependency deps[2] = {};
    // In: the previous frame's Canopy (depth written at the fragment tests; colour handed on at
    // colour output, kColorToPresent) before this pass clears them.
    deps[0].srcSubpass = VK_SUBPASS_EXTERNAL;
    deps[0].dstSubpass = 0;
    deps[0].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    deps[0].srcAccessMask = VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    deps[0].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_EARLY_FRAGMENT_TESTS_BIT |
                           VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    deps[0].dstAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT |
                            VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_READ_BIT;
    // Out: the pass's writes and final layouts made available at the stages Canopy's `current` names
    // (without it the implicit dependency ends at BOTTOM_OF_PIPE and nothing chains to Canopy).
    deps[1].srcSubpass = 0;
    deps[1].dstSubpass = VK_SUBPASS_EXTERNAL;
    deps[1].srcStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    deps[1].srcAccessMask = VK_ACCESS_COLOR_ATTACHMENT_WRITE_BIT | VK_ACCESS_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT;
    deps[1].dstStageMask = VK_PIPELINE_STAGE_COLOR_ATTACHMENT_OUTPUT_BIT | VK_PIPELINE_STAGE_LATE_FRAGMENT_TESTS_BIT;
    deps[1].dstAccessMask = 0;
    VkRenderPassCreateInfo rp{VK_STRUCTURE_TYPE_RENDER_PASS_CREATE_INFO};
    rp.attachmentCount = 2;
    rp.pAttachments = at;
    rp.subpassCount = 1;
    rp.pSubpasses = &sub;
    rp.dependencyCount = 2;
    rp.pDependencies = deps;
    CANOPY_VK(vkCreateRenderPass(d.device, &rp, nullptr, &pass));
    VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pci.queueFamilyIndex = d.queueFamily;
    CANOPY_VK(vkCreateCommandPool(d.device, &pci, nullptr, &scenePool));  // recorded once: never reset
    pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    CANOPY_VK(vkCreateCommandPool(d.device, &pci, nullptr, &framePool));  // Canopy's: re-recorded each frame
    VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
    ai.commandBufferCount = 2;
    ai.commandPool = scenePool;
    CANOPY_VK(vkAllocateCommandBuffers(d.device, &ai, scene));
    ai.commandPool = framePool;
    CANOPY_VK(vkAllocateCommandBuffers(d.device, &ai, frame));
    for (int i = 0; i < 2; ++i) {
      const VkImageView views[2] = {colors[i].view, depth.view};
      VkFramebufferCreateInfo fb{VK_STRUCTURE_TYPE_FRAMEBUFFER_CREATE_INFO};
      fb.renderPass = pass;
      fb.attachmentCount = 2;
      fb.pAttachments = views;
      fb.width = w;
      fb.height = h;
      fb.layers = 1;
      CANOPY_VK(vkCreateFramebuffer(d.device, &fb, nullptr, &framebuffers[i]));
      VkFenceCreateInfo fci{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
      CANOPY_VK(vkCreateFence(d.device, &fci, nullptr, &fences[i]));
      // The scene pass, pre-recorded once per image (the host's opaque scene would be drawn here).
      VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
      bi.flags = VK_COMMAND_BUFFER_USAGE_SIMULTANEOUS_USE_BIT;
      CANOPY_VK(vkBeginCommandBuffer(scene[i], &bi));
      VkClearValue clears[2] = {};
      std::memcpy(clears[0].color.float32, &kSky, sizeof kSky);
      clears[1].depthStencil = {1.0f, 0};
      VkRenderPassBeginInfo rb{VK_STRUCTURE_TYPE_RENDER_PASS_BEGIN_INFO};
      rb.renderPass = pass;
      rb.framebuffer = framebuffers[i];
      rb.renderArea = {{0, 0}, {w, h}};
      rb.clearValueCount = 2;
      rb.pClearValues = clears;
      vkCmdBeginRenderPass(scene[i], &rb, VK_SUBPASS_CONTENTS_INLINE);
      vkCmdEndRenderPass(scene[i]);
      CANOPY_VK(vkEndCommandBuffer(scene[i]));
    }
    return Status();
  }
  // Host frame `number` into image number % 2: Canopy recorded into frame buffer number % 2 (waited
  // for first), submitted after the pre-recorded scene pass.
  Status render(uint64_t number, CanopyContext* ctx, const LayerView& view, float dt) {
    const size_t slot = number % 2;
    if (pending[slot]) {
      CANOPY_VK(vkWaitForFences(dev->device, 1, &fences[slot], VK_TRUE, UINT64_MAX));
      CANOPY_VK(vkResetFences(dev->device, 1, &fences[slot]));
      pending[slot] = false;
    }
    CANOPY_VK(vkResetCommandBuffer(frame[slot], 0));
    VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
    bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
    CANOPY_VK(vkBeginCommandBuffer(frame[slot], &bi));
    CanopyFrameInputs in;
    in.frame = makeCanopyFrame(view, dt, number);
    in.color = canopyImage(colors[slot].image, colors[slot].view, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                           colorFormat, kColorAfterPass, kColorToPresent);
    in.depth = canopyImage(depth.image, depth.view, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, depthFormat,
                           kDepthAfterPass, kDepthAfterPass);
    CANOPY_TRY(recordCanopy(ctx, frame[slot], in));
    CANOPY_VK(vkEndCommandBuffer(frame[slot]));
    const VkCommandBuffer both[2] = {scene[slot], frame[slot]};
    VkSubmitInfo si{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    si.commandBufferCount = 2;
    si.pCommandBuffers = both;
    CANOPY_VK(vkQueueSubmit(dev->queue, 1, &si, fences[slot]));
    pending[slot] = true;
    return Status();
  }
  Status finish() {
    for (int i = 0; i < 2; ++i)
      if (pending[i]) {
        CANOPY_VK(vkWaitForFences(dev->device, 1, &fences[i], VK_TRUE, UINT64_MAX));
        CANOPY_VK(vkResetFences(dev->device, 1, &fences[i]));
        pending[i] = false;
      }
    return Status();
  }
  // Image `i` as linear colour (sRGB decoded), as the presentation engine would get it.
  Status read(int i, std::vector<glm::vec4>* rgba) {
    CANOPY_TRY(finish());
    std::vector<uint8_t> b(size_t(w) * h * 4);
    CANOPY_TRY(readbackImage(*dev, colors[i], 0, 4, b.data(), kColorToPresent));
    auto lin = [](uint8_t v) {
      const float c = v / 255.0f;
      return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
    };
    rgba->clear();
    for (size_t p = 0; p < size_t(w) * h; ++p) rgba->push_back({lin(b[4 * p]), lin(b[4 * p + 1]), lin(b[4 * p + 2]), b[4 * p + 3] / 255.0f});
    return Status();
  }
  void destroy() {
    (void)finish();
    for (int i = 0; i < 2; ++i) {
      if (fences[i]) vkDestroyFence(dev->device, fences[i], nullptr);
      if (framebuffers[i]) vkDestroyFramebuffer(dev->device, framebuffers[i], nullptr);
      destroyImage(*dev, colors[i]);
    }
    if (scenePool) vkDestroyCommandPool(dev->device, scenePool, nullptr);
    if (framePool) vkDestroyCommandPool(dev->device, framePool, nullptr);
    if (pass) vkDestroyRenderPass(dev->device, pass, nullptr);
    destroyImage(*dev, depth);
  }
};

// 12 frames of the render-pass host give the image of the test host (dynamic rendering, recorded
// frames) at the same frames; validation and synchronization validation report nothing.
TEST_F(HostShapesTest, AClassicRenderPassHostThatPreRecordsShowsWhatTheDynamicHostShows) {
  const LayerView view = orbit(20.0f, 96.0f / 64.0f);
  Host reference;
  reference.colorFormat = VK_FORMAT_R8G8B8A8_SRGB;
  std::vector<glm::vec4> expected, got;
  std::vector<float> z;
  render(reference, view, 12, 1.5f, &expected, &z);
  RenderPassHost host;
  Status s = host.create(dev);
  ASSERT_TRUE(s.ok()) << s.message();
  CanopyDesc d;
  d.width = host.w;
  d.height = host.h;
  d.colorFormat = host.colorFormat;
  d.depthFormat = host.depthFormat;
  d.params.windMode = WindMode::PlaneSides;
  d.params.simulation.wind.strength = 1.5f;
  CanopyContext* ctx = nullptr;
  s = createCanopy(dev, model, d, &ctx);
  ASSERT_TRUE(s.ok()) << s.message();
  for (int i = 0; i < 12; ++i) {
    s = host.render(++frameNumber, ctx, view, 1.0f / 30.0f);
    ASSERT_TRUE(s.ok()) << s.message();
  }
  s = host.read(int(frameNumber % 2), &got);
  ASSERT_TRUE(s.ok()) << s.message();
  const Coverage cov = coverageOf(got, host.w);
  const double d3 = differing(got, expected, 3.0f / 255.0f);
  std::printf("render-pass host: %.4f of the pixels differ from the dynamic host's; coverage %.0f px\n", d3, cov.pixels);
  EXPECT_GT(cov.pixels, 0.05 * got.size());
  EXPECT_LE(d3, 0.002);
  destroyCanopy(ctx);
  host.destroy();
}

}  // namespace

namespace {

// ---------------------------------------------------------------------------------------------
// A host with a plain TAA resolve (docs/performance.md "Temporal anti-aliasing")

// The resolve a host runs after Canopy, on the CPU here: the history fetched where the motion
// vector says the pixel was (bilinear), clamped to the current frame's 3x3 neighbourhood (unless
// `clamp` is off), blended with the current frame by `alpha`.
struct TaaResolve {
  uint32_t w = 0, h = 0;
  float alpha = 0.1f;
  bool clamp = true, useMotion = true;
  std::vector<glm::vec3> history;
  void add(const std::vector<glm::vec4>& c, const std::vector<glm::vec2>& motion) {
    if (history.empty()) {
      for (const glm::vec4& v : c) history.push_back(glm::vec3(v));
      return;
    }
    auto at = [&](const std::vector<glm::vec3>& img, int x, int y) {
      return img[size_t(std::clamp(y, 0, int(h) - 1)) * w + size_t(std::clamp(x, 0, int(w) - 1))];
    };
    std::vector<glm::vec3> next(history.size());
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        const size_t i = size_t(y) * w + x;
        const glm::vec2 m = useMotion && !motion.empty() ? motion[i] : glm::vec2(0.0f);
        const glm::vec2 q = glm::vec2(float(x), float(y)) - m;  // where the pixel's surface was
        const int x0 = int(std::floor(q.x)), y0 = int(std::floor(q.y));
        const float fx = q.x - float(x0), fy = q.y - float(y0);
        glm::vec3 hist = glm::mix(glm::mix(at(history, x0, y0), at(history, x0 + 1, y0), fx),
                                  glm::mix(at(history, x0, y0 + 1), at(history, x0 + 1, y0 + 1), fx), fy);
        if (clamp) {
          glm::vec3 lo(1e30f), hi(-1e30f);
          for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
              const glm::vec4 n = c[size_t(std::clamp(int(y) + dy, 0, int(h) - 1)) * w + size_t(std::clamp(int(x) + dx, 0, int(w) - 1))];
              lo = glm::min(lo, glm::vec3(n));
              hi = glm::max(hi, glm::vec3(n));
            }
          hist = glm::clamp(hist, lo, hi);
        }
        next[i] = glm::mix(hist, glm::vec3(c[i]), alpha);
      }
    history = std::move(next);
  }
};

float diff3(const glm::vec3& a, const glm::vec3& b) {
  const glm::vec3 d = glm::abs(a - b);
  return std::max(d.x, std::max(d.y, d.z));
}

// A still camera jittered by Halton (2, 3) over 8 frames: the resolved leaf edges come near a 4x4
// supersampled frame of the same camera, nearer than one unjittered frame; a crown swaying in a
// strong wind leaves no trail wider than 1 px behind its leaves.
TEST_F(HostShapesTest, ATaaHostConvergesOnTheLeafEdgesAndLeavesNoTrail) {
  const uint32_t w = 96, h = 64, S = 4;
  const LayerView view = orbit(20.0f, float(w) / float(h));
  // The reference: the same camera at 4x4 the pixels, box-filtered.
  std::vector<glm::vec4> big;
  std::vector<float> z;
  Host ss;
  ss.w = w * S;
  ss.h = h * S;
  render(ss, view, 3, 0.0f, &big, &z);
  std::vector<glm::vec3> reference(size_t(w) * h, glm::vec3(0.0f));
  for (uint32_t y = 0; y < h * S; ++y)
    for (uint32_t x = 0; x < w * S; ++x) reference[size_t(y / S) * w + x / S] += glm::vec3(big[size_t(y) * w * S + x]) / float(S * S);
  // Leaf edges: pixels whose reference neighbourhood spans more than 0.1.
  std::vector<size_t> edges;
  for (uint32_t y = 1; y + 1 < h; ++y)
    for (uint32_t x = 1; x + 1 < w; ++x) {
      glm::vec3 lo(1e30f), hi(-1e30f);
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const glm::vec3 r = reference[size_t(int(y) + dy) * w + size_t(int(x) + dx)];
          lo = glm::min(lo, r);
          hi = glm::max(hi, r);
        }
      if (diff3(hi, lo) > 0.1f) edges.push_back(size_t(y) * w + x);
    }
  ASSERT_GT(edges.size(), 100u);
  auto edgeError = [&](const std::vector<glm::vec3>& img) {
    double e = 0;
    for (size_t i : edges) e += diff3(img[i], reference[i]);
    return e / double(edges.size());
  };
  // Still, no wind: 32 jittered frames through the resolve; one unjittered frame beside it.
  std::vector<glm::vec3> single;
  double converged = 0, aliased = 0;
  {
    Host host;
    host.motion = true;
    ASSERT_TRUE(host.create(dev, 1).ok());
    CanopyContext* ctx = make(host, 0.0f, VK_FORMAT_R16G16_SFLOAT);
    ASSERT_NE(ctx, nullptr);
    TaaResolve taa{w, h};
    std::vector<glm::vec4> c;
    std::vector<glm::vec2> m;
    for (uint32_t k = 0; k <= 32; ++k) {
      host.adjustCamera = [k](CanopyCamera& cam) {
        const glm::vec2 j = k < 32 ? halton23(k % 8) : glm::vec2(0.0f);  // the last frame unjittered
        cam.jitter[0] = j.x;
        cam.jitter[1] = j.y;
      };
      ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok());
      ASSERT_TRUE(host.read(&c, &z).ok());
      ASSERT_TRUE(host.readMotion(&m).ok());
      if (k < 32) taa.add(c, m);
    }
    for (const glm::vec4& v : c) single.push_back(glm::vec3(v));
    converged = edgeError(taa.history);
    aliased = edgeError(single);
    destroyCanopy(ctx);
    host.destroy();
  }
  // Swaying (a strong wind), still camera: the trail is the resolve's foliage where the current
  // frame shows sky; its width the farthest such pixel from the current foliage (Chebyshev).
  struct Variant {
    const char* name;
    bool clamp, useMotion;
  };
  const Variant variants[] = {{"clamped, motion vectors", true, true}, {"clamped, no motion vectors", true, false}, {"unclamped, motion vectors", false, true}};
  int width[3] = {0, 0, 0};
  // The smear: how far the resolve is from the current frame over its foliage (motion vectors that
  // follow the sway keep it low).
  double smear[3] = {0, 0, 0};
  size_t smearPixels = 0;
  {
    Host host;
    host.motion = true;
    ASSERT_TRUE(host.create(dev, 1).ok());
    CanopyContext* ctx = make(host, 6.0f, VK_FORMAT_R16G16_SFLOAT);
    ASSERT_NE(ctx, nullptr);
    std::vector<TaaResolve> taa(3, TaaResolve{w, h});
    for (int v = 0; v < 3; ++v) {
      taa[v].clamp = variants[v].clamp;
      taa[v].useMotion = variants[v].useMotion;
    }
    std::vector<glm::vec4> c;
    std::vector<glm::vec2> m;
    float largestMotion = 0.0f;
    for (uint32_t k = 0; k < 48; ++k) {
      host.adjustCamera = [k](CanopyCamera& cam) {
        const glm::vec2 j = halton23(k % 8);
        cam.jitter[0] = j.x;
        cam.jitter[1] = j.y;
      };
      ASSERT_TRUE(host.frame(++frameNumber, {ctx}, view, 1.0f / 30.0f).ok());
      ASSERT_TRUE(host.read(&c, &z).ok());
      ASSERT_TRUE(host.readMotion(&m).ok());
      for (const glm::vec2& v : m) largestMotion = std::max(largestMotion, glm::length(v));
      std::vector<int> foliage(size_t(w) * h);
      for (size_t i = 0; i < c.size(); ++i) foliage[i] = canopy::test::maxDiff(c[i], kSky) > 0.05f;
      for (int v = 0; v < 3; ++v) {
        taa[v].add(c, m);
        if (k < 16) continue;  // the wind has grown
        for (size_t i = 0; i < c.size(); ++i)
          if (foliage[i]) {
            smear[v] += diff3(taa[v].history[i], glm::vec3(c[i]));
            smearPixels += v == 0;
          }
        for (uint32_t y = 0; y < h; ++y)
          for (uint32_t x = 0; x < w; ++x) {
            const size_t i = size_t(y) * w + x;
            if (foliage[i] || diff3(taa[v].history[i], glm::vec3(kSky)) <= 0.05f) continue;
            int r = 1;  // the nearest current foliage, ring by ring
            for (bool found = false; !found && r < 16; ++r)
              for (int dy = -r; dy <= r && !found; ++dy)
                for (int dx = -r; dx <= r && !found; ++dx) {
                  const int xx = int(x) + dx, yy = int(y) + dy;
                  found = (std::abs(dx) == r || std::abs(dy) == r) && xx >= 0 && yy >= 0 && xx < int(w) && yy < int(h) &&
                          foliage[size_t(yy) * w + size_t(xx)];
                }
            width[v] = std::max(width[v], r - 1);
          }
      }
    }
    std::printf("TAA (Halton 2,3 over 8, alpha 0.1, 96x64): leaf-edge error against 4x4 supersampling %.4f resolved, %.4f one "
                "unjittered frame (%zu edge pixels)\n",
                converged, aliased, edges.size());
    for (double& v : smear) v /= double(std::max<size_t>(smearPixels, 1));
    std::printf("TAA trail, a crown swaying by up to %.2f px a frame: width %s %d px, %s %d px, %s %d px; smear over the foliage "
                "%.4f, %.4f, %.4f\n",
                largestMotion, variants[0].name, width[0], variants[1].name, width[1], variants[2].name, width[2], smear[0], smear[1], smear[2]);
    EXPECT_GT(largestMotion, 0.5f) << "the wind must sway the crown";
    destroyCanopy(ctx);
    host.destroy();
  }
  EXPECT_LT(converged, aliased) << "the resolve comes nearer the supersampled frame than one frame";
  // The layers hold the re-slice's own samples: the resolve averages the composite's jittered reads
  // of them (and the wood drawn each frame), so it comes nearer, not all the way (docs/performance.md).
  EXPECT_LE(converged, 0.06);
  EXPECT_LE(width[0], 1) << "no trail wider than 1 px";
  EXPECT_LT(smear[0], smear[1]) << "the motion vectors follow the sway";
}

}  // namespace
