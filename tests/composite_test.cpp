// Inverse warp + compositing (paper 3.2, 3.6) on synthetic layers with known content: a constant
// displacement shifts a pattern by exactly that many pixels; layers composite in order with the
// trunk background and the host's scene inserted by depth; the depth output is the nearest layer
// with alpha >= 0.5; motion vectors; the levers (early exit, empty-tile skip) leave the image
// unchanged; GPU against the CPU reference on random content and random warps.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <glm/gtc/packing.hpp>

#include "compute/dynamics.h"
#include "engine/transfer.h"
#include "render/composite.h"
#include "render/composite_reference.h"
#include "tests/gpu_test.h"

using namespace canopy;
using canopy::test::GpuTest;

namespace {

struct Scene {
  uint32_t w = 64, h = 48, n = 1, cell = 8;
  std::vector<glm::vec4> layerColor;  // n x h x w
  std::vector<float> layerDepth;
  std::vector<glm::vec4> bgColor;     // h x w
  std::vector<float> bgDepth;
  std::vector<glm::vec4> sceneColor;
  std::vector<float> sceneDepth;
  std::vector<glm::vec2> disp, prev;  // n x gridY x gridX
  glm::vec2 motionClear{7.0f, 7.0f};
  CompositeParams params;
  bool background = true;
  bool motionValid = true;
  uint32_t tilesPerGroup = 0;  // CompositorDesc.tilesPerGroup (0: by device class)

