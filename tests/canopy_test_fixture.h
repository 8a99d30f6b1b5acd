#pragma once
// The façade tests' host and fixture (tests/canopy_test.cpp, tests/canopy_reslice_test.cpp): a
// minimal host with its own colour and depth recording Canopy through recordCanopy, the CPU
// reference of its last frame, and a 4000-face crown rendered at a chosen wind.
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

namespace canopy::test::facade {

using namespace canopy;
using canopy::test::GpuTest;


inline const glm::vec4 kSky(0.45f, 0.6f, 0.8f, 1.0f);

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

// The façade tests compare frames with the CPU reference composite (render/composite_reference.h),
// which composites the layers over the background image: the rigid parts are that still background
// here (RigidMotion::Still); drawn every frame with the foliage: tests/rigid_motion_test.cpp.
inline CanopyDesc smallDesc(uint32_t w, uint32_t h, VkFormat color) {
  CanopyDesc d;
  d.width = w;
  d.height = h;
  d.colorFormat = color;
  d.params.layers.rigidMotion = RigidMotion::Still;
  return d;
}

inline LayerView cameraFor(const VegetationModel& m, uint32_t w, uint32_t h, float yaw) {
  return orbitView(m.boundsMin, m.boundsMax, yaw, 10.0f, 40.0f, float(w) / float(h), 1.05f);
}

// The CPU reference of the frame just recorded, from the layer images and displacements on the device.
inline Status referenceFrame(Device& dev, CanopyContext* ctx, uint32_t w, uint32_t h, CompositeReferenceOutputs* out,
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

inline float maxDiff(const glm::vec4& a, const glm::vec4& b) {
  const glm::vec4 d = glm::abs(a - b);
  return std::max(std::max(d.x, d.y), std::max(d.z, d.w));
}

// At most 0.5 % of the pixels more than 3/255 off the CPU reference, 1 % of the depths.
inline void expectNearReference(const std::vector<glm::vec4>& color, const std::vector<float>& depth,
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
  bool compositeCompute = false, compositeComputeAvailable = false;  // CanopyStats of the last frame
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
    out->compositeCompute = canopyStats(ctx).compositeCompute;
    out->compositeComputeAvailable = canopyStats(ctx).compositeComputeAvailable;
    if (host.dev) host.destroy();
    destroyCanopy(ctx);
  }
};

}  // namespace canopy::test::facade
