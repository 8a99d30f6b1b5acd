// The public facade (render/canopy.h) end to end through recordCanopy() into a host's own colour
// and depth images: zero wind gives the static composite of the layers; with wind the output is
// the CPU reference's warp of the same layers; parameter changes rebuild only what depends on
// them; golden images of fixed scenes at a fixed time, compared by a tolerance metric with a diff
// image written on failure.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/packing.hpp>

#include "tools/image_io.h"
#include "engine/transfer.h"
#include "render/canopy.h"
#include "render/composite_reference.h"
#include "render/gltf_loader.h"
#include "tools/leaf_cloud.h"
#include "tools/scene_generator.h"
#include "tools/world_lock.h"
#include "tests/gpu_test.h"

using namespace canopy;
using canopy::test::GpuTest;

namespace {

const glm::vec4 kSky(0.45f, 0.6f, 0.8f, 1.0f);

// A minimal host: its own colour + depth images, cleared by its own pass every frame, then Canopy
// recorded into the same command buffer, the images left for a transfer read.
struct Host {
  Device* dev = nullptr;
  uint32_t w = 0, h = 0;
  VkFormat colorFormat = VK_FORMAT_R16G16B16A16_SFLOAT;
  Image color, depth;
  glm::vec4 clear = kSky;  // with alpha 0 the target's alpha after Canopy's passes is its coverage