  uint32_t gridX() const { return gridCorners(w, cell); }
  uint32_t gridY() const { return gridCorners(h, cell); }
  size_t pixels() const { return size_t(w) * h; }
  void resize(uint32_t layers) {
    n = layers;
    layerColor.assign(pixels() * n, glm::vec4(0.0f));
    layerDepth.assign(pixels() * n, 1.0f);
    bgColor.assign(pixels(), glm::vec4(0.0f));
    bgDepth.assign(pixels(), 1.0f);
    sceneColor.assign(pixels(), glm::vec4(0.0f, 0.0f, 0.0f, 1.0f));
    sceneDepth.assign(pixels(), 1.0f);
    disp.assign(size_t(gridX()) * gridY() * n, glm::vec2(0.0f));
    prev = disp;
  }
  glm::vec4& color(uint32_t l, uint32_t x, uint32_t y) { return layerColor[(size_t(l) * h + y) * w + x]; }
  float& depth(uint32_t l, uint32_t x, uint32_t y) { return layerDepth[(size_t(l) * h + y) * w + x]; }
};

struct Result {
  std::vector<glm::vec4> color;
  std::vector<float> depth;
  std::vector<glm::vec2> motion;
  gpu::CompositePush push{};
};

std::vector<uint64_t> toHalf(const std::vector<glm::vec4>& v) {
  std::vector<uint64_t> out(v.size());
  for (size_t i = 0; i < v.size(); ++i) out[i] = glm::packHalf4x16(v[i]);
  return out;
}

float maxDiff(const glm::vec4& a, const glm::vec4& b) {
  const glm::vec4 d = glm::abs(a - b);
  return std::max(std::max(d.x, d.y), std::max(d.z, d.w));
}

class CompositeTest : public GpuTest {
 protected:
  Result run(Scene& sc) {
    Result r;
    const VkFormat kColor = VK_FORMAT_R16G16B16A16_SFLOAT, kDepth = VK_FORMAT_D32_SFLOAT, kMotion = VK_FORMAT_R16G16_SFLOAT;
    auto image = [&](VkFormat f, uint32_t layers, VkImageUsageFlags usage, Image* out) {
      ImageDesc d;
      d.format = f;
      d.width = sc.w;
      d.height = sc.h;
      d.layers = layers;
      d.usage = usage | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
      d.arrayView = layers > 1 || usage == VK_IMAGE_USAGE_SAMPLED_BIT;
      Status s = createImage(dev, d, out);
      EXPECT_TRUE(s.ok()) << s.message();
    };
    const VkImageUsageFlags sampled = VK_IMAGE_USAGE_SAMPLED_BIT;
    Image lc, ld, bgc, bgd, hc, hd, hm;
    image(kColor, sc.n, sampled, &lc);
    image(kDepth, sc.n, sampled, &ld);
    image(kColor, 1, sampled | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, &bgc);
    image(kDepth, 1, sampled | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, &bgd);
    image(kColor, 1, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, &hc);
    image(kDepth, 1, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | sampled | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, &hd);
    image(kMotion, 1, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT, &hm);
    const rg::State fs = rg::stateOf(rg::Use::FragmentSampled), colorRW = rg::stateOf(rg::Use::ColorAttachmentReadWrite),
                    depthW = rg::stateOf(rg::Use::DepthAttachmentWrite), src = rg::stateOf(rg::Use::TransferSrc),
                    read = rg::stateOf(rg::Use::ComputeStorageRead);
    auto upload = [&](const Image& img, const void* data, size_t bytes, rg::State st) {
      Status s = uploadImage(dev, nullptr, img, data, bytes, st);
      EXPECT_TRUE(s.ok()) << s.message();
    };
    const auto lcHalf = toHalf(sc.layerColor), bgHalf = toHalf(sc.bgColor), scHalf = toHalf(sc.sceneColor);
    upload(lc, lcHalf.data(), lcHalf.size() * 8, fs);
    upload(ld, sc.layerDepth.data(), sc.layerDepth.size() * 4, fs);
    upload(bgc, bgHalf.data(), bgHalf.size() * 8, fs);
    upload(bgd, sc.bgDepth.data(), sc.bgDepth.size() * 4, fs);
    upload(hc, scHalf.data(), scHalf.size() * 8, colorRW);
    upload(hd, sc.sceneDepth.data(), sc.sceneDepth.size() * 4, depthW);
    std::vector<uint32_t> motionInit(sc.pixels(), glm::packHalf2x16(sc.motionClear));
    upload(hm, motionInit.data(), motionInit.size() * 4, colorRW);
    Buffer disp, prev;
    for (auto [buf, data] : {std::pair{&disp, &sc.disp}, std::pair{&prev, &sc.prev}}) {
      EXPECT_TRUE(createBuffer(dev, data->size() * 8, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                               MemoryUsage::DeviceLocal, buf).ok());
      EXPECT_TRUE(uploadBuffer(dev, nullptr, *buf, data->data(), data->size() * 8, read).ok());
    }
    Compositor c;
    CompositorDesc cd;
    cd.width = sc.w;
    cd.height = sc.h;
    cd.colorFormat = kColor;
    cd.depthFormat = kDepth;
    cd.motionFormat = kMotion;
    cd.maxLayers = sc.n;
    cd.tilesPerGroup = sc.tilesPerGroup;
    Status s = createCompositor(dev, cd, &c);
    EXPECT_TRUE(s.ok()) << s.message();
    gpu::AnimFrame a{};
    a.layerCount = sc.n;
    a.gridX = sc.gridX();
    a.gridY = sc.gridY();
    a.cellSize = float(sc.cell);
    a.width = float(sc.w);
    a.height = float(sc.h);
    if (s.ok()) s = prepareComposite(c, sc.params, a, sc.background, true, sc.motionValid);
    EXPECT_TRUE(s.ok()) << s.message();
    r.push = c.push;

    rg::RenderGraph g;
    LayerResources lr;
    lr.color = g.importImage("layers", descOf(lc), fs, fs);
    lr.depth = g.importImage("layer depth", descOf(ld), fs, fs);
    lr.backgroundColor = g.importImage("background", descOf(bgc), fs, fs);
    lr.backgroundDepth = g.importImage("background depth", descOf(bgd), fs, fs);
    const auto dId = g.importBuffer("disp", disp.size, read, read), pId = g.importBuffer("prev", prev.size, read, read);
    CompositeTargets t;
    t.color = g.importImage("host colour", descOf(hc), colorRW, src);
    t.depth = g.importImage("host depth", descOf(hd), depthW, src);
    t.motion = g.importImage("host motion", descOf(hm), colorRW, src);
    for (auto [id, img] : {std::pair{lr.color, &lc}, {lr.depth, &ld}, {lr.backgroundColor, &bgc},
                           {lr.backgroundDepth, &bgd}, {t.color, &hc}, {t.depth, &hd}, {t.motion, &hm}})
      EXPECT_TRUE(g.bindImage(id, *img).ok());
    EXPECT_TRUE(g.bindBuffer(dId, disp.buffer).ok());
    EXPECT_TRUE(g.bindBuffer(pId, prev.buffer).ok());
    if (s.ok()) s = addCompositePasses(c, g, lr, dId, pId, t);
    if (s.ok()) s = g.compile();
    if (s.ok()) s = g.realize(dev);
    if (s.ok()) s = submitAndWait(dev, [&](VkCommandBuffer cmd) { return g.record(cmd); });
    EXPECT_TRUE(s.ok()) << s.message();
    std::vector<uint64_t> color(sc.pixels());
    std::vector<uint32_t> motion(sc.pixels());
    r.depth.resize(sc.pixels());
    EXPECT_TRUE(readbackImage(dev, hc, 0, 8, color.data(), src).ok());
    EXPECT_TRUE(readbackImage(dev, hd, 0, 4, r.depth.data(), src).ok());
    EXPECT_TRUE(readbackImage(dev, hm, 0, 4, motion.data(), src).ok());
    for (uint64_t v : color) r.color.push_back(glm::unpackHalf4x16(v));
    for (uint32_t v : motion) r.motion.push_back(glm::unpackHalf2x16(v));
    g.release(dev);
    destroyCompositor(c);
    for (Image* img : {&lc, &ld, &bgc, &bgd, &hc, &hd, &hm}) destroyImage(dev, *img);
    destroyBuffer(dev, disp);
    destroyBuffer(dev, prev);
    return r;
  }