  Status create(Device& d, uint32_t width, uint32_t height, VkFormat format) {
    dev = &d;
    w = width;
    h = height;
    colorFormat = format;
    ImageDesc c;
    c.format = format;
    c.width = w;
    c.height = h;
    c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    CANOPY_TRY(createImage(d, c, &color, "host colour"));
    c.format = VK_FORMAT_D32_SFLOAT;
    c.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
              VK_IMAGE_USAGE_TRANSFER_DST_BIT;
    return createImage(d, c, &depth, "host depth");
  }
  void destroy() {
    destroyImage(*dev, color);
    destroyImage(*dev, depth);
  }
  Status frame(CanopyContext* ctx, const CanopyFrame& f) {
    const rg::State colorRW = rg::stateOf(rg::Use::ColorAttachmentReadWrite),
                    depthW = rg::stateOf(rg::Use::DepthAttachmentWrite), src = rg::stateOf(rg::Use::TransferSrc);
    rg::RenderGraph g;
    const auto c = g.importImage("host colour", descOf(color), {}, colorRW);
    const auto d = g.importImage("host depth", descOf(depth), {}, depthW);
    g.addPass("host clear", [&](rg::PassContext& x) {
       VkClearColorValue cv{};
       for (int k = 0; k < 4; ++k) cv.float32[k] = clear[k];
       const VkImageSubresourceRange cr{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}, dr{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
       vkCmdClearColorImage(x.cmd, x.image(c).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &cv, 1, &cr);
       VkClearDepthStencilValue dv{1.0f, 0};
       vkCmdClearDepthStencilImage(x.cmd, x.image(d).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &dv, 1, &dr);
       return Status();
     })
        .write(c, rg::Use::TransferDst)
        .write(d, rg::Use::TransferDst);
    CANOPY_TRY(g.bindImage(c, color));
    CANOPY_TRY(g.bindImage(d, depth));
    CANOPY_TRY(g.compile());
    CANOPY_TRY(g.realize(*dev));
    CanopyFrameInputs in;
    in.frame = f;
    in.color = canopyImage(color.image, color.view, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT, colorFormat, colorRW, src);
    in.depth = canopyImage(depth.image, depth.view, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                           VK_FORMAT_D32_SFLOAT, depthW, src);
    Status s = submitAndWait(*dev, [&](VkCommandBuffer cmd) -> Status {
      CANOPY_TRY(g.record(cmd));
      return recordCanopy(ctx, cmd, in);
    });
    g.release(*dev);
    return s;
  }
  // Colour as linear float (RGBA16F) and depth.
  Status read(std::vector<glm::vec4>* rgba, std::vector<float>* z) {
    const rg::State src = rg::stateOf(rg::Use::TransferSrc);
    std::vector<uint64_t> half(size_t(w) * h);
    CANOPY_TRY(readbackImage(*dev, color, 0, 8, half.data(), src));
    rgba->clear();
    for (uint64_t v : half) rgba->push_back(glm::unpackHalf4x16(v));
    z->resize(size_t(w) * h);
    return readbackImage(*dev, depth, 0, 4, z->data(), src);
  }
};

CanopyDesc smallDesc(uint32_t w, uint32_t h, VkFormat color) {
  CanopyDesc d;
  d.width = w;
  d.height = h;
  d.colorFormat = color;
  return d;
}

LayerView cameraFor(const VegetationModel& m, uint32_t w, uint32_t h, float yaw) {
  return orbitView(m.boundsMin, m.boundsMax, yaw, 10.0f, 40.0f, float(w) / float(h), 1.05f);
}

// The CPU reference of the frame just recorded, from the layer images and displacements on the device.
Status referenceFrame(Device& dev, CanopyContext* ctx, uint32_t w, uint32_t h, CompositeReferenceOutputs* out,
                      float* maxDisplacement) {
  LayeredVegetation& lv = canopyLayers(ctx);
  LayerDynamics& dyn = canopyDynamics(ctx);
  const gpu::CompositePush push = canopyCompositor(ctx).push;
  CompositeReferenceInputs in;
  in.width = w;
  in.height = h;
  in.layers = push.layerCount;
  in.layerWidth = lv.desc.width;  // the guard band included
  in.layerHeight = lv.desc.height;
  for (uint32_t l = 0; l < in.layers; ++l) {
    std::vector<glm::vec4> c;
    std::vector<float> z;
    CANOPY_TRY(readLayerColor(lv, l, &c));
    CANOPY_TRY(readLayerDepth(lv, l, &z));
    in.layerColor.insert(in.layerColor.end(), c.begin(), c.end());
    in.layerDepth.insert(in.layerDepth.end(), z.begin(), z.end());
  }
  CANOPY_TRY(readBackground(lv, &in.backgroundColor, &in.backgroundDepth));
  in.sceneColor.assign(size_t(w) * h, kSky);
  in.sceneDepth.assign(size_t(w) * h, 1.0f);
  const size_t count = size_t(push.gridX) * push.gridY * push.layerCount;
  in.displacement.resize(count);
  in.previous.resize(count);
  const rg::State read = rg::stateOf(rg::Use::ComputeStorageRead);
  CANOPY_TRY(readbackBuffer(dev, dyn.displacement, in.displacement.data(), count * 8, read));
  CANOPY_TRY(readbackBuffer(dev, dyn.previous, in.previous.data(), count * 8, read));
  *maxDisplacement = 0.0f;
  for (const glm::vec2& d : in.displacement) *maxDisplacement = std::max(*maxDisplacement, glm::length(d));
  in.view = canopyCompositor(ctx).view;
  compositeReference(push, in, out);
  return Status();
}

float maxDiff(const glm::vec4& a, const glm::vec4& b) {
  const glm::vec4 d = glm::abs(a - b);
  return std::max(std::max(d.x, d.y), std::max(d.z, d.w));
}

// At most 0.5 % of the pixels more than 3/255 off the CPU reference, 1 % of the depths.
void expectNearReference(const std::vector<glm::vec4>& color, const std::vector<float>& depth,
                         const CompositeReferenceOutputs& ref, const std::string& when) {
  size_t off = 0, depthOff = 0;
  for (size_t i = 0; i < color.size(); ++i) {
    off += maxDiff(color[i], ref.color[i]) > 3.0f / 255.0f;
    depthOff += std::abs(depth[i] - ref.depth[i]) > 1e-6f;
  }
  EXPECT_LE(off, color.size() / 200) << when << ": pixels more than 3/255 off the CPU reference";
  EXPECT_LE(depthOff, color.size() / 100) << when << ": depths off the CPU reference";
}

// The output of the last of `frames` frames of a 4000-face crown with a trunk (128x96, through
// recordCanopy) and the CPU reference of that frame.
struct CrownFrame {
  std::vector<glm::vec4> color;
  std::vector<float> depth;
  CompositeReferenceOutputs ref;
  float maxDisplacement = -1.0f;
  uint64_t graphBuilds = 0;
  uint32_t layerWidth = 0;  // the layer images' width (guard band included)
  uint64_t reslices = 0, reslicesBeforeLast = 0;
};

class CanopyTest : public GpuTest {
 protected:
  void renderCrown(float windStrength, uint32_t cellSize, int frames, CrownFrame* out,
                   CompositeDebugView view = CompositeDebugView::None, uint32_t halfResolutionLayers = 0,
                   std::vector<std::vector<glm::vec4>>* layers = nullptr, float lastTurnDegrees = 0.0f) {
    const uint32_t w = 128, h = 96;
    const VegetationModel model = makeLeafCloud(4000, 3, true);
    CanopyContext* ctx = nullptr;
    Status s = createCanopy(dev, model, smallDesc(w, h, VK_FORMAT_R16G16B16A16_SFLOAT), &ctx);
    ASSERT_TRUE(s.ok()) << s.message();
    CanopyParams p = canopyParams(ctx);
    p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    p.simulation.wind.strength = windStrength;
    p.dynamics.cellSize = cellSize;
    p.composite.debugView = view;
    p.composite.debugVelocityScale = std::max(windStrength, 0.1f);
    p.layers.halfResolutionLayers = halfResolutionLayers;
    Host host;
    s = setCanopyParams(ctx, p);
    if (s.ok()) s = host.create(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT);
    CanopyFrame f;
    const LayerView view = cameraFor(model, w, h, 20.0f);
    f.camera = toCamera(view);
    for (int i = 0; i < frames && s.ok(); ++i) {
      // The last frame turned (a pure rotation): shown reprojected, without a re-slice.
      if (i + 1 == frames && lastTurnDegrees != 0.0f) {
        LayerView turned = view;
        turned.view = glm::rotate(glm::mat4(1.0f), glm::radians(lastTurnDegrees), glm::vec3(0, 1, 0)) * view.view;
        f.camera = toCamera(turned);
        out->reslicesBeforeLast = canopyStats(ctx).layers.rebuilds;
      }
      s = host.frame(ctx, f);
    }
    out->reslices = canopyStats(ctx).layers.rebuilds;
    if (s.ok()) s = host.read(&out->color, &out->depth);
    if (s.ok()) s = referenceFrame(dev, ctx, w, h, &out->ref, &out->maxDisplacement);
    if (layers && s.ok()) {
      LayeredVegetation& lv = canopyLayers(ctx);
      layers->resize(lv.settings.layout.count());
      out->layerWidth = lv.desc.width;
      for (uint32_t l = 0; l < layers->size() && s.ok(); ++l) s = readLayerColor(lv, l, &(*layers)[l]);
    }
    EXPECT_TRUE(s.ok()) << s.message();
    out->graphBuilds = canopyStats(ctx).internalGraphBuilds;
    if (host.dev) host.destroy();
    destroyCanopy(ctx);
  }
};

TEST_F(CanopyTest, ZeroWindGivesTheStaticCompositeOfTheLayers) {
  CrownFrame r;
  renderCrown(0.0f, 16, 3, &r);
  if (HasFailure()) return;
  EXPECT_EQ(r.maxDisplacement, 0.0f) << "no wind, no motion";
  float worst = 0.0f;
  size_t leaves = 0, depthOff = 0;
  for (size_t i = 0; i < r.color.size(); ++i) {
    worst = std::max(worst, maxDiff(r.color[i], r.ref.color[i]));
    leaves += r.depth[i] < 1.0f;
    depthOff += r.depth[i] != r.ref.depth[i];
  }
  EXPECT_LE(worst, 1.0f / 255.0f) << "zero wind must give the static composite of the layers";
  EXPECT_EQ(depthOff, 0u);
  EXPECT_GT(leaves, r.color.size() / 20) << "the vegetation covers part of the image";
  EXPECT_EQ(r.graphBuilds, 1u) << "the record() graph is built once for unchanged images";
}

TEST_F(CanopyTest, WindWarpsTheLayersAsTheCpuReferenceDoes) {
  CrownFrame r;
  renderCrown(2.0f, 8, 15, &r);
  if (HasFailure()) return;
  EXPECT_GT(r.maxDisplacement, 0.5f) << "the wind moves the layers by more than half a pixel somewhere";
  expectNearReference(r.color, r.depth, r.ref, "with wind");
}

// Far layers at half resolution (issue 34's cheaper re-slice; docs/design.md "Layers: half
// resolution"): each is drawn into its image's top-left quarter and nothing beyond it, the composite
// reads it there as the CPU reference does, and the picture stays close to the full-resolution one.
TEST_F(CanopyTest, HalfResolutionLayersAreDrawnInTheirQuarterAndReadThere) {
  LayerSettings bad;
  bad.halfResolutionLayers = 6;  // of the default 5(3-1-1)
  const Status refused = validateLayerSettings(bad);
  EXPECT_FALSE(refused.ok());
  EXPECT_NE(refused.message().find("halfResolutionLayers = 6 is outside [0, 5]"), std::string::npos) << refused.message();
  CrownFrame full, half;
  std::vector<std::vector<glm::vec4>> fullLayers, halfLayers;
  renderCrown(2.0f, 8, 15, &full, CompositeDebugView::None, 0, &fullLayers);
  renderCrown(2.0f, 8, 15, &half, CompositeDebugView::None, 2, &halfLayers);
  if (HasFailure()) return;
  ASSERT_EQ(halfLayers.size(), 5u) << "the default layout 5(3-1-1)";
  expectNearReference(half.color, half.depth, half.ref, "two far layers at half resolution");
  // The layer images: the output and the guard band.
  const size_t texels = fullLayers[0].size();
  const uint32_t lw = half.layerWidth, lh = uint32_t(texels / std::max(lw, 1u));
  ASSERT_EQ(size_t(lw) * lh, texels);
  for (uint32_t l = 0; l < 5; ++l) {
    size_t outside = 0, covered = 0, fullCovered = 0;
    for (uint32_t y = 0; y < lh; ++y)
      for (uint32_t x = 0; x < lw; ++x) {
        const float a = halfLayers[l][size_t(y) * lw + x].a;
        covered += a > 0.0f;
        fullCovered += fullLayers[l][size_t(y) * lw + x].a > 0.0f;
        outside += a > 0.0f && (x >= lw / 2 || y >= lh / 2);
      }
    if (l < 3) {
      // Near layers are drawn by the single pass's other vertex shader with the same arithmetic.
      float worst = 0.0f;
      for (size_t i = 0; i < texels; ++i) worst = std::max(worst, maxDiff(halfLayers[l][i], fullLayers[l][i]));
      EXPECT_LE(worst, 1.0f / 255.0f) << "layer " << l << " is at full resolution";
    } else {
      EXPECT_EQ(outside, 0u) << "layer " << l << " drew beyond its quarter";
      EXPECT_GT(covered, 0u) << "layer " << l << " holds leaves";
      // A quarter of the texels, give or take the leaves' edges.
      EXPECT_NEAR(double(covered), 0.25 * double(fullCovered), 0.08 * double(fullCovered)) << "layer " << l;
    }
    std::printf("layer %u: %zu texels with alpha > 0 (full resolution: %zu), %zu beyond the quarter\n", l, covered,
                fullCovered, outside);
  }
  // The composite against the full-resolution one: foliage coverage (depth written) and colour.
  size_t both = 0, either = 0, colourOff = 0;
  double colourSum = 0.0;
  for (size_t i = 0; i < full.color.size(); ++i) {
    const bool a = full.depth[i] < 1.0f, b = half.depth[i] < 1.0f;
    both += a && b;
    either += a || b;
    if (a || b) {
      const float d = maxDiff(full.color[i], half.color[i]);
      colourSum += d;
      colourOff += d > 16.0f / 255.0f;
    }
  }
  // Turned by a degree in the last frame: reprojected (no re-slice), still as the CPU reference.
  CrownFrame turned;
  renderCrown(2.0f, 8, 15, &turned, CompositeDebugView::None, 2, nullptr, 1.0f);
  if (HasFailure()) return;
  EXPECT_EQ(turned.reslices, turned.reslicesBeforeLast) << "a 1 degree turn within the guard band does not re-slice";
  expectNearReference(turned.color, turned.depth, turned.ref, "half resolution, reprojected");
  const double iou = either ? double(both) / double(either) : 1.0;
  std::printf("composite against full resolution: coverage IoU %.4f, mean colour difference %.4f over foliage, %.2f %% "
              "of foliage pixels off by > 16/255\n",
              iou, either ? colourSum / double(either) : 0.0, either ? 100.0 * double(colourOff) / double(either) : 0.0);
  EXPECT_GT(iou, 0.9) << "the far layers at half resolution cover about the same pixels";
}

// The demo's debug views (issue 6), drawn by the composite pass itself.
TEST_F(CanopyTest, DebugViewsShowLayersGridAndVelocity) {
  const uint32_t w = 128;
  // False colour: the vegetation shows the layers' palette colours instead of its own.
  CrownFrame layers;
  renderCrown(0.0f, 16, 3, &layers, CompositeDebugView::Layers);
  if (HasFailure()) return;
  const uint32_t count = 5;  // the default layout 5(3-1-1)
  std::vector<size_t> perLayer(count, 0);
  size_t foliage = 0;
  for (size_t i = 0; i < layers.color.size(); ++i) {
    if (layers.depth[i] >= 1.0f || layers.ref.color[i] == kSky) continue;
    const glm::vec3 c = glm::vec3(layers.color[i]);
    if (glm::length(c) < 1e-3f) continue;
    foliage++;
    for (uint32_t l = 0; l < count; ++l)
      if (glm::dot(glm::normalize(c), glm::normalize(gpu::debugLayerColor(l))) > 0.995f) perLayer[l]++;
  }
  size_t shown = 0, matched = 0;
  for (size_t n : perLayer) {
    shown += n > foliage / 100;
    matched += n;
  }
  EXPECT_GE(shown, 3u) << "at least three layers visible in their own colours";
  EXPECT_GT(matched, foliage / 3) << "of " << foliage << " vegetation pixels";

  // Warp grid without wind: the undisplaced grid, lines on the pixel columns next to multiples of 16.
  CrownFrame grid;
  renderCrown(0.0f, 16, 2, &grid, CompositeDebugView::Grid);
  if (HasFailure()) return;
  const glm::vec4 yellow(1.0f, 0.85f, 0.1f, 1.0f);
  size_t onLine = 0, offLine = 0;
  for (size_t i = 0; i < grid.color.size(); ++i) {
    const uint32_t x = uint32_t(i % w), y = uint32_t(i / w);
    const bool line = x % 16 == 0 || x % 16 == 15 || y % 16 == 0 || y % 16 == 15;
    const bool isYellow = maxDiff(grid.color[i], yellow) < 2.0f / 255.0f;
    onLine += line && isYellow;
    offLine += !line && isYellow;
  }
  EXPECT_EQ(offLine, 0u);
  EXPECT_GT(onLine, grid.color.size() / 5);

  // Velocity field with wind from the left: the field's colour (red = +x) over the whole plane.
  CrownFrame still, velocity;
  renderCrown(2.0f, 16, 10, &still);
  renderCrown(2.0f, 16, 10, &velocity, CompositeDebugView::Velocity);
  if (HasFailure()) return;
  double redStill = 0, redVelocity = 0;
  for (size_t i = 0; i < still.color.size(); ++i) {
    redStill += still.color[i].r - still.color[i].b;
    redVelocity += velocity.color[i].r - velocity.color[i].b;
  }
  EXPECT_GT(redVelocity / double(still.color.size()), redStill / double(still.color.size()) + 0.1)
      << "the velocity view is red where the wind blows toward +x";
}

TEST_F(CanopyTest, ParameterChangesRebuildOnlyWhatDependsOnThem) {
  const uint32_t w = 96, h = 64;
  const VegetationModel model = makeLeafCloud(2000, 4, false);
  CanopyContext* ctx = nullptr;
  Status s = createCanopy(dev, model, smallDesc(w, h, VK_FORMAT_R16G16B16A16_SFLOAT), &ctx);
  ASSERT_TRUE(s.ok()) << s.message();
  Host host;
  ASSERT_TRUE(host.create(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT).ok());
  CanopyFrame f;
  f.camera = toCamera(cameraFor(model, w, h, 0.0f));
  ASSERT_TRUE(host.frame(ctx, f).ok());
  ASSERT_TRUE(host.frame(ctx, f).ok());
  CanopyStats st = canopyStats(ctx);
  EXPECT_FALSE(st.layersRebuilt) << "a still camera does not re-slice";
  const uint64_t gen = st.resourceGeneration, builds = st.internalGraphBuilds, rebuilds = st.layers.rebuilds;
  // A new warp-grid cell and wind: constants only.
  CanopyParams p = canopyParams(ctx);
  p.dynamics.cellSize = 8;
  p.dynamics.delay = DelayMode::Approximate;
  p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  p.simulation.wind.sides = kWindFromRight | kWindFromTop;
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  ASSERT_TRUE(host.frame(ctx, f).ok());
  st = canopyStats(ctx);
  EXPECT_EQ(st.resourceGeneration, gen);
  EXPECT_EQ(st.internalGraphBuilds, builds);
  EXPECT_EQ(st.layers.rebuilds, rebuilds);
  // A new layer count: new layer images, a rebuilt graph, re-sliced layers.
  ASSERT_TRUE(parseLayerLayout("3(1-1-1)", &p.layers.layout).ok());
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  s = host.frame(ctx, f);
  ASSERT_TRUE(s.ok()) << s.message();
  st = canopyStats(ctx);
  EXPECT_EQ(st.resourceGeneration, gen + 1);
  EXPECT_EQ(st.internalGraphBuilds, builds + 1);
  EXPECT_TRUE(st.layersRebuilt);
  EXPECT_EQ(canopyCompositor(ctx).push.layerCount, 3u);
  // Refusals name the parameter and leave the context as it was.
  p.dynamics.cellSize = 2;
  s = setCanopyParams(ctx, p);
  EXPECT_NE(s.message().find("cellSize"), std::string::npos) << s.message();
  p.dynamics.cellSize = 8;
  ASSERT_TRUE(parseLayerLayout("12(4-4-4)", &p.layers.layout).ok());
  s = setCanopyParams(ctx, p);
  EXPECT_NE(s.message().find("maxLayers"), std::string::npos) << s.message();
  f.dt = -1.0f;
  s = host.frame(ctx, f);
  EXPECT_NE(s.message().find("dt"), std::string::npos) << s.message();
  f.dt = 0.0f;  // pause: the simulation holds, the frame still composites
  const uint64_t steps = canopyStats(ctx).simulation.steps;
  ASSERT_TRUE(host.frame(ctx, f).ok());
  EXPECT_EQ(canopyStats(ctx).simulation.steps, steps);
  host.destroy();
  destroyCanopy(ctx);
}

// A host's resize (the demo's window): the size-dependent parts are recreated, the simulation goes
// on where it was (no reload, no reset), and the frame at the new size is still the CPU
// reference's warp of its layers.
TEST_F(CanopyTest, ResizeKeepsTheSimulationAndWarpsAtTheNewSize) {
  const VegetationModel model = makeLeafCloud(3000, 3, true);
  CanopyContext* ctx = nullptr;
  Status s = createCanopy(dev, model, smallDesc(96, 64, VK_FORMAT_R16G16B16A16_SFLOAT), &ctx);
  ASSERT_TRUE(s.ok()) << s.message();
  CanopyParams p = canopyParams(ctx);
  p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  p.simulation.wind.strength = 2.0f;
  p.dynamics.cellSize = 8;
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  Host small;
  ASSERT_TRUE(small.create(dev, 96, 64, VK_FORMAT_R16G16B16A16_SFLOAT).ok());
  CanopyFrame f;
  f.camera = toCamera(cameraFor(model, 96, 64, 20.0f));
  for (int i = 0; i < 5 && s.ok(); ++i) s = small.frame(ctx, f);
  ASSERT_TRUE(s.ok()) << s.message();
  small.destroy();
  const CanopyStats before = canopyStats(ctx);
  EXPECT_EQ(before.simulation.steps, 5u);

  const uint32_t w = 128, h = 96;
  s = resizeCanopy(ctx, w, h);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(canopyStats(ctx).resourceGeneration, before.resourceGeneration + 1) << "a graph holding Canopy must be rebuilt";
  EXPECT_EQ(canopyStats(ctx).simulation.steps, 5u) << "resizing does not touch the simulation";
  Host big;
  ASSERT_TRUE(big.create(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT).ok());
  f.camera = toCamera(cameraFor(model, w, h, 20.0f));
  for (int i = 0; i < 10 && s.ok(); ++i) s = big.frame(ctx, f);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(canopyStats(ctx).simulation.steps, 15u) << "the simulation goes on from where it was";
  EXPECT_GE(canopyStats(ctx).layers.rebuilds, before.layers.rebuilds + 1) << "the layers are re-sliced at the new size";
  std::vector<glm::vec4> color;
  std::vector<float> depth;
  CompositeReferenceOutputs ref;
  float maxDisplacement = 0.0f;
  ASSERT_TRUE(big.read(&color, &depth).ok());
  ASSERT_TRUE(referenceFrame(dev, ctx, w, h, &ref, &maxDisplacement).ok());
  ASSERT_EQ(ref.color.size(), color.size()) << "the layers have the new size";
  EXPECT_GT(maxDisplacement, 0.5f);
  size_t off = 0, leaves = 0;
  for (size_t i = 0; i < color.size(); ++i) {
    off += maxDiff(color[i], ref.color[i]) > 3.0f / 255.0f;
    leaves += depth[i] < 1.0f;
  }
  EXPECT_LE(off, color.size() / 200) << "pixels more than 3/255 off the CPU reference after the resize";
  EXPECT_GT(leaves, color.size() / 20);

  s = resizeCanopy(ctx, 0, 96);
  EXPECT_NE(s.message().find("width = 0 is outside [1, 16384]"), std::string::npos) << s.message();
  big.destroy();
  destroyCanopy(ctx);
}

// Nothing to animate is refused with the reason, not drawn as an empty frame: a model without
// triangles (a glTF whose scene reaches no triangle mesh), and one whose materials are all rigid.
TEST_F(CanopyTest, ModelsWithNothingToAnimateAreRefused) {
  CanopyContext* ctx = nullptr;
  VegetationModel empty;
  empty.path = "empty.gltf";
  empty.materials.resize(1);
  Status s = createCanopy(dev, empty, smallDesc(64, 48, VK_FORMAT_R16G16B16A16_SFLOAT), &ctx);
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(ctx, nullptr);
  EXPECT_NE(s.message().find("'empty.gltf' has no triangles"), std::string::npos) << s.message();

  const VegetationModel cloud = makeLeafCloud(500, 4, true);
  CanopyDesc d = smallDesc(64, 48, VK_FORMAT_R16G16B16A16_SFLOAT);
  for (size_t i = 0; i < cloud.materials.size(); ++i) d.split.rigid.push_back("#" + std::to_string(i));
  s = createCanopy(dev, cloud, d, &ctx);
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(ctx, nullptr);
  EXPECT_NE(s.message().find("has no foliage: every material is rigid"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("split.foliage"), std::string::npos) << s.message();
}

// ---- golden images ------------------------------------------------------------------------------

struct GoldenScene {
  const char* name;
  const char* layout;
  DelayMode delay;
  float yaw;
  int frames;
};

void PrintTo(const GoldenScene& s, std::ostream* os) { *os << s.name; }

std::string outputDir() {
  const std::string dir = std::string(CANOPY_TEST_OUTPUT) + "/golden";
  std::filesystem::create_directories(dir);
  return dir;
}

class GoldenTest : public GpuTest, public ::testing::WithParamInterface<GoldenScene> {};

TEST_P(GoldenTest, MatchesTheCheckedInImage) {
  const GoldenScene sc = GetParam();
  const uint32_t w = 256, h = 192;
  const VegetationModel model = makeLeafCloud(6000, 21, true);
  CanopyDesc desc = smallDesc(w, h, VK_FORMAT_R8G8B8A8_SRGB);
  CanopyContext* ctx = nullptr;
  Status s = createCanopy(dev, model, desc, &ctx);
  ASSERT_TRUE(s.ok()) << s.message();
  CanopyParams p = canopyParams(ctx);
  ASSERT_TRUE(parseLayerLayout(sc.layout, &p.layers.layout).ok());
  p.dynamics.delay = sc.delay;
  p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  p.simulation.wind.strength = 1.5f;
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  Host host;
  ASSERT_TRUE(host.create(dev, w, h, VK_FORMAT_R8G8B8A8_SRGB).ok());
  CanopyFrame f;
  f.camera = toCamera(cameraFor(model, w, h, sc.yaw));
  for (int i = 0; i < sc.frames && s.ok(); ++i) s = host.frame(ctx, f);
  ASSERT_TRUE(s.ok()) << s.message();
  std::vector<uint8_t> got(size_t(w) * h * 4);
  ASSERT_TRUE(readbackImage(dev, host.color, 0, 4, got.data(), rg::stateOf(rg::Use::TransferSrc)).ok());
  host.destroy();
  destroyCanopy(ctx);
  for (size_t i = 3; i < got.size(); i += 4) got[i] = 255;

  const std::string golden = std::string(CANOPY_GOLDEN_DIR) + "/" + sc.name + ".png";
  if (std::getenv("CANOPY_UPDATE_GOLDEN")) {
    ASSERT_TRUE(writePng(golden, w, h, got).ok());
    GTEST_SKIP() << "wrote " << golden << " (CANOPY_UPDATE_GOLDEN is set)";
  }
  uint32_t gw = 0, gh = 0;
  std::vector<uint8_t> want;
  s = readPng(golden, &gw, &gh, &want);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(gw, w);
  ASSERT_EQ(gh, h);
  // Metric: mean absolute error per channel, and the share of pixels off by more than 16/255 in
  // any channel (rasterization and filtering may differ slightly between driver versions).
  std::vector<uint8_t> diff(got.size(), 255);
  double sum = 0;
  size_t bad = 0;
  for (size_t px = 0; px < size_t(w) * h; ++px) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int e = std::abs(int(got[px * 4 + c]) - int(want[px * 4 + c]));
      sum += e;
      worst = std::max(worst, e);
      diff[px * 4 + c] = uint8_t(std::min(255, e * 8));
    }
    bad += worst > 16;
  }
  const double mean = sum / (3.0 * w * h);
  const double badShare = double(bad) / double(w * h);
  if (mean > 1.0 || badShare > 0.005) {
    const std::string dir = outputDir();
    const Status wa = writePng(dir + "/" + sc.name + "_actual.png", w, h, got);
    const Status wd = writePng(dir + "/" + sc.name + "_diff.png", w, h, diff);
    EXPECT_TRUE(wa.ok() && wd.ok()) << wa.message() << wd.message();
    ADD_FAILURE() << sc.name << ": mean abs error " << mean << "/255 (limit 1.0), " << badShare * 100
                  << "% of pixels off by > 16/255 (limit 0.5%); wrote " << dir << "/" << sc.name
                  << "_actual.png and _diff.png (x8)";
  }
}

// Issue 36: the same plant authored in metres, centimetres and inches (its vertices and the camera
// scaled; the simulation plane follows the camera) sways the same: eq. 4's L_i is taken in the
// simulation's domain units. Frames compared by the golden images' metric, and no layer's delay
// reaches maxDelay. With the old world units the centimetre plant's delays pass maxDelay and its
// frames differ: the comparison can fail.
// A context drawing into a fresh test host of w x h (sRGB), its parameters edited by `edit`.
Status openScene(Device& dev, const VegetationModel& m, uint32_t w, uint32_t h, const std::function<void(CanopyParams&)>& edit,
                 CanopyContext** ctx, Host* host) {
  CANOPY_TRY(createCanopy(dev, m, smallDesc(w, h, VK_FORMAT_R8G8B8A8_SRGB), ctx));
  CanopyParams p = canopyParams(*ctx);
  edit(p);
  CANOPY_TRY(setCanopyParams(*ctx, p));
  return host->create(dev, w, h, VK_FORMAT_R8G8B8A8_SRGB);
}

struct ScaleRun {
  std::vector<uint8_t> frame;
  float maxDelay = 0;  // the largest |L_i / V_D| over the layers, s (V_0z = 0)
};

ScaleRun renderScaled(Device& dev, VegetationModel model, float scale, DelayDistanceUnits units) {
  ScaleRun r;
  const uint32_t w = 192, h = 144;
  for (glm::vec3& p : model.positions) p *= scale;
  model.boundsMin *= scale;
  model.boundsMax *= scale;
  CanopyContext* ctx = nullptr;
  Host host;
  Status s = openScene(dev, model, w, h, [&](CanopyParams& p) {
    p.dynamics.delayUnits = units;
    p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    p.simulation.wind.strength = 1.5f;
  }, &ctx, &host);
  EXPECT_TRUE(s.ok()) << s.message();
  if (!s.ok()) {
    destroyCanopy(ctx);
    return r;
  }
  CanopyFrame f;
  f.camera = toCamera(cameraFor(model, w, h, 20.0f));
  for (int i = 0; i < 30 && s.ok(); ++i) s = host.frame(ctx, f);
  EXPECT_TRUE(s.ok()) << s.message();
  const gpu::AnimFrame& a = canopyDynamics(ctx).current;
  for (uint32_t i = 0; i < a.layerCount; ++i) r.maxDelay = std::max(r.maxDelay, std::abs(a.layers[i].distance / a.layers[i].vd));
  r.frame.resize(size_t(w) * h * 4);
  EXPECT_TRUE(readbackImage(dev, host.color, 0, 4, r.frame.data(), rg::stateOf(rg::Use::TransferSrc)).ok());
  host.destroy();
  destroyCanopy(ctx);
  return r;
}

// The golden metric: mean absolute error per channel (/255) and the share of pixels off by > 16.
std::pair<double, double> imageError(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  double sum = 0;
  size_t bad = 0;
  const size_t px = a.size() / 4;
  for (size_t i = 0; i < px; ++i) {
    int worst = 0;
    for (int c = 0; c < 3; ++c) {
      const int e = std::abs(int(a[i * 4 + c]) - int(b[i * 4 + c]));
      sum += e;
      worst = std::max(worst, e);
    }
    bad += worst > 16;
  }
  return {sum / (3.0 * double(px)), double(bad) / double(px)};
}

TEST_F(CanopyTest, ThePlantInMetresCentimetresAndInchesSwaysTheSame) {
  struct Model {
    const char* name;
    VegetationModel m;
  };
  std::vector<Model> models;
  models.push_back({"leaf cloud", makeLeafCloud(6000, 21, true)});
  const std::string plant = std::string(CANOPY_SHARED_ASSETS) + "/DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf";
  if (std::filesystem::exists(plant)) {
    VegetationModel m;
    ASSERT_TRUE(loadGltf(plant, {}, &m).ok());
    models.push_back({"DiffuseTransmissionPlant", std::move(m)});
  } else {
    std::printf("shared assets folder absent (%s): the glTF plant is skipped, the leaf cloud is tested\n", CANOPY_SHARED_ASSETS);
  }
  const float maxDelay = DynamicsParams{}.maxDelay;
  for (const Model& mod : models) {
    SCOPED_TRACE(mod.name);
    const ScaleRun metres = renderScaled(dev, mod.m, 1.0f, DelayDistanceUnits::Domain);
    EXPECT_LT(metres.maxDelay, maxDelay);
    for (float scale : {100.0f, 39.3701f}) {
      const ScaleRun other = renderScaled(dev, mod.m, scale, DelayDistanceUnits::Domain);
      const auto [mean, bad] = imageError(metres.frame, other.frame);
      std::printf("%s x%g: largest delay %.3f s (metres %.3f s), mean abs error %.3f/255, %.3f %% of pixels off by > 16/255\n",
                  mod.name, scale, other.maxDelay, metres.maxDelay, mean, 100.0 * bad);
      EXPECT_LT(other.maxDelay, maxDelay);
      EXPECT_NEAR(other.maxDelay, metres.maxDelay, 1e-3f * metres.maxDelay);
      EXPECT_LE(mean, 1.0);
      EXPECT_LE(bad, 0.005);
    }
    // The old units: the centimetre plant's delays are a hundred times longer.
    const ScaleRun world = renderScaled(dev, mod.m, 1.0f, DelayDistanceUnits::World);
    const ScaleRun worldCm = renderScaled(dev, mod.m, 100.0f, DelayDistanceUnits::World);
    const auto [mean, bad] = imageError(world.frame, worldCm.frame);
    std::printf("%s in world units: largest delay %.3f s in metres, %.3f s in centimetres (clamped at %.0f s); "
                "mean abs error %.3f/255, %.3f %% of pixels off by > 16/255\n",
                mod.name, world.maxDelay, worldCm.maxDelay, maxDelay, mean, 100.0 * bad);
    EXPECT_GE(worldCm.maxDelay, maxDelay * 0.999f);
    EXPECT_TRUE(mean > 1.0 || bad > 0.005) << "world units: the scaled plant should sway differently";
  }
}

// Issue 36, per-plant roots (beyond eq. 7): a generated field of separated plants (nine shrubs on a
// 3 x 3 grid, each a plant of VegetationModel::trianglePlant) seen from above at 25 degrees, 300
// frames of strong wind. Per plant, the largest displacement over the frames at the warp-grid
// corner nearest its base (the bottom of its projected box, at its middle) and at its leaves' top,
// in every layer it has leaves in: each base moves less than a quarter of its top (eq. 7's h is the
// plant's upright height on screen, so the corner just above a root line reaches R sooner than with
// the rect's rows: 2-20 % measured, 2-10 % before). With the paper's
// single root (RootMode::Vegetation) the plants standing behind the front row bend about the front
// row's base line, so their bases move with their tops: the measure can fail.
struct PlantSway {
  float base = 0, top = 0;
};

std::map<uint32_t, PlantSway> plantSway(Device& dev, const VegetationModel& field, RootMode roots) {
  std::map<uint32_t, PlantSway> out;
  const uint32_t w = 640, h = 480;  // each plant over several 16-pixel warp cells
  CanopyContext* ctx = nullptr;
  Host host;
  Status s = openScene(dev, field, w, h, [&](CanopyParams& p) {
    p.dynamics.roots = roots;
    p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    p.simulation.wind.strength = 3.0f;
  }, &ctx, &host);
  EXPECT_TRUE(s.ok()) << s.message();
  if (!s.ok()) {
    destroyCanopy(ctx);
    return out;
  }
  CanopyFrame f;
  f.camera = toCamera(orbitView(field.boundsMin, field.boundsMax, 10.0f, 25.0f, 40.0f, float(w) / float(h), 1.0f));
  for (int frame = 0; frame < 300 && s.ok(); ++frame) {
    s = host.frame(ctx, f);
    if (!s.ok() || frame < 30) continue;  // the wind rising from rest
    const LayeredVegetation& lv = canopyLayers(ctx);
    const LayerDynamics& dyn = canopyDynamics(ctx);
    const gpu::AnimFrame& a = dyn.current;
    const uint32_t corners = a.gridX * a.gridY;
    std::vector<glm::vec2> d(size_t(corners) * a.layerCount);
    s = readbackBuffer(dev, dyn.displacement, d.data(), d.size() * 8, rg::stateOf(rg::Use::ComputeStorageRead));
    // The displacement the inverse warp applies at layer pixel (x, y): the grid's bilinear mix.
    auto at = [&](uint32_t layer, float x, float y) {
      const float gx = std::clamp(x / a.cellSize, 0.0f, float(a.gridX - 1)), gy = std::clamp(y / a.cellSize, 0.0f, float(a.gridY - 1));
      const uint32_t x0 = std::min(uint32_t(gx), a.gridX - 2), y0 = std::min(uint32_t(gy), a.gridY - 2);
      const float tx = gx - float(x0), ty = gy - float(y0);
      auto c = [&](uint32_t i, uint32_t j) { return d[size_t(layer) * corners + j * a.gridX + i]; };
      return glm::length(glm::mix(glm::mix(c(x0, y0), c(x0 + 1, y0), tx), glm::mix(c(x0, y0 + 1), c(x0 + 1, y0 + 1), tx), ty));
    };
    for (uint32_t i = 0; i < lv.visible.layers.size(); ++i) {
      const LayerInfo& li = lv.visible.layers[i];
      for (size_t k = 0; k < li.plants.size(); ++k) {
        const glm::vec4 r = li.plants[k];
        const float cx = 0.5f * (r.x + r.y);
        PlantSway& ps = out[li.plantKeys[k]];
        ps.base = std::max(ps.base, at(i, cx, r.w));
        ps.top = std::max(ps.top, at(i, cx, r.z));
      }
    }
  }
  EXPECT_TRUE(s.ok()) << s.message();
  host.destroy();
  destroyCanopy(ctx);
  return out;
}

TEST_F(CanopyTest, EachPlantOfAFieldBendsAboutItsOwnBase) {
  SceneDesc sd;
  sd.kind = SceneKind::Shrub;
  sd.faces = 6000;
  VegetationModel shrub;
  ASSERT_TRUE(generateScene(sd, &shrub).ok());
  const glm::vec3 size = shrub.boundsMax - shrub.boundsMin;
  const float spacing = 2.0f * std::max(size.x, size.z);
  VegetationModel field = shrub;
  field.positions.clear(), field.normals.clear(), field.uvs.clear(), field.indices.clear();
  field.triangleMaterial.clear(), field.trianglePlant.clear(), field.bend.clear(), field.branches.clear();
  field.boxParent.clear(), field.triangleBox.clear();
  field.boundsMin = glm::vec3(INFINITY);
  field.boundsMax = glm::vec3(-INFINITY);
  for (uint32_t k = 0; k < 9; ++k) {
    const glm::vec3 offset(spacing * float(k % 3), 0.0f, -spacing * float(k / 3));
    const uint32_t base = uint32_t(field.positions.size());
    for (const glm::vec3& q : shrub.positions) field.positions.push_back(q + offset);
    field.normals.insert(field.normals.end(), shrub.normals.begin(), shrub.normals.end());
    field.uvs.insert(field.uvs.end(), shrub.uvs.begin(), shrub.uvs.end());
    for (uint32_t i : shrub.indices) field.indices.push_back(base + i);
    field.triangleMaterial.insert(field.triangleMaterial.end(), shrub.triangleMaterial.begin(), shrub.triangleMaterial.end());
    field.trianglePlant.resize(field.triangleMaterial.size(), k);
    field.boundsMin = glm::min(field.boundsMin, shrub.boundsMin + offset);
    field.boundsMax = glm::max(field.boundsMax, shrub.boundsMax + offset);
  }
  const std::map<uint32_t, PlantSway> own = plantSway(dev, field, RootMode::PerPlant);
  ASSERT_EQ(own.size(), 9u) << "every plant has leaves in some layer";
  for (const auto& [key, ps] : own) {
    std::printf("plant %u: base %.2f px, top %.2f px (%.3f)\n", key, ps.base, ps.top, ps.top > 0 ? ps.base / ps.top : 0.0f);
    EXPECT_GT(ps.top, 1.0f) << "plant " << key << " sways";
    EXPECT_LT(ps.base, 0.25f * ps.top) << "plant " << key;
  }
  const std::map<uint32_t, PlantSway> one = plantSway(dev, field, RootMode::Vegetation);
  uint32_t moved = 0;
  for (const auto& [key, ps] : one) {
    std::printf("one root for the field: plant %u: base %.2f px, top %.2f px\n", key, ps.base, ps.top);
    moved += ps.base >= 0.2f * ps.top;
  }
  EXPECT_GE(moved, 3u) << "with one root the back rows' bases move with their tops";
}

INSTANTIATE_TEST_SUITE_P(Scenes, GoldenTest,
                         ::testing::Values(GoldenScene{"crown_exact_5layers", "5(3-1-1)", DelayMode::Exact, 20.0f, 24},
                                           GoldenScene{"crown_approx_3layers", "3(1-1-1)", DelayMode::Approximate,
                                                       65.0f, 30}),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace

// Issue 34: a layer set drawn at camera A and shown at camera B (reprojected, no re-slice) against
// the set drawn at B, wind off, by the world-lock measure (tools/world_lock.h): a pure rotation is
// exact up to resampling and does not re-slice under the default policy; a small orbit and a small
// dolly stay within their slabs' parallax; a turn that brings in foliage from beyond the output's
// edge finds it in the guard band (no re-slice) and matches as well as the same turn mid-image
// (the resampling's error grows with the turn: the image's local scale changes towards its edges).
// Bounds: measured on lavapipe (depth-coverage IoU 0.972, 0.954, 0.989, 0.960, 0.956; silhouette
// mean 0.27, 0.41, 0.22, 0.49, 0.44 px), then rounded outwards (docs/lab/performance-notebook.md "Moving camera: reprojected, re-sliced by its error").
TEST_F(CanopyTest, ReprojectedLayersMatchLayersDrawnAtTheNewCamera) {
  const uint32_t w = 160, h = 120;
  const VkFormat fmt = VK_FORMAT_R16G16B16A16_SFLOAT;
  const VegetationModel model = makeLeafCloud(4000, 3, true);
  const LayerView a = cameraFor(model, w, h, 20.0f);
  struct Case {
    const char* name;
    LayerView a, b;
    bool defaultPolicy;  // the default thresholds (else none: the set drawn at A is kept)
    double minIoU, maxSilhouettePx;
  };
  auto turned = [&](float degrees) {
    LayerView t = a;
    t.view = glm::rotate(glm::mat4(1.0f), glm::radians(degrees), glm::vec3(0, 1, 0)) * a.view;
    return t;
  };
  LayerView rotation = turned(2.0f), orbit = cameraFor(model, w, h, 21.0f), dolly = a;
  // The guard band (16 x 16 px here): a camera turned 24 degrees away, so the output's left edge
  // cuts the crown, then 4 degrees back: what comes into view was drawn in the guard band.
  const LayerView edgeA = turned(24.0f), edgeB = turned(20.0f);
  const glm::vec3 centre = 0.5f * (model.boundsMin + model.boundsMax);
  const glm::vec3 eye = viewPosition(a.view);
  dolly.view = glm::translate(a.view, 0.02f * (eye - centre));  // 2 % of the distance closer
  const Case cases[] = {{"pure rotation 2 degrees", a, rotation, true, 0.96, 0.4},
                        {"pure rotation 4 degrees", a, turned(4.0f), true, 0.95, 0.5},
                        {"orbit 1 degree", a, orbit, false, 0.97, 0.4},
                        {"dolly 2 %", a, dolly, false, 0.94, 0.7},
                        {"a turn within the guard band", edgeA, edgeB, true, 0.95, 0.5}};
  {
    // Without a guard band the same turn needs content beyond the layers: a re-slice.
    CanopyDesc d = smallDesc(w, h, fmt);
    d.guardBand = 0.0f;
    CanopyContext* none = nullptr;
    ASSERT_TRUE(createCanopy(dev, model, d, &none).ok());
    CanopyParams p = canopyParams(none);
    p.layers.rebuildBudgetMs = 0.0f;
    ASSERT_TRUE(setCanopyParams(none, p).ok());
    Host host;
    ASSERT_TRUE(host.create(dev, w, h, fmt).ok());
    CanopyFrame f;
    f.camera = toCamera(edgeA);
    ASSERT_TRUE(host.frame(none, f).ok());
    const uint64_t rebuilds = canopyStats(none).layers.rebuilds;
    f.camera = toCamera(edgeB);
    ASSERT_TRUE(host.frame(none, f).ok());
    EXPECT_EQ(canopyStats(none).layers.rebuilds, rebuilds + 1);
    EXPECT_NE(canopyStats(none).layers.lastRebuildReason.find("content beyond the layers"), std::string::npos)
        << canopyStats(none).layers.lastRebuildReason;
    host.destroy();
    destroyCanopy(none);
  }
  const uint8_t sky[3] = {uint8_t(std::lround(kSky.r * 255)), uint8_t(std::lround(kSky.g * 255)), uint8_t(std::lround(kSky.b * 255))};
  auto rgba8 = [](const std::vector<glm::vec4>& c) {
    std::vector<uint8_t> out(c.size() * 4);
    for (size_t i = 0; i < c.size(); ++i)
      for (int k = 0; k < 4; ++k) out[4 * i + k] = uint8_t(std::lround(std::clamp(c[i][k], 0.0f, 1.0f) * 255.0f));
    return out;
  };
  // The reference re-slices at every frame, so what it draws at B does not depend on what came
  // before: one context serves every case (contexts are the test's cost under the sanitizers).
  CanopyContext* fresh = nullptr;
  ASSERT_TRUE(createCanopy(dev, model, smallDesc(w, h, fmt), &fresh).ok());
  Host hostFresh;
  ASSERT_TRUE(hostFresh.create(dev, w, h, fmt).ok());
  for (const Case& k : cases) {
    SCOPED_TRACE(k.name);
    CanopyContext* held = nullptr;
    ASSERT_TRUE(createCanopy(dev, model, smallDesc(w, h, fmt), &held).ok());
    CanopyParams p = canopyParams(held);
    p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    p.simulation.wind.strength = 0.0f;
    p.layers.rebuildBudgetMs = 0.0f;
    if (!k.defaultPolicy) {
      p.layers.errorThresholdPixels = 1000.0f;
      p.layers.turnThresholdDegrees = 180.0f;
    }
    ASSERT_TRUE(setCanopyParams(held, p).ok());
    p.layers.policy = ReslicePolicy::EveryFrame;
    ASSERT_TRUE(setCanopyParams(fresh, p).ok());
    Host hostHeld;
    ASSERT_TRUE(hostHeld.create(dev, w, h, fmt).ok());
    CanopyFrame f;
    f.camera = toCamera(k.a);
    ASSERT_TRUE(hostHeld.frame(held, f).ok());
    ASSERT_TRUE(hostFresh.frame(fresh, f).ok());
    EXPECT_EQ(canopyStats(held).layers.guardX, 16u);
    EXPECT_EQ(canopyStats(held).layers.layerWidth, w + 32u);
    const uint64_t rebuilds = canopyStats(held).layers.rebuilds;
    f.camera = toCamera(k.b);
    ASSERT_TRUE(hostHeld.frame(held, f).ok());
    ASSERT_TRUE(hostFresh.frame(fresh, f).ok());
    EXPECT_EQ(canopyStats(held).layers.rebuilds, rebuilds) << "re-sliced: " << canopyStats(held).layers.lastRebuildReason;
    EXPECT_NE(canopyCompositor(held).push.flags & COMPOSITE_REPROJECT, 0u);
    std::vector<glm::vec4> ch, cf;
    std::vector<float> zh, zf;
    ASSERT_TRUE(hostHeld.read(&ch, &zh).ok());
    ASSERT_TRUE(hostFresh.read(&cf, &zf).ok());
    // Coverage where Canopy wrote the host's depth (a layer's alpha >= depthAlpha), and in colour
    // (any pixel more than 1 level off the sky): the reprojection's resampling cuts alpha-tested
    // edges at 1/2 (compositeSharpenEdge), so no faint halo widens the colour coverage.
    std::vector<uint8_t> mh(zh.size()), mf(zf.size());
    for (size_t i = 0; i < zh.size(); ++i) mh[i] = zh[i] < 1.0f, mf[i] = zf[i] < 1.0f;
    const WorldLockError e = compareMasks(mh, mf, rgba8(ch), rgba8(cf), w, h);
    const WorldLockError c = compareFrames(rgba8(ch), rgba8(cf), w, h, sky);
    std::printf("  %s: depth coverage IoU %.4f, silhouette mean %.3f px, p99 %.2f px, centroid %.3f px, colour %.2f levels; "
                "colour coverage (> 1 level) IoU %.4f, silhouette mean %.3f px\n",
                k.name, e.coverageIoU, e.silhouetteMeanPx, e.silhouetteP99Px, e.centroidPx, e.colourMean, c.coverageIoU,
                c.silhouetteMeanPx);
    EXPECT_GT(e.coveredB, 500u) << "the vegetation is in view";
    EXPECT_GE(e.coverageIoU, k.minIoU);
    EXPECT_LE(e.silhouetteMeanPx, k.maxSilhouettePx);
    EXPECT_GE(c.coverageIoU, k.minIoU) << "colour coverage";
    EXPECT_LE(c.silhouetteMeanPx, k.maxSilhouettePx) << "colour coverage";
    // The depth written for the host follows the reprojected layers: where both frames hold
    // foliage, the depths agree up to the two placements' differences (the set drawn at B slices
    // the leaves by B's view depths), the same for every case: no offset of the whole.
    std::vector<float> dz;
    for (size_t i = 0; i < zh.size(); ++i)
      if (zh[i] < 1.0f && zf[i] < 1.0f) dz.push_back(std::abs(zh[i] - zf[i]));
    ASSERT_GT(dz.size(), 500u);
    std::sort(dz.begin(), dz.end());
    EXPECT_LE(dz[dz.size() / 2], 0.005f) << "median depth difference";
    EXPECT_LE(dz[dz.size() * 9 / 10], 0.05f) << "90th percentile depth difference";
    hostHeld.destroy();
    destroyCanopy(held);
  }
  hostFresh.destroy();
  destroyCanopy(fresh);
}

// Issue 34, the depth search (docs/design.md "Layers: reprojection", per-texel depth): an orbit of
// 8 degrees shown without a re-slice, on both composite paths, is the CPU reference's search of
// the layers and the trunk (wind on: the warp composed with it); against layers drawn at the new
// camera it keeps the leaves where they belong better than the planes alone
// (CompositeParams.depthSearchSteps = 0).
TEST_F(CanopyTest, TheDepthSearchShowsEachTexelWhereItsDepthPutsIt) {
  struct Run {
    std::vector<glm::vec4> color;
    std::vector<float> depth;
    CompositeReferenceOutputs ref;
    gpu::CompositeView view{};
  };
  // Frames at camera a, then one at b, shown reprojected (the policy's thresholds lifted); the
  // compute path's tile lists from the classification unless `classify` is cleared.
  bool classify = true;
  auto run = [&](const VegetationModel& model, uint32_t w, uint32_t h, const LayerView& a, const LayerView& b, CompositePath path,
                 uint32_t steps, float wind, ReslicePolicy policy, bool reference, Run* out) {
    CanopyContext* ctx = nullptr;
    ASSERT_TRUE(createCanopy(dev, model, smallDesc(w, h, VK_FORMAT_R16G16B16A16_SFLOAT), &ctx).ok());
    CanopyParams p = canopyParams(ctx);
    p.composite.skipEmptyTiles = classify;
    p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    p.simulation.wind.strength = wind;
    p.composite.path = path;
    p.composite.depthSearchSteps = steps;
    p.layers.policy = policy;
    p.layers.rebuildBudgetMs = 0.0f;
    p.layers.errorThresholdPixels = 1000.0f;
    p.layers.turnThresholdDegrees = 180.0f;
    Host host;
    Status s = setCanopyParams(ctx, p);
    if (s.ok()) s = host.create(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT);
    CanopyFrame f;
    f.camera = toCamera(a);
    for (int i = 0; i < 3 && s.ok(); ++i) s = host.frame(ctx, f);
    const uint64_t rebuilds = canopyStats(ctx).layers.rebuilds;
    f.camera = toCamera(b);
    if (s.ok()) s = host.frame(ctx, f);
    if (policy != ReslicePolicy::EveryFrame) EXPECT_EQ(canopyStats(ctx).layers.rebuilds, rebuilds);
    if (s.ok()) s = host.read(&out->color, &out->depth);
    float maxDisplacement = 0.0f;
    if (s.ok() && reference) {
      s = referenceFrame(dev, ctx, w, h, &out->ref, &maxDisplacement);
      EXPECT_GT(maxDisplacement, 0.1f) << "the wind warps the layers";
    }
    out->view = canopyCompositor(ctx).view;
    EXPECT_TRUE(s.ok()) << s.message();
    if (host.dev) host.destroy();
    destroyCanopy(ctx);
  };
  {
    const uint32_t w = 128, h = 96;
    const VegetationModel model = makeLeafCloud(4000, 3, true);
    const LayerView a = cameraFor(model, w, h, 20.0f), b = cameraFor(model, w, h, 28.0f);
    for (CompositePath path : {CompositePath::Compute, CompositePath::Fragment}) {
      SCOPED_TRACE(path == CompositePath::Compute ? "compute path" : "fragment path");
      Run r;
      run(model, w, h, a, b, path, 16, 1.0f, ReslicePolicy::OnViewChange, true, &r);
      if (HasFailure()) return;
      // Searched: one sample and its secant step where the slab's ray spans at most two layer pixels.
      for (uint32_t i = 0; i < 5; ++i) EXPECT_GE(r.view.search[i].z, 1.0f) << "layer " << i << " searched";
      EXPECT_GE(r.view.search[COMPOSITE_VIEW_BACKGROUND].z, 1.0f) << "the trunk searched";
      expectNearReference(r.color, r.depth, r.ref, "an 8 degree orbit, reprojected with the depth search");
      if (path != CompositePath::Compute) continue;
      // The classification's boxes (each tile's corners through the homographies, grown to the
      // search's ray ends, asked of the occupancy's 2-pixel cells) drop no layer a pixel reads:
      // the image of every tile listing every layer, pixel for pixel.
      Run all;
      classify = false;
      run(model, w, h, a, b, path, 16, 1.0f, ReslicePolicy::OnViewChange, false, &all);
      classify = true;
      if (HasFailure()) return;
      size_t differ = 0, covered = 0;
      for (size_t i = 0; i < all.color.size(); ++i) {
        differ += all.color[i] != r.color[i] || all.depth[i] != r.depth[i];
        covered += all.depth[i] < 1.0f;
      }
      EXPECT_GT(covered, all.depth.size() / 20) << "the leaves must cover pixels for the comparison to mean anything";
      EXPECT_EQ(differ, 0u) << "a reprojected frame's tile lists dropped a layer";
    }
  }
  auto mask = [](const std::vector<float>& z) {
    std::vector<uint8_t> m(z.size());
    for (size_t i = 0; i < z.size(); ++i) m[i] = z[i] < 1.0f;
    return m;
  };
  auto rgba8 = [](const std::vector<glm::vec4>& c) {
    std::vector<uint8_t> out(c.size() * 4);
    for (size_t i = 0; i < c.size(); ++i)
      for (int k = 0; k < 4; ++k) out[4 * i + k] = uint8_t(std::lround(std::clamp(c[i][k], 0.0f, 1.0f) * 255.0f));
    return out;
  };
  // Against layers drawn at the new camera (wind off): a sparse cloud of large leaves, each slab's
  // leaves far apart in depth, orbited 10 degrees, and the generated shrub orbited 6 degrees.
  SceneDesc sd;
  sd.faces = 20000;
  VegetationModel shrub;
  ASSERT_TRUE(generateScene(sd, &shrub).ok());
  const VegetationModel cloud = makeLeafCloud(60, 7, false);
  struct Config {
    const char* name;
    const VegetationModel* model;
    uint32_t w, h;
    float degrees, minIoUGain, maxSilhouetteRatio;
  };
  const Config configs[] = {{"60 large leaves, 10 degrees", &cloud, 256, 192, 10.0f, 0.03f, 0.6f},
                            {"20K-face shrub, 6 degrees", &shrub, 320, 240, 6.0f, 0.015f, 0.85f}};
  for (const Config& c : configs) {
    SCOPED_TRACE(c.name);
    const LayerView a = cameraFor(*c.model, c.w, c.h, 20.0f), b = cameraFor(*c.model, c.w, c.h, 20.0f + c.degrees);
    Run search, plane, fresh;
    run(*c.model, c.w, c.h, a, b, CompositePath::Compute, 16, 0.0f, ReslicePolicy::OnViewChange, false, &search);
    run(*c.model, c.w, c.h, a, b, CompositePath::Compute, 0, 0.0f, ReslicePolicy::OnViewChange, false, &plane);
    run(*c.model, c.w, c.h, a, b, CompositePath::Compute, 16, 0.0f, ReslicePolicy::EveryFrame, false, &fresh);
    if (HasFailure()) return;
    for (uint32_t i = 0; i < 5; ++i) EXPECT_EQ(plane.view.search[i].z, 0.0f) << "layer " << i << ": the plane alone";
    const WorldLockError es = compareMasks(mask(search.depth), mask(fresh.depth), rgba8(search.color), rgba8(fresh.color), c.w, c.h);
    const WorldLockError ep = compareMasks(mask(plane.depth), mask(fresh.depth), rgba8(plane.color), rgba8(fresh.color), c.w, c.h);
    std::printf("  %s, against layers drawn at the new camera: depth search IoU %.4f, silhouette mean %.3f px, centroid %.3f px; "
                "planes alone IoU %.4f, silhouette mean %.3f px, centroid %.3f px\n",
                c.name, es.coverageIoU, es.silhouetteMeanPx, es.centroidPx, ep.coverageIoU, ep.silhouetteMeanPx, ep.centroidPx);
    EXPECT_GT(es.coveredB, 500u) << "the vegetation is in view";
    EXPECT_GE(es.coverageIoU, ep.coverageIoU + c.minIoUGain);
    EXPECT_LE(es.silhouetteMeanPx, c.maxSilhouetteRatio * ep.silhouetteMeanPx);
  }
}

// Issue 16, through the public API: a re-slice spread over frames while the wind keeps animating
// the old layers; every frame, during the slices and the cross-fade, is the CPU reference's
// composite of the layers then visible. Issue 34: a turn of the camera is then re-sliced the same
// way while the old set is shown reprojected to the new camera (the CPU reference reprojects too),
// and the new set, drawn from another camera, replaces it in one copy (no texel blend of two
// cameras' images). requestCanopyRebuild and a camera cut re-slice at once.
TEST_F(CanopyTest, SpreadReslicingKeepsAnimatingAsTheCpuReferenceDoes) {
  const uint32_t w = 128, h = 96;
  const VegetationModel model = makeLeafCloud(4000, 3, true);
  CanopyContext* ctx = nullptr;
  Status s = createCanopy(dev, model, smallDesc(w, h, VK_FORMAT_R16G16B16A16_SFLOAT), &ctx);
  ASSERT_TRUE(s.ok()) << s.message();
  CanopyParams p = canopyParams(ctx);
  p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  p.simulation.wind.strength = 2.0f;
  p.dynamics.cellSize = 8;
  p.layers.rebuildBudgetMs = 0.5f;
  p.layers.crossFadeFrames = 4;
  const uint64_t gen = canopyStats(ctx).resourceGeneration;
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  EXPECT_EQ(canopyStats(ctx).resourceGeneration, gen + 1) << "the second layer set is new";
  Host host;
  ASSERT_TRUE(host.create(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT).ok());
  CanopyFrame f;
  f.camera = toCamera(cameraFor(model, w, h, 20.0f));
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(host.frame(ctx, f).ok());
  auto checkReference = [&](const std::string& when) {
    std::vector<glm::vec4> color;
    std::vector<float> depth;
    CompositeReferenceOutputs ref;
    float maxDisp = 0;
    ASSERT_TRUE(host.read(&color, &depth).ok());
    ASSERT_TRUE(referenceFrame(dev, ctx, w, h, &ref, &maxDisp).ok());
    EXPECT_GT(maxDisp, 0.5f) << when << ": the wind moves the layers";
    expectNearReference(color, depth, ref, when);
  };
  ASSERT_TRUE(requestCanopyRebuild(ctx, false).ok());
  ASSERT_TRUE(host.frame(ctx, f).ok());
  CanopyStats st = canopyStats(ctx);
  EXPECT_FALSE(st.layersRebuilt);
  EXPECT_NE(st.layers.spreadPhase, 0u);
  int frames = 1, fadeFrames = 0;
  bool checkedSlices = false, checkedFade = false;
  while (canopyStats(ctx).layers.spreadRebuilds == 0 && frames < 10000) {
    ASSERT_TRUE(host.frame(ctx, f).ok());
    ++frames;
    st = canopyStats(ctx);
    fadeFrames += st.layersRebuilt;
    if (st.layers.spreadPhase == 2 && !checkedSlices) {
      checkReference("while drawing slices");
      checkedSlices = true;
    }
    if (st.layers.spreadPhase == 3 && st.layers.crossFade == 0.5f) {
      checkReference("halfway through the cross-fade");
      checkedFade = true;
    }
  }
  EXPECT_TRUE(checkedSlices && checkedFade);
  EXPECT_EQ(st.layers.spreadRebuilds, 1u);
  EXPECT_EQ(fadeFrames, 4) << "the visible layers change only in the cross-fade's frames";
  EXPECT_EQ(st.layers.lastSpreadFrames, uint32_t(frames));
  ASSERT_TRUE(host.frame(ctx, f).ok());
  checkReference("after the cross-fade");
  // A turn: the old set reprojected while the new one is drawn, then one copy.
  f.camera = toCamera(cameraFor(model, w, h, 24.0f));
  ASSERT_TRUE(host.frame(ctx, f).ok());
  st = canopyStats(ctx);
  EXPECT_NE(st.layers.spreadPhase, 0u) << st.layers.lastRebuildReason;
  checkReference("the turned camera's first frame, reprojected");
  EXPECT_NE(canopyCompositor(ctx).push.flags & COMPOSITE_REPROJECT, 0u);
  int copies = 0;
  checkedSlices = false;
  for (int i = 0; canopyStats(ctx).layers.spreadRebuilds == 1 && i < 10000; ++i) {
    ASSERT_TRUE(host.frame(ctx, f).ok());
    st = canopyStats(ctx);
    copies += st.layersRebuilt;
    if (st.layers.spreadPhase == 2 && !checkedSlices) {
      checkReference("while drawing the turned camera's slices, reprojected");
      checkedSlices = true;
    }
  }
  EXPECT_TRUE(checkedSlices);
  EXPECT_EQ(st.layers.spreadRebuilds, 2u);
  EXPECT_EQ(copies, 1) << "sets drawn from two cameras are swapped in one copy";
  ASSERT_TRUE(host.frame(ctx, f).ok());
  EXPECT_EQ(canopyCompositor(ctx).push.flags & COMPOSITE_REPROJECT, 0u) << "the new set is the camera's own";
  checkReference("after the turned camera's set is in");
  // Forced re-slices.
  ASSERT_TRUE(requestCanopyRebuild(ctx, true).ok());
  ASSERT_TRUE(host.frame(ctx, f).ok());
  st = canopyStats(ctx);
  EXPECT_TRUE(st.layersRebuilt);
  EXPECT_EQ(st.layers.lastRebuildReason, "requested at once");
  EXPECT_EQ(st.layers.spreadPhase, 0u);
  ASSERT_TRUE(requestCanopyRebuild(ctx, false).ok());
  ASSERT_TRUE(host.frame(ctx, f).ok());
  st = canopyStats(ctx);
  EXPECT_FALSE(st.layersRebuilt);
  EXPECT_EQ(st.layers.lastRebuildReason, "requested");
  EXPECT_NE(st.layers.spreadPhase, 0u);
  f.cameraCut = true;
  ASSERT_TRUE(host.frame(ctx, f).ok());
  st = canopyStats(ctx);
  EXPECT_TRUE(st.layersRebuilt);
  EXPECT_EQ(st.layers.spreadPhase, 0u) << "a camera cut re-slices at once";
  EXPECT_FALSE(requestCanopyRebuild(nullptr, true).ok());
  p.layers.crossFadeFrames = 500;
  s = setCanopyParams(ctx, p);
  EXPECT_NE(s.message().find("crossFadeFrames"), std::string::npos) << s.message();
  host.destroy();
  destroyCanopy(ctx);
}

// Issue 34: a cross-fade at one camera never lowers the coverage below the smaller set's. A layout
// of the same layer count moves leaves between layers; each layer's depth takes the nearer of the
// two sets' at its first blend, so the new copy of a moved leaf passes the composite's depth test
// (without it, covered pixels fell to 80 % here), and the new set is laid over the old before the
// old set's own texels fade out, so the leaf is whole in one of its two layers in every frame (a
// plain mix composed 1 - s (1 - s) there). Bounds: covered pixels (alpha >= 1/2) and summed alpha
// each >= 99 % of the smaller set's (half-float rounding and partial edge texels).
TEST_F(CanopyTest, CrossFadeNeverLowersCoverageBelowTheSmallerSet) {
  const uint32_t w = 128, h = 96;
  const VegetationModel model = makeLeafCloud(600, 3, true);
  CanopyContext* ctx = nullptr;
  Status s = createCanopy(dev, model, smallDesc(w, h, VK_FORMAT_R16G16B16A16_SFLOAT), &ctx);
  ASSERT_TRUE(s.ok()) << s.message();
  CanopyParams p = canopyParams(ctx);
  p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  p.simulation.wind.strength = 0.0f;
  p.layers.rebuildBudgetMs = 0.5f;
  p.layers.crossFadeFrames = 8;
  ASSERT_TRUE(parseLayerLayout("5(3-1-1)", &p.layers.layout).ok());
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  Host host;
  host.clear = glm::vec4(0.0f);
  ASSERT_TRUE(host.create(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT).ok());
  CanopyFrame f;
  f.camera = toCamera(cameraFor(model, w, h, 20.0f));
  struct Coverage {
    double covered = 0, alpha = 0;
  };
  auto coverage = [&](Coverage* c) {
    std::vector<glm::vec4> color;
    std::vector<float> depth;
    ASSERT_TRUE(host.read(&color, &depth).ok());
    *c = Coverage{};
    for (const glm::vec4& v : color) {
      c->covered += v.a >= 0.5f ? 1.0 : 0.0;
      c->alpha += v.a;
    }
  };
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(host.frame(ctx, f).ok());
  Coverage before, after, lowest;
  coverage(&before);
  ASSERT_GT(before.covered, 300.0);
  std::vector<glm::vec4> oldColor, newColor;
  std::vector<float> z;
  ASSERT_TRUE(host.read(&oldColor, &z).ok());
  lowest = before;
  ASSERT_TRUE(parseLayerLayout("5(1-1-3)", &p.layers.layout).ok());
  ASSERT_TRUE(setCanopyParams(ctx, p).ok());
  int fadeFrames = 0;
  for (int i = 0; i < 10000; ++i) {
    ASSERT_TRUE(host.frame(ctx, f).ok());
    const CanopyStats st = canopyStats(ctx);
    Coverage c;
    coverage(&c);
    fadeFrames += st.layers.spreadPhase == 3 && st.layers.crossFade > 0.0f && st.layers.crossFade < 1.0f;
    lowest.covered = std::min(lowest.covered, c.covered);
    lowest.alpha = std::min(lowest.alpha, c.alpha);
    if (st.layers.spreadPhase == 0) break;
  }
  EXPECT_EQ(fadeFrames, 7) << "crossFadeFrames - 1 blend frames, then the copy";
  ASSERT_TRUE(host.frame(ctx, f).ok());
  coverage(&after);
  ASSERT_TRUE(host.read(&newColor, &z).ok());
  float changed = 0;
  for (size_t i = 0; i < oldColor.size(); ++i) changed = std::max(changed, maxDiff(oldColor[i], newColor[i]));
  EXPECT_GT(changed, 0.05f) << "the new layout changes the picture (leaves moved between layers)";
  const double smallerCovered = std::min(before.covered, after.covered), smallerAlpha = std::min(before.alpha, after.alpha);
  EXPECT_GE(lowest.covered, 0.99 * smallerCovered) << "covered pixels: before " << before.covered << ", after " << after.covered;
  EXPECT_GE(lowest.alpha, 0.99 * smallerAlpha) << "summed alpha: before " << before.alpha << ", after " << after.alpha;
  host.destroy();
  destroyCanopy(ctx);
}

// issue 16: through the public API, a mesh over CanopyDesc.deviceMemoryBudget stays in host memory
// and is streamed through the staging ring; once the first re-slice is complete the frames equal
// the resident mesh's (no wind: the static composite), and Canopy's allocator never held more than
// the budget for the streamed context.
TEST_F(CanopyTest, StreamedMeshWithinTheDeviceBudget) {
  const uint32_t w = 128, h = 96;
  SceneDesc sd;
  sd.kind = SceneKind::Shrub;
  sd.faces = 300000;
  sd.seed = 2;
  sd.textureSize = 32;
  VegetationModel model;
  ASSERT_TRUE(generateScene(sd, &model).ok());
  CanopyDesc rd = smallDesc(w, h, VK_FORMAT_R16G16B16A16_SFLOAT);
  rd.deviceMemoryBudget = 0;
  rd.params.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
  rd.params.simulation.wind.strength = 0.0f;
  rd.params.layers.rebuildBudgetMs = 1.0f;  // both layer sets, as the budget plans for
  const uint64_t before = dev.allocator->liveBytes;
  CanopyContext* resident = nullptr;
  Status s = createCanopy(dev, model, rd, &resident);
  ASSERT_TRUE(s.ok()) << s.message();
  const uint64_t residentBytes = dev.allocator->liveBytes - before;
  const CanopyStats rs = canopyStats(resident);
  EXPECT_TRUE(rs.layers.meshResident);
  const LayeredVegetation& rl = canopyLayers(resident);
  const uint64_t mesh = rs.layers.meshBytes;
  const uint64_t other =
      residentBytes - (rl.mesh.vertices.allocation.size + rl.mesh.indexBuffer.allocation.size + rl.mesh.leafRoots.allocation.size);
  CanopyDesc sdsc = rd;
  sdsc.params.layers.rebuildBudgetMs = 0.0f;
  sdsc.deviceMemoryBudget = other + mesh / 2;
  sdsc.meshStagingRingBytes = 1 << 20;
  Host host;
  ASSERT_TRUE(host.create(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT).ok());
  CanopyFrame f;
  f.camera = toCamera(cameraFor(model, w, h, 20.0f));
  uint64_t frameNumber = 0;
  for (int i = 0; i < 3; ++i) {
    f.frameNumber = ++frameNumber;
    ASSERT_TRUE(host.frame(resident, f).ok());
  }
  std::vector<glm::vec4> colorR, colorS;
  std::vector<float> depthR, depthS;
  ASSERT_TRUE(host.read(&colorR, &depthR).ok());
  // The streamed context's peak, from its creation to its last frame (before any readback: the
  // test's own staging buffers are not the context's).
  const uint64_t start = dev.allocator->liveBytes;
  dev.allocator->peakLiveBytes = start;
  CanopyContext* streamed = nullptr;
  s = createCanopy(dev, model, sdsc, &streamed);
  ASSERT_TRUE(s.ok()) << s.message();
  const CanopyStats ss = canopyStats(streamed);
  EXPECT_FALSE(ss.layers.meshResident);
  EXPECT_GT(ss.layers.meshRingBytes, 0u);
  EXPECT_LT(ss.layers.meshRingBytes, mesh);
  uint32_t frames = 0;
  while (canopyStats(streamed).layers.spreadRebuilds == 0) {
    f.frameNumber = ++frameNumber;
    ++frames;
    const Status fs = host.frame(streamed, f);
    ASSERT_TRUE(fs.ok()) << fs.message();
    ASSERT_LT(frames, 1000u);
  }
  EXPECT_GT(frames, 2u) << "the ring holds less than the mesh: several frames";
  f.frameNumber = ++frameNumber;
  ASSERT_TRUE(host.frame(streamed, f).ok());
  EXPECT_LE(dev.allocator->peakLiveBytes - start, sdsc.deviceMemoryBudget)
      << "peak " << dev.allocator->peakLiveBytes - start << " bytes, budget " << sdsc.deviceMemoryBudget;
  ASSERT_TRUE(host.read(&colorS, &depthS).ok());
  size_t off = 0, depthOff = 0, covered = 0;
  for (size_t i = 0; i < colorR.size(); ++i) {
    off += maxDiff(colorR[i], colorS[i]) > 1.0f / 255.0f;
    depthOff += depthR[i] != depthS[i];
    covered += depthS[i] < 1.0f;
  }
  EXPECT_EQ(off, 0u) << "pixels of the streamed mesh's frame more than 1/255 off the resident mesh's";
  EXPECT_EQ(depthOff, 0u);
  EXPECT_GT(covered, colorS.size() / 20) << "the vegetation covers part of the image";
  CompositeReferenceOutputs ref;
  float maxDisp = 0.0f;
  ASSERT_TRUE(referenceFrame(dev, streamed, w, h, &ref, &maxDisp).ok());
  expectNearReference(colorS, depthS, ref, "streamed mesh");
  host.destroy();
  destroyCanopy(streamed);
  destroyCanopy(resident);
  // The ring's range, and a budget the compositor alone exceeds, are refused naming the parameter.
  CanopyDesc bad = sdsc;
  bad.meshStagingRingBytes = 1000;
  CanopyContext* none = nullptr;
  s = createCanopy(dev, model, bad, &none);
  EXPECT_NE(s.message().find("meshStagingRingBytes"), std::string::npos) << s.message();
  bad = sdsc;
  bad.deviceMemoryBudget = 4096;
  s = createCanopy(dev, model, bad, &none);
  EXPECT_NE(s.message().find("deviceMemoryBudget"), std::string::npos) << s.message();
  EXPECT_EQ(none, nullptr);
}