  CompositeReferenceOutputs reference(const Scene& sc, const gpu::CompositePush& push) {
    CompositeReferenceInputs in;
    in.width = sc.w;
    in.height = sc.h;
    in.layers = sc.n;
    in.layerColor = sc.layerColor;
    in.layerDepth = sc.layerDepth;
    in.backgroundColor = sc.bgColor;
    in.backgroundDepth = sc.bgDepth;
    in.sceneColor = sc.sceneColor;
    in.sceneDepth = sc.sceneDepth;
    in.displacement = sc.disp;
    in.previous = sc.prev;
    CompositeReferenceOutputs out;
    compositeReference(push, in, &out);
    return out;
  }
};

// A random opaque pattern, with random (not lerp-friendly) values per texel.
void fillPattern(Scene& sc, uint32_t layer, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (uint32_t y = 0; y < sc.h; ++y)
    for (uint32_t x = 0; x < sc.w; ++x) {
      sc.color(layer, x, y) = glm::vec4(u(rng), u(rng), u(rng), 1.0f);
      sc.depth(layer, x, y) = 0.5f;
    }
}

TEST_F(CompositeTest, ConstantDisplacementShiftsThePatternByExactlyThatManyPixels) {
  Scene sc;
  sc.resize(1);
  fillPattern(sc, 0, 11);
  sc.background = false;
  const glm::ivec2 d(3, -2);
  std::fill(sc.disp.begin(), sc.disp.end(), glm::vec2(d));
  const Result r = run(sc);
  uint32_t checked = 0;
  float worst = 0.0f;
  for (uint32_t y = 0; y < sc.h; ++y)
    for (uint32_t x = 0; x < sc.w; ++x) {
      const int sx = int(x) - d.x, sy = int(y) - d.y;  // output(p) = layer(p - d)
      const glm::vec4 want = (sx >= 0 && sy >= 0 && sx < int(sc.w) && sy < int(sc.h)) ? sc.color(0, sx, sy)
                                                                                        : sc.sceneColor[y * sc.w + x];
      worst = std::max(worst, maxDiff(r.color[y * sc.w + x], want));
      ++checked;
    }
  EXPECT_EQ(checked, sc.pixels());
  EXPECT_LE(worst, 1.0f / 255.0f) << "a (3, -2) px displacement must move the pattern by exactly (3, -2) px";
  // A half-pixel shift blends the two neighbours equally (bilinear), as the CPU reference does.
  std::fill(sc.disp.begin(), sc.disp.end(), glm::vec2(2.5f, 0.0f));
  const Result half = run(sc);
  const CompositeReferenceOutputs ref = reference(sc, half.push);
  worst = 0.0f;
  for (size_t i = 0; i < sc.pixels(); ++i) worst = std::max(worst, maxDiff(half.color[i], ref.color[i]));
  EXPECT_LE(worst, 2.0f / 255.0f);
}

// Three uniform layers (depths 0.2, 0.5, 0.8), an opaque white trunk at depth 0.6 in the left half,
// the host's scene at depth 0.4 (blue) in the top half and far (black) below.
Scene orderScene(float alpha1) {
  Scene sc;
  sc.resize(3);
  const glm::vec4 straight[3] = {{1, 0, 0, 0.3f}, {0, 1, 0, alpha1}, {0, 0, 1, 0.8f}};
  const float z[3] = {0.2f, 0.5f, 0.8f};
  for (uint32_t l = 0; l < 3; ++l)
    for (uint32_t y = 0; y < sc.h; ++y)
      for (uint32_t x = 0; x < sc.w; ++x) {
        sc.color(l, x, y) = glm::vec4(glm::vec3(straight[l]) * straight[l].a, straight[l].a);
        sc.depth(l, x, y) = z[l];
      }
  for (uint32_t y = 0; y < sc.h; ++y)
    for (uint32_t x = 0; x < sc.w; ++x) {
      const size_t i = size_t(y) * sc.w + x;
      if (x < sc.w / 2) {
        sc.bgColor[i] = glm::vec4(1.0f);
        sc.bgDepth[i] = 0.6f;
      }
      if (y < sc.h / 2) {
        sc.sceneColor[i] = glm::vec4(0, 0, 1, 1);
        sc.sceneDepth[i] = 0.4f;
      }
    }
  return sc;
}

glm::vec4 over(glm::vec4 front, glm::vec4 back) { return front + (1.0f - front.a) * back; }

TEST_F(CompositeTest, LayersCompositeInOrderWithTrunkAndSceneInsertedByDepth) {
  for (float alpha1 : {0.6f, 0.4f}) {
    Scene sc = orderScene(alpha1);
    const Result r = run(sc);
    const glm::vec4 l0 = sc.color(0, 0, 0), l1 = sc.color(1, 0, 0), l2 = sc.color(2, 0, 0);
    const glm::vec4 black(0, 0, 0, 1), blue(0, 0, 1, 1), white(1.0f);
    struct Probe {
      uint32_t x, y;
      glm::vec4 color;
      float depth;
      const char* what;
    };
    // Depth: the nearest layer with alpha >= 0.5 (layer 0 has 0.3), else the trunk, else the scene.
    const Probe probes[] = {
        {48, 36, over(l0, over(l1, over(l2, black))), alpha1 >= 0.5f ? 0.5f : 0.8f, "no trunk, far scene: all layers"},
        {16, 36, over(l0, over(l1, white)), alpha1 >= 0.5f ? 0.5f : 0.6f, "trunk at 0.6 hides layer 2"},
        {16, 10, over(l0, blue), 0.4f, "scene at 0.4 hides layers 1, 2 and the trunk"},
        {48, 10, over(l0, blue), 0.4f, "scene at 0.4 hides layers 1 and 2"},
    };
    for (const Probe& p : probes) {
      const size_t i = size_t(p.y) * sc.w + p.x;
      EXPECT_LE(maxDiff(r.color[i], p.color), 1.0f / 255.0f)
          << p.what << " (alpha1 " << alpha1 << "): got " << r.color[i].r << "," << r.color[i].g << "," << r.color[i].b;
      EXPECT_NEAR(r.depth[i], p.depth, 1e-6f) << p.what << " (alpha1 " << alpha1 << ")";
    }
  }
}

TEST_F(CompositeTest, MotionVectorsAreCurrentMinusPreviousDisplacementOfTheFrontLayer) {
  Scene sc;
  sc.resize(2);
  for (uint32_t y = 0; y < sc.h; ++y)
    for (uint32_t x = 0; x < sc.w; ++x) {
      if (x < sc.w / 2) {
        sc.color(0, x, y) = glm::vec4(0.5f, 0.2f, 0.1f, 1.0f);
        sc.depth(0, x, y) = 0.3f;
      }
      if (y >= sc.h / 2) {
        sc.color(1, x, y) = glm::vec4(0.1f, 0.5f, 0.1f, 1.0f);
        sc.depth(1, x, y) = 0.6f;
      }
    }
  const size_t corners = size_t(sc.gridX()) * sc.gridY();
  for (size_t i = 0; i < corners; ++i) {
    sc.disp[i] = {2, 1};
    sc.prev[i] = {1, 1};
    sc.disp[corners + i] = {0, -1};
    sc.prev[corners + i] = {0, 2};
  }
  sc.background = false;
  const Result r = run(sc);
  auto at = [&](uint32_t x, uint32_t y) { return r.motion[size_t(y) * sc.w + x]; };
  EXPECT_EQ(at(10, 10), glm::vec2(1, 0)) << "layer 0 frontmost";
  EXPECT_EQ(at(10, 40), glm::vec2(1, 0)) << "layer 0 in front of layer 1";
  EXPECT_EQ(at(50, 40), glm::vec2(0, -3)) << "layer 1 frontmost";
  EXPECT_EQ(at(50, 10), sc.motionClear) << "no vegetation: the host's motion is left alone";
  sc.motionValid = false;  // e.g. the first frame: no previous displacement
  const Result first = run(sc);
  EXPECT_EQ(first.motion[size_t(10) * sc.w + 10], glm::vec2(0, 0));
  EXPECT_EQ(first.motion[size_t(10) * sc.w + 50], sc.motionClear);
}

// Random sparse layers, a random trunk and scene, a random smooth warp of up to 6 px.
Scene randomScene(uint32_t seed) {
  Scene sc;
  sc.w = 96;
  sc.h = 72;
  sc.resize(4);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (uint32_t l = 0; l < sc.n; ++l)
    for (int blob = 0; blob < 12; ++blob) {
      const glm::vec2 c(u(rng) * sc.w, u(rng) * sc.h);
      const float radius = 3.0f + 8.0f * u(rng);
      const glm::vec3 rgb(u(rng), u(rng), u(rng));
      const float a = u(rng) < 0.5f ? 1.0f : 0.2f + 0.7f * u(rng);
      const float z = 0.2f + 0.15f * float(l) + 0.1f * u(rng);
      for (uint32_t y = 0; y < sc.h; ++y)
        for (uint32_t x = 0; x < sc.w; ++x)
          if (glm::length(glm::vec2(x + 0.5f, y + 0.5f) - c) < radius) {
            sc.color(l, x, y) = glm::vec4(rgb * a, a);
            sc.depth(l, x, y) = z;
          }
    }
  for (uint32_t y = 0; y < sc.h; ++y)
    for (uint32_t x = 0; x < sc.w; ++x) {
      const size_t i = size_t(y) * sc.w + x;
      if (x > 40 && x < 52) {
        sc.bgColor[i] = glm::vec4(0.4f, 0.25f, 0.1f, 1.0f);
        sc.bgDepth[i] = 0.55f;
      }
      sc.sceneColor[i] = glm::vec4(0.2f, 0.3f, 0.6f, 1.0f);
      sc.sceneDepth[i] = y > 60 ? 0.35f : 1.0f;
    }
  for (glm::vec2& d : sc.disp) d = glm::vec2(12.0f * u(rng) - 6.0f, 12.0f * u(rng) - 6.0f);
  for (glm::vec2& d : sc.prev) d = glm::vec2(12.0f * u(rng) - 6.0f, 12.0f * u(rng) - 6.0f);
  return sc;
}

TEST_F(CompositeTest, MatchesTheCpuReferenceAndTheLeversLeaveTheImageAlone) {
 for (CompositePath path : {CompositePath::Compute, CompositePath::Fragment}) {
  SCOPED_TRACE(path == CompositePath::Compute ? "compute path" : "fragment path");
  Scene sc = randomScene(5);
  sc.params.path = path;
  sc.params.earlyExit = false;
  sc.params.skipEmptyTiles = false;
  const Result plain = run(sc);
  sc.params.earlyExit = true;
  sc.params.skipEmptyTiles = true;
  const Result fast = run(sc);
  const CompositeReferenceOutputs ref = reference(sc, fast.push);
  float leverWorst = 0.0f;
  size_t colourOff = 0, depthOff = 0, motionOff = 0;
  double sum = 0;
  for (size_t i = 0; i < sc.pixels(); ++i) {
    leverWorst = std::max(leverWorst, maxDiff(plain.color[i], fast.color[i]));
    EXPECT_EQ(plain.depth[i], fast.depth[i]);
    const float e = maxDiff(fast.color[i], ref.color[i]);
    sum += e;
    colourOff += e > 3.0f / 255.0f;
    depthOff += std::abs(fast.depth[i] - ref.depth[i]) > 1e-6f;
    const glm::vec2 wantMotion = ref.vegetationFront[i] ? ref.motion[i] : sc.motionClear;
    motionOff += glm::length(fast.motion[i] - wantMotion) > 0.02f;
  }
  EXPECT_LE(leverWorst, 2.0f / 1024.0f) << "early exit and the empty-tile skip must not change the image";
  const double mean = sum / double(sc.pixels());
  EXPECT_LE(mean, 0.5 / 255.0) << "mean colour error against the CPU reference";
  EXPECT_LE(colourOff, sc.pixels() / 200) << "pixels more than 3/255 off the CPU reference";
  EXPECT_LE(depthOff, sc.pixels() / 100) << "pixels whose depth differs from the CPU reference";
  EXPECT_LE(motionOff, sc.pixels() / 100) << "pixels whose motion differs from the CPU reference";
  // The warp's filter at both ends of its range (issue 67: 1 is plain bilinear, 8 nearly nearest):
  // each against its reference, and the two must differ (the sharpening is not a no-op).
  for (float k : {1.0f, 8.0f}) {
    SCOPED_TRACE(k);
    sc.params.sharpness = k;
    const Result sharp = run(sc);
    EXPECT_FLOAT_EQ(sharp.push.sharpness, k);
    const CompositeReferenceOutputs refSharp = reference(sc, sharp.push);
    size_t sharpOff = 0, fromDefault = 0;
    for (size_t i = 0; i < sc.pixels(); ++i) {
      sharpOff += maxDiff(sharp.color[i], refSharp.color[i]) > 3.0f / 255.0f;
      fromDefault += maxDiff(sharp.color[i], fast.color[i]) > 3.0f / 255.0f;
    }
    EXPECT_LE(sharpOff, sc.pixels() / 100);
    EXPECT_GE(fromDefault, sc.pixels() / 100) << "a filter of " << k << " gave the default filter's image";
  }
  sc.params.sharpness = CompositeParams{}.sharpness;
  // Nearest sampling: the other sampling mode against its reference.
  sc.params.bilinear = false;
  const Result nearest = run(sc);
  const CompositeReferenceOutputs refNearest = reference(sc, nearest.push);
  size_t nearestOff = 0;
  for (size_t i = 0; i < sc.pixels(); ++i) nearestOff += maxDiff(nearest.color[i], refNearest.color[i]) > 3.0f / 255.0f;
  EXPECT_LE(nearestOff, sc.pixels() / 100);
 }
}

// Issue 15: the compute path's tile lists never drop a contributing layer. Small leaves on empty
// layers, displaced by up to ~3 tiles so each lands in tiles its layer does not occupy (and across
// tile borders): the classified kernel must give the unclassified kernel's image (every tile
// listing every layer), and both the fragment path's.
TEST_F(CompositeTest, TileListsNeverDropALayerCarriedAcrossTileBorders) {
  Scene sc;
  sc.w = 96;
  sc.h = 72;
  sc.resize(3);
  std::mt19937 rng(15);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (uint32_t l = 0; l < sc.n; ++l)
    for (int leaf = 0; leaf < 6; ++leaf) {
      const uint32_t cx = 20 + uint32_t(u(rng) * 56), cy = 16 + uint32_t(u(rng) * 40);
      for (uint32_t y = cy - 2; y <= cy + 2; ++y)
        for (uint32_t x = cx - 2; x <= cx + 2; ++x) {
          sc.color(l, x, y) = glm::vec4(0.2f * float(l + 1), 0.6f, 0.1f, 1.0f);
          sc.depth(l, x, y) = 0.2f + 0.2f * float(l);
        }
    }
  // A smooth warp of up to 22 px (the tile is 8 px), different per layer and corner.
  for (uint32_t l = 0; l < sc.n; ++l)
    for (uint32_t gy = 0; gy < sc.gridY(); ++gy)
      for (uint32_t gx = 0; gx < sc.gridX(); ++gx)
        sc.disp[(size_t(l) * sc.gridY() + gy) * sc.gridX() + gx] =
            glm::vec2(22.0f * std::sin(0.5f * float(gx) + float(l)), 22.0f * std::cos(0.4f * float(gy) + 2.0f * float(l)));
  sc.prev = sc.disp;
  sc.background = false;
  sc.params.path = CompositePath::Compute;
  sc.params.skipEmptyTiles = true;
  const Result classified = run(sc);
  // Listed tiles per workgroup of the tile kernel: one (GPUs), a count that leaves a partial last
  // group, and more than the whole list — the same pixels every time.
  for (uint32_t perGroup : {1u, 3u, 64u}) {
    SCOPED_TRACE("tilesPerGroup " + std::to_string(perGroup));
    sc.tilesPerGroup = perGroup;
    const Result grouped = run(sc);
    size_t differGroup = 0;
    for (size_t i = 0; i < sc.pixels(); ++i)
      differGroup += classified.color[i] != grouped.color[i] || classified.depth[i] != grouped.depth[i];
    EXPECT_EQ(differGroup, 0u);
  }
  sc.tilesPerGroup = 0;
  sc.params.skipEmptyTiles = false;
  const Result unclassified = run(sc);
  sc.params.path = CompositePath::Fragment;
  const Result fragment = run(sc);
  size_t covered = 0, differ = 0, differFragment = 0;
  for (size_t i = 0; i < sc.pixels(); ++i) {
    covered += unclassified.color[i].a > 0.0f && unclassified.color[i] != glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
    differ += maxDiff(classified.color[i], unclassified.color[i]) > 0.0f || classified.depth[i] != unclassified.depth[i];
    differFragment += maxDiff(classified.color[i], fragment.color[i]) > 3.0f / 255.0f;
  }
  EXPECT_GT(covered, 200u) << "the warped leaves must cover pixels for the test to mean anything";
  EXPECT_EQ(differ, 0u) << "the tile lists dropped a layer somewhere";
  EXPECT_LE(differFragment, sc.pixels() / 200) << "compute and fragment paths disagree";
}

// A warp whose corners differ by up to 150 px between neighbours: each screen tile's source
// rectangle spans most of the layer (up to 19 occupancy tiles across, clamped at the image's
// edges), which the classification asks of the occupancy's summed-area table in four reads. The
// classified image is the unclassified one, pixel for pixel.
TEST_F(CompositeTest, TileListsStayExactWhenAWarpSpansMostOfTheLayer) {
  Scene sc;
  sc.w = 200;
  sc.h = 40;
  sc.resize(2);
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (uint32_t l = 0; l < sc.n; ++l)
    for (int leaf = 0; leaf < 5; ++leaf) {
      const uint32_t cx = 4 + uint32_t(u(rng) * 190), cy = 4 + uint32_t(u(rng) * 30);
      for (uint32_t y = cy - 2; y <= cy + 2; ++y)
        for (uint32_t x = cx - 2; x <= cx + 2; ++x) {
          sc.color(l, x, y) = glm::vec4(0.3f + 0.4f * float(l), 0.5f, 0.2f, 1.0f);
          sc.depth(l, x, y) = 0.3f + 0.3f * float(l);
        }
    }
  for (uint32_t l = 0; l < sc.n; ++l)
    for (uint32_t gy = 0; gy < sc.gridY(); ++gy)
      for (uint32_t gx = 0; gx < sc.gridX(); ++gx)
        sc.disp[(size_t(l) * sc.gridY() + gy) * sc.gridX() + gx] =
            glm::vec2(((gx + gy + l) % 2 ? 75.0f : -75.0f) * u(rng), 6.0f * (u(rng) - 0.5f));
  sc.prev = sc.disp;
  sc.params.path = CompositePath::Compute;
  sc.params.skipEmptyTiles = true;
  const Result classified = run(sc);
  sc.params.skipEmptyTiles = false;
  const Result unclassified = run(sc);
  size_t covered = 0, differ = 0;
  for (size_t i = 0; i < sc.pixels(); ++i) {
    covered += unclassified.color[i].a > 0.0f && unclassified.color[i] != glm::vec4(0.0f, 0.0f, 0.0f, 1.0f);
    differ += maxDiff(classified.color[i], unclassified.color[i]) > 0.0f || classified.depth[i] != unclassified.depth[i];
  }
  EXPECT_GT(covered, 200u) << "the warped leaves must cover pixels for the test to mean anything";
  EXPECT_EQ(differ, 0u) << "the tile lists dropped a layer somewhere";
}

// All 32 layers (the most a context allows) with the rigid background: the compute path's tile
// lists carry layer 31 and the background apart, and match the fragment path.
TEST_F(CompositeTest, ThirtyTwoLayersAndTheBackgroundKeepTheirOwnBitsInTheTileLists) {
  Scene sc;
  sc.w = 32;
  sc.h = 24;
  sc.resize(32);
  for (uint32_t y = 4; y < 12; ++y)
    for (uint32_t x = 4; x < 12; ++x) {
      sc.color(31, x, y) = glm::vec4(0.1f, 0.7f, 0.2f, 1.0f);
      sc.depth(31, x, y) = 0.4f;
    }
  for (uint32_t y = 0; y < sc.h; ++y)
    for (uint32_t x = 20; x < 26; ++x) {
      sc.bgColor[size_t(y) * sc.w + x] = glm::vec4(0.4f, 0.25f, 0.1f, 1.0f);
      sc.bgDepth[size_t(y) * sc.w + x] = 0.6f;
    }
  sc.params.path = CompositePath::Compute;
  const Result compute = run(sc);
  sc.params.path = CompositePath::Fragment;
  const Result fragment = run(sc);
  size_t differ = 0;
  for (size_t i = 0; i < sc.pixels(); ++i) differ += maxDiff(compute.color[i], fragment.color[i]) > 3.0f / 255.0f;
  EXPECT_EQ(differ, 0u);
  EXPECT_GT(compute.color[size_t(8) * sc.w + 8].g, 0.6f) << "layer 31 drawn";
  EXPECT_GT(compute.color[size_t(8) * sc.w + 22].r, 0.35f) << "background drawn";
}

TEST_F(CompositeTest, RefusesBadFormatsAndParameters) {
  CompositorDesc d;
  d.width = 16;
  d.height = 16;
  d.depthFormat = VK_FORMAT_S8_UINT;  // no depth aspect (depth-stencil formats are accepted: embedding_test.cpp)
  Compositor c;
  Status s = createCompositor(dev, d, &c);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("depth format"), std::string::npos) << s.message();
  d.depthFormat = VK_FORMAT_D32_SFLOAT;
  d.motionFormat = VK_FORMAT_R8G8B8A8_UNORM;
  s = createCompositor(dev, d, &c);
  EXPECT_NE(s.message().find("motion format"), std::string::npos) << s.message();
  d.motionFormat = VK_FORMAT_UNDEFINED;
  d.tilesPerGroup = 65;
  s = createCompositor(dev, d, &c);
  EXPECT_NE(s.message().find("tilesPerGroup = 65 is outside 0..64"), std::string::npos) << s.message();
  CompositeParams p;
  p.depthAlpha = 0.0f;
  s = validateCompositeParams(p);
  EXPECT_NE(s.message().find("depthAlpha"), std::string::npos) << s.message();
  for (float k : {0.5f, 9.0f, std::nanf("")}) {
    p = CompositeParams{};
    p.sharpness = k;
    s = validateCompositeParams(p);
    EXPECT_NE(s.message().find("sharpness"), std::string::npos) << k << ": " << s.message();
  }
}

}  // namespace
