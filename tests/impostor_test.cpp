// Impostors (issue 18; seed 002, Lluch et al.; docs/design.md "Impostors") on the device, under
// the validation helper: a box's baked view against a direct orthographic render of its leaves,
// the layers at the switch distance against the full-geometry layers, a continuous (monotone)
// transition across the band, the box order leaving the layers unchanged when impostors are off,
// and the refusals.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include <glm/gtc/matrix_transform.hpp>

#include "render/foliage_boxes.h"
#include "render/layers.h"
#include "tests/gpu_test.h"
#include "tests/layer_render.h"
#include "tools/image_io.h"
#include "tools/own_device.h"
#include "tools/scene_generator.h"

using namespace canopy;
using canopy::test::GpuTest;

namespace {

class ImpostorTest : public GpuTest {};

VegetationModel treeWithBoxes(uint64_t faces = 12000, SceneKind kind = SceneKind::TreeCrown) {
  SceneDesc sd;
  sd.kind = kind;
  sd.faces = faces;
  sd.textureSize = 64;
  sd.boxes = true;
  VegetationModel m;
  EXPECT_TRUE(generateScene(sd, &m).ok());
  return m;
}

Status renderOnce(Device& dev, LayeredVegetation& lv, const LayerView& view) {
  return canopy::test::renderLayersOnce(dev, lv, view);
}

// All layers flattened front to back ("over", premultiplied): what the layers show together.
std::vector<glm::vec4> flatten(LayeredVegetation& lv) {
  std::vector<glm::vec4> out(size_t(lv.desc.width) * lv.desc.height, glm::vec4(0.0f));
  for (uint32_t l = 0; l < lv.settings.layout.count(); ++l) {
    std::vector<glm::vec4> px;
    EXPECT_TRUE(readLayerColor(lv, l, &px).ok());
    for (size_t i = 0; i < out.size(); ++i) out[i] += px[i] * (1.0f - out[i].a);
  }
  return out;
}

std::string outputDir() {
  const std::string dir = std::string(CANOPY_TEST_OUTPUT) + "/impostors";
  std::filesystem::create_directories(dir);
  return dir;
}

// Image comparison: mean absolute difference of premultiplied RGBA over the pixels either image
// covers (alpha > 1/255), and the coverage agreement (pixels with alpha > 0.5 in both over those
// in either). A diff image is written on request (failures).
struct ImageDiff {
  double meanAbs = 0, coverageIoU = 1;
  uint64_t covered = 0;
};
ImageDiff compareImages(const std::vector<glm::vec4>& a, const std::vector<glm::vec4>& b) {
  ImageDiff d;
  double sum = 0;
  uint64_t both = 0, either = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].a <= 1.0f / 255 && b[i].a <= 1.0f / 255) continue;
    d.covered++;
    const glm::vec4 e = glm::abs(a[i] - b[i]);
    sum += (e.r + e.g + e.b + e.a) / 4.0;
    const bool ia = a[i].a > 0.5f, ib = b[i].a > 0.5f;
    both += ia && ib;
    either += ia || ib;
  }
  d.meanAbs = d.covered ? sum / double(d.covered) : 0.0;
  d.coverageIoU = either ? double(both) / double(either) : 1.0;
  return d;
}
void writeDiff(const std::string& name, uint32_t w, uint32_t h, const std::vector<glm::vec4>& a,
               const std::vector<glm::vec4>& b) {
  std::vector<uint8_t> rgba(size_t(w) * h * 4 * 3);
  // Three panels side by side: a, b, |a - b| x 4.
  const uint32_t W = 3 * w;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      const glm::vec4 panels[3] = {a[i], b[i], glm::min(glm::abs(a[i] - b[i]) * 4.0f, glm::vec4(1.0f))};
      for (int p = 0; p < 3; ++p) {
        uint8_t* o = &rgba[(size_t(y) * W + p * w + x) * 4];
        for (int c = 0; c < 3; ++c) o[c] = uint8_t(std::clamp(panels[p][c] + (1.0f - panels[p].a) * (p < 2 ? 0.2f : 0.0f), 0.0f, 1.0f) * 255.0f);
        o[3] = 255;
      }
    }
  (void)writePng(outputDir() + "/" + name + ".png", W, h, rgba);
}

LayerView lookFrom(glm::vec3 eye, glm::vec3 target, uint32_t w, uint32_t h, float fovDegrees = 40.0f) {
  LayerView v;
  v.view = glm::lookAt(eye, target, glm::vec3(0, 1, 0));
  v.proj = perspectiveVulkan(glm::radians(fovDegrees), float(w) / float(h), 0.1f, 1000.0f);
  return v;
}

// The largest box with views (the top one: maxLevel 0 bakes one box per plant).
const ImpostorNode* largestBaked(const LayeredVegetation& lv) {
  const ImpostorNode* best = nullptr;
  for (const ImpostorNode& n : lv.impostors.nodes)
    if (n.firstTile != kNoTile && (!best || n.radius > best->radius)) best = &n;
  return best;
}

// The node's view k as RGBA float (premultiplied), read from its atlas tile.
std::vector<glm::vec4> readTile(Device& dev, LayeredVegetation& lv, const ImpostorNode& n, uint32_t k) {
  const Impostors& imp = lv.impostors;
  const uint32_t tile = n.firstTile + k - imp.firstView, perLayer = imp.tilesPerLayer(), side = imp.tilesPerRow * imp.tileSize;
  std::vector<uint8_t> texels(size_t(side) * imp.rowsPerLayer * imp.tileSize * 4);
  EXPECT_TRUE(readbackImage(dev, imp.color, tile / perLayer, 4, texels.data(), rg::stateOf(rg::Use::FragmentSampled)).ok());
  const uint32_t tx = (tile % perLayer) % imp.tilesPerRow, ty = (tile % perLayer) / imp.tilesPerRow, T = imp.tileSize;
  std::vector<glm::vec4> out(size_t(T) * T);
  for (uint32_t y = 0; y < T; ++y)
    for (uint32_t x = 0; x < T; ++x) {
      const uint8_t* p = &texels[((size_t(ty * T + y)) * side + tx * T + x) * 4];
      out[size_t(y) * T + x] = glm::vec4(p[0], p[1], p[2], p[3]) / 255.0f;
    }
  return out;
}

TEST_F(ImpostorTest, AViewMatchesADirectOrthographicRenderOfItsLeaves) {
  VegetationModel m = treeWithBoxes();
  LayeredVegetationDesc d;
  d.width = d.height = 128;
  d.impostors.enable = true;
  d.impostors.tilePixels = 64;
  d.impostors.maxLevel = 2;
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
  ASSERT_GT(lv.impostors.baked, 2u);
  EXPECT_EQ(lv.stats.impostorTilePixels, 64u);
  // The box under test: the model's own box with the most leaves at a level, its subtree's
  // triangles collected from the model's hierarchy, not from the impostor code.
  std::vector<uint8_t> foliage(m.triangleCount());
  for (size_t t = 0; t < foliage.size(); ++t) foliage[t] = lv.mesh.split.role[m.triangleMaterial[t]] == MaterialRole::Foliage;
  BoxHierarchy h;
  ASSERT_TRUE(boxesFromModel(m, foliage, &h).ok());
  auto inSubtree = [&](uint32_t b, uint32_t root) {
    for (; b != kNoBox; b = h.boxes[b].parent)
      if (b == root) return true;
    return false;
  };
  // Raw levels 2 and 3: the tree's bracketed axiom (the plant and scene boxes above it are its
  // twins, with the same leaves, and get no views) and its first branches.
  for (uint32_t level : {2u, 3u}) {
    uint32_t box = kNoBox;
    uint64_t most = 0;
    for (uint32_t b = 0; b < h.boxes.size(); ++b) {
      if (h.boxes[b].level != level) continue;
      uint64_t n = 0;
      for (uint32_t t = 0; t < m.triangleCount(); ++t) n += foliage[t] && inSubtree(m.triangleBox[t], b);
      if (n > most) most = n, box = b;
    }
    ASSERT_NE(box, kNoBox);
    const glm::vec3 c = 0.5f * (h.boxes[box].boundsMin + h.boxes[box].boundsMax);
    const ImpostorNode* node = nullptr;
    for (const ImpostorNode& n : lv.impostors.nodes)
      if (n.firstTile != kNoTile && glm::length(n.center - c) < 1e-5f && n.level == level) node = &n;
    ASSERT_NE(node, nullptr) << "level " << level << " box " << box << " was not baked";
    // The sub-model: that subtree's foliage only.
    VegetationModel sub = m;
    sub.path.clear();
    sub.indices.clear();
    sub.triangleMaterial.clear();
    sub.boxParent.clear();
    sub.triangleBox.clear();
    sub.bend.clear();
    sub.branches.clear();
    for (uint32_t t = 0; t < m.triangleCount(); ++t) {
      if (!foliage[t] || !inSubtree(m.triangleBox[t], box)) continue;
      for (int k = 0; k < 3; ++k) sub.indices.push_back(m.indices[3 * size_t(t) + k]);
      sub.triangleMaterial.push_back(m.triangleMaterial[t]);
    }
    sub.boundsMin = h.boxes[box].boundsMin;
    sub.boundsMax = h.boxes[box].boundsMax;
    for (uint32_t k : {6u, 7u, 9u, 11u}) {
      // The same orthographic camera, with the view's direction as the viewer's (the leaf shading's
      // view vector), rendered by the layers into one layer of the tile's size.
      const gpu::ImpostorFrame fr = gpu::impostorFrameOf(k);
      LayerView v;
      v.view = glm::mat4(1.0f);
      for (int col = 0; col < 3; ++col) {
        v.view[col][0] = fr.u[col];
        v.view[col][1] = fr.v[col];
        v.view[col][2] = fr.n[col];
      }
      v.proj = impostorViewProj(*node, k) * glm::inverse(v.view);
      LayeredVegetationDesc sd;
      sd.width = sd.height = lv.impostors.tileSize;
      sd.settings.layout = LayerLayout{{1, 0, 0}};
      LayeredVegetation direct;
      ASSERT_TRUE(createLayeredVegetation(dev, sub, sd, &direct).ok());
      ASSERT_TRUE(renderOnce(dev, direct, v).ok());
      std::vector<glm::vec4> want;
      ASSERT_TRUE(readLayerColor(direct, 0, &want).ok());
      destroyLayeredVegetation(direct);
      const std::vector<glm::vec4> got = readTile(dev, lv, *node, k);
      const ImageDiff diff = compareImages(got, want);
      // Stated metric: mean |RGBA difference| over covered pixels <= 0.02 (the atlas is 8-bit, the
      // layers half floats), coverage IoU >= 0.97, and the box covers a real part of its image.
      EXPECT_GT(diff.covered, uint64_t(lv.impostors.tileSize) * lv.impostors.tileSize / 20) << "view " << k;
      EXPECT_LE(diff.meanAbs, 0.02) << "level " << level << " view " << k;
      EXPECT_GE(diff.coverageIoU, 0.97) << "level " << level << " view " << k;
      if (diff.meanAbs > 0.02 || diff.coverageIoU < 0.97)
        writeDiff("view_level" + std::to_string(level) + "_k" + std::to_string(k), lv.impostors.tileSize, lv.impostors.tileSize, got, want);
    }
  }
  destroyLayeredVegetation(lv);
}

TEST_F(ImpostorTest, WithImpostorsOffTheBoxOrderDrawsTheSameLayers) {
  VegetationModel m = treeWithBoxes();
  LayeredVegetationDesc d;
  d.width = 160;
  d.height = 120;
  LayeredVegetation plain, boxed;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &plain).ok());
  d.impostors.enable = true;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &boxed).ok());
  const glm::vec3 c = 0.5f * (m.boundsMin + m.boundsMax);
  const float r = glm::length(m.boundsMax - m.boundsMin);
  const LayerView v = lookFrom(c + glm::vec3(0.3f, 0.2f, 1.0f) * r, c, d.width, d.height);
  ASSERT_TRUE(renderOnce(dev, plain, v).ok());
  ASSERT_TRUE(renderOnce(dev, boxed, v).ok());
  for (uint32_t l = 0; l < plain.settings.layout.count(); ++l) {
    std::vector<glm::vec4> a, b;
    ASSERT_TRUE(readLayerColor(plain, l, &a).ok());
    ASSERT_TRUE(readLayerColor(boxed, l, &b).ok());
    const ImageDiff diff = compareImages(a, b);
    EXPECT_LE(diff.meanAbs, 1e-3) << "layer " << l;
    EXPECT_GE(diff.coverageIoU, 0.999) << "layer " << l;
  }
  EXPECT_EQ(boxed.stats.lastImpostors, 0u);
  destroyLayeredVegetation(plain);
  destroyLayeredVegetation(boxed);
}

// One tree seen from where its top box's projected size is P pixels.
struct SwitchScene {
  VegetationModel m;
  LayerView view;
  float projected = 0;  // the plant box's projected size from `view`
};
SwitchScene switchScene(uint32_t w, uint32_t h, float distanceInRadii, glm::vec3 from = glm::vec3(0.4f, 0.15f, 1.0f)) {
  SwitchScene s;
  s.m = treeWithBoxes();
  const glm::vec3 c = 0.5f * (s.m.boundsMin + s.m.boundsMax);
  const float radius = 0.5f * glm::length(s.m.boundsMax - s.m.boundsMin);
  s.view = lookFrom(c + glm::normalize(from) * radius * distanceInRadii, c, w, h, 30.0f);
  return s;
}
// The projected size (bounding-sphere diameter, pixels) of the box the cut measures.
float projectedSize(const ImpostorNode& n, const LayerView& v, uint32_t h) {
  const float z = -(v.view * glm::vec4(n.center, 1.0f)).z;
  return 2.0f * n.radius * std::abs(v.proj[1][1]) * 0.5f * float(h) / z;
}

// The scene's layers with views for the tree's top box only (128 px), its projected size measured.
Status createSwitchLayers(Device& dev, SwitchScene& sc, uint32_t w, uint32_t h, LayeredVegetation* lv,
                          LayerDrawMode draw = LayerDrawMode::Auto, ImpostorViews views = ImpostorViews::Diagonal6,
                          float rebuildBudgetMs = 0.0f, uint32_t fixedSliceTriangles = 0) {
  LayeredVegetationDesc d;
  d.settings.rebuildBudgetMs = rebuildBudgetMs;
  d.settings.rigidMotion = RigidMotion::Still;  // the rigid chunks in the slices, as the background
  d.fixedSliceTriangles = fixedSliceTriangles;
  d.impostors.views = views;
  d.width = w;
  d.height = h;
  d.settings.draw = draw;
  d.impostors.enable = true;
  d.impostors.maxLevel = 0;
  d.impostors.tilePixels = 128;
  CANOPY_TRY(createLayeredVegetation(dev, sc.m, d, lv));
  const ImpostorNode* top = largestBaked(*lv);
  if (!top) return Status::error("no box has views");
  sc.projected = projectedSize(*top, sc.view, h);
  return Status();
}

TEST_F(ImpostorTest, AtTheSwitchDistanceTheImpostorLayerMatchesTheLeaves) {
  // Both view sets (the paper's six diagonal views, the default; twelve before 0.7), both ways of
  // drawing them, from three directions: along an axis, between the diagonal planes, and oblique.
  const uint32_t w = 256, h = 192;
  const glm::vec3 directions[3] = {{0.0f, 0.0f, 1.0f}, {0.4f, 0.15f, 1.0f}, {1.0f, 0.6f, 0.8f}};
  double sumIoU[2][2] = {}, sumAbs[2][2] = {};
  for (ImpostorViews views : {ImpostorViews::Diagonal6, ImpostorViews::FacesAndDiagonals12}) {
    const int vi = views == ImpostorViews::Diagonal6 ? 0 : 1;
    for (int dir = 0; dir < 3; ++dir) {
      SCOPED_TRACE(dir);
      SwitchScene sc = switchScene(w, h, 3.0f, directions[dir]);
      LayeredVegetation lv;
      ASSERT_TRUE(createSwitchLayers(dev, sc, w, h, &lv, LayerDrawMode::Auto, views).ok());
      EXPECT_EQ(lv.stats.impostorViewsPerBox, vi == 0 ? 6u : 12u);
      EXPECT_EQ(lv.stats.impostorBytesPerBox, uint64_t(lv.stats.impostorViewsPerBox) * 128 * 128 * 8);
      ASSERT_TRUE(renderOnce(dev, lv, sc.view).ok());
      const std::vector<glm::vec4> leaves = flatten(lv);
      EXPECT_EQ(lv.stats.lastImpostors, 0u);
      for (ImpostorShape shape : {ImpostorShape::CrossedPolygons, ImpostorShape::FacingPolygon}) {
        const int si = shape == ImpostorShape::CrossedPolygons ? 0 : 1;
        LayerSettings s = lv.settings;
        s.impostors.mode = ImpostorMode::ByProjectedSize;
        s.impostors.shape = shape;
        s.impostors.band = 0.0f;
        s.impostors.switchPixels = sc.projected * 1.001f;  // the box is exactly at its switch
        ASSERT_TRUE(setLayerSettings(lv, s).ok());
        ASSERT_TRUE(renderOnce(dev, lv, sc.view).ok());
        EXPECT_EQ(lv.stats.lastImpostors, 1u);
        EXPECT_EQ(lv.stats.lastFadingBoxes, 0u);
        EXPECT_EQ(lv.stats.lastDrawnTriangles, 0u);  // every leaf is under the plant box
        // The impostor lands whole in the layer of its root.
        const ImpostorNode* plant = largestBaked(lv);
        ASSERT_NE(plant, nullptr);
        const uint32_t rootLayer =
            gpu::layerOfDepth(lv.visible.frame, glm::dot(lv.visible.frame.depthRow, glm::vec4(plant->root, 1.0f)));
        std::vector<glm::vec4> impostor;
        for (uint32_t l = 0; l < lv.settings.layout.count(); ++l) {
          std::vector<glm::vec4> px;
          ASSERT_TRUE(readLayerColor(lv, l, &px).ok());
          double alpha = 0;
          for (const glm::vec4& p : px) alpha += p.a;
          if (l == rootLayer) {
            EXPECT_GT(alpha, 100.0) << "the impostor's layer " << l << " is empty";
            impostor = px;
          } else {
            EXPECT_EQ(alpha, 0.0) << "layer " << l << " holds impostor pixels outside its root's layer " << rootLayer;
          }
        }
        // Stated metric against the full-geometry layers flattened: coverage IoU >= 0.6 (>= 0.5 for
        // six diagonal views on one facing polygon, a combination kept for comparison: seen along
        // an axis no diagonal view faces the viewer), mean |RGBA difference| over covered pixels
        // <= 0.25 (Lluch's impostor is an approximation: the views are 8-bit images resampled, a
        // box's leaves seen from one of a few directions).
        const double minIoU = vi == 0 && si == 1 ? 0.5 : 0.6;
        const ImageDiff diff = compareImages(impostor, leaves);
        std::printf("switch distance, %s, %s, direction %d: %.1f px box, impostor vs leaves: mean |d| %.4f, coverage IoU %.3f over %llu px\n",
                    vi == 0 ? "6 diagonal views" : "12 views", si == 0 ? "crossed polygons" : "facing polygon", dir,
                    sc.projected, diff.meanAbs, diff.coverageIoU, (unsigned long long)diff.covered);
        sumIoU[vi][si] += diff.coverageIoU / 3.0;
        sumAbs[vi][si] += diff.meanAbs / 3.0;
        EXPECT_GE(diff.coverageIoU, minIoU);
        EXPECT_LE(diff.meanAbs, 0.25);
        if (diff.coverageIoU < minIoU || diff.meanAbs > 0.25)
          writeDiff("switch_layer_" + std::to_string(vi) + std::to_string(si) + std::to_string(dir), w, h, impostor, leaves);
      }
      destroyLayeredVegetation(lv);
    }
  }
  for (int vi = 0; vi < 2; ++vi)
    for (int si = 0; si < 2; ++si)
      std::printf("mean over the directions, %s, %s: mean |d| %.4f, coverage IoU %.3f\n", vi == 0 ? "6 diagonal views" : "12 views",
                  si == 0 ? "crossed polygons" : "facing polygon", sumAbs[vi][si], sumIoU[vi][si]);
  // The paper's six views are worth drawing as its crossed polygons: closer to the leaves than the
  // same views on one facing polygon, on both measures.
  EXPECT_GT(sumIoU[0][0], sumIoU[0][1]);
  EXPECT_LT(sumAbs[0][0], sumAbs[0][1]);
}

TEST_F(ImpostorTest, TheTransitionIsContinuousAcrossTheBand) {
  // The CPU weight every draw uses: monotone, 0 above (1 + band) x switch, 1 at the switch.
  float last = 0.0f;
  for (float p = 400.0f; p >= 10.0f; p -= 0.5f) {
    const float a = gpu::impostorSizeWeight(p, 100.0f, 0.5f);
    EXPECT_GE(a, last);
    last = a;
  }
  EXPECT_EQ(gpu::impostorSizeWeight(150.0f, 100.0f, 0.5f), 0.0f);
  EXPECT_EQ(gpu::impostorSizeWeight(100.0f, 100.0f, 0.5f), 1.0f);
  // The images: a fixed view, the switch swept so that the plant box's share goes 0 .. 1.
  const uint32_t w = 224, h = 168;
  SwitchScene sc = switchScene(w, h, 3.0f);
  LayeredVegetation lv;
  ASSERT_TRUE(createSwitchLayers(dev, sc, w, h, &lv).ok());
  const float band = 1.0f;
  std::vector<std::vector<glm::vec4>> images;
  const float shares[] = {0.0f, 0.2f, 0.4f, 0.6f, 0.8f, 1.0f};
  for (float a : shares) {
    LayerSettings s = lv.settings;
    s.impostors.mode = ImpostorMode::ByProjectedSize;
    s.impostors.band = band;
    // a = ((1 + band) S - P) / (band S)  =>  S = P / (1 + band - a band)
    s.impostors.switchPixels = sc.projected / (1.0f + band - a * band);
    ASSERT_TRUE(setLayerSettings(lv, s).ok());
    ASSERT_TRUE(renderOnce(dev, lv, sc.view).ok());
    const bool fading = a > 0.01f && a < 0.99f;
    EXPECT_EQ(lv.stats.lastFadingBoxes, fading ? 1u : 0u) << "share " << a;
    EXPECT_EQ(lv.stats.lastImpostors, a > 0.01f ? 1u : 0u) << "share " << a;
    images.push_back(flatten(lv));
  }
  // Continuity: the difference from the all-leaves image grows, the difference from the
  // all-impostor image shrinks, step by step (within 0.002 of noise), and no step jumps by more
  // than half the whole change (no pop).
  std::vector<double> fromLeaves, fromImpostor;
  for (const auto& img : images) {
    fromLeaves.push_back(compareImages(img, images.front()).meanAbs);
    fromImpostor.push_back(compareImages(img, images.back()).meanAbs);
  }
  for (size_t i = 0; i < images.size(); ++i)
    std::printf("share %.1f: |I - I(leaves)| %.4f, |I - I(impostor)| %.4f\n", shares[i], fromLeaves[i], fromImpostor[i]);
  ASSERT_GT(fromLeaves.back(), 0.01) << "the impostor changed nothing";
  for (size_t i = 1; i < images.size(); ++i) {
    EXPECT_GE(fromLeaves[i], fromLeaves[i - 1] - 0.002) << "step " << i;
    EXPECT_LE(fromImpostor[i], fromImpostor[i - 1] + 0.002) << "step " << i;
    EXPECT_LE(compareImages(images[i], images[i - 1]).meanAbs, 0.5 * fromLeaves.back()) << "step " << i;
  }
  destroyLayeredVegetation(lv);
}

TEST_F(ImpostorTest, OneDrawPerLayerGivesTheSingleDrawsImpostors) {
  // Devices without shaderOutputLayer draw each layer on its own, the impostor clipped to its
  // root's layer: the same layers as gl_Layer, fully switched and inside the band.
  const uint32_t w = 192, h = 144;
  SwitchScene sc = switchScene(w, h, 3.0f);
  LayeredVegetation single, perLayer;
  ASSERT_TRUE(createSwitchLayers(dev, sc, w, h, &single, LayerDrawMode::SinglePass).ok());
  ASSERT_TRUE(createSwitchLayers(dev, sc, w, h, &perLayer, LayerDrawMode::PerLayer).ok());
  // Also with every layer at half resolution (docs/design.md "Layers: half resolution"): both paths
  // draw the impostors and leaves into each layer's quarter alike, and nothing beyond it.
  const uint32_t layers = single.settings.layout.count();
  for (uint32_t half : {0u, layers})
  for (float share : {1.0f, 0.5f}) {
    for (LayeredVegetation* lv : {&single, &perLayer}) {
      LayerSettings s = lv->settings;
      s.halfResolutionLayers = half;
      s.impostors.mode = ImpostorMode::ByProjectedSize;
      s.impostors.band = 0.5f;
      s.impostors.switchPixels = sc.projected / (1.5f - share * 0.5f) * 1.001f;
      ASSERT_TRUE(setLayerSettings(*lv, s).ok());
      ASSERT_TRUE(renderOnce(dev, *lv, sc.view).ok());
      EXPECT_EQ(lv->stats.lastFadingBoxes, share < 1.0f ? 1u : 0u);
    }
    size_t covered = 0;
    for (uint32_t l = 0; l < single.settings.layout.count(); ++l) {
      std::vector<glm::vec4> a, b;
      ASSERT_TRUE(readLayerColor(single, l, &a).ok());
      ASSERT_TRUE(readLayerColor(perLayer, l, &b).ok());
      const ImageDiff diff = compareImages(a, b);
      EXPECT_LE(diff.meanAbs, 1e-3) << "share " << share << " layer " << l << " half " << half;
      EXPECT_GE(diff.coverageIoU, 0.999) << "share " << share << " layer " << l << " half " << half;
      if (!half) continue;
      const uint32_t lw = single.desc.width, lh = single.desc.height;
      size_t beyond = 0;
      for (uint32_t y = 0; y < lh; ++y)
        for (uint32_t x = 0; x < lw; ++x) {
          covered += a[size_t(y) * lw + x].a > 0.0f;
          beyond += a[size_t(y) * lw + x].a > 0.0f && (x >= (lw + 1) / 2 || y >= (lh + 1) / 2);
        }
      EXPECT_EQ(beyond, 0u) << "share " << share << " layer " << l << ": drawn beyond the quarter";
    }
    if (half) {
      std::printf("every layer at half resolution, impostor share %.1f: %zu texels covered\n", share, covered);
      EXPECT_GT(covered, 0u) << "share " << share;
    }
  }
  destroyLayeredVegetation(single);
  destroyLayeredVegetation(perLayer);
}

// Impostors with spread re-slicing (issue 34): the spread re-slice makes the cut for its own
// placement when that is done, draws the cut's leaves slice by slice (the opaque impostors with the
// first slice, the fading ones with the last) into the next set and fades it in; the layers it
// leaves are those a re-slice at once draws with the same cut, for both draw paths, fully switched
// and inside the band.
TEST_F(ImpostorTest, SpreadReslicingDrawsTheCutAsAReSliceAtOnceDoes) {
  const uint32_t w = 192, h = 144;
  for (LayerDrawMode mode : {LayerDrawMode::SinglePass, LayerDrawMode::PerLayer}) {
    if (mode == LayerDrawMode::SinglePass && !dev.shaderOutputLayer) continue;
    for (float share : {1.0f, 0.5f}) {
      SwitchScene sc = switchScene(w, h, 3.0f);
      LayeredVegetation spread, once;
      ASSERT_TRUE(createSwitchLayers(dev, sc, w, h, &spread, mode, ImpostorViews::Diagonal6, 2.0f, 500).ok());
      ASSERT_TRUE(createSwitchLayers(dev, sc, w, h, &once, mode).ok());
      uint64_t slices = 0;
      {
        rg::RenderGraph g;
        ASSERT_TRUE(addLayerPasses(spread, g, nullptr).ok());
        ASSERT_TRUE(g.compile().ok());
        ASSERT_TRUE(g.realize(dev).ok());
        auto frame = [&] {
          bool changed = false;
          Status st = updateLayerView(spread, sc.view, &changed);
          if (st.ok()) st = submitAndWait(dev, [&](VkCommandBuffer cmd) { return g.record(cmd); });
          return st;
        };
        ASSERT_TRUE(frame().ok());  // the first view: leaves only, at once
        EXPECT_EQ(spread.stats.lastImpostors, 0u);
        // Impostors on: a settings change, re-sliced over frames at the same camera.
        for (LayeredVegetation* lv : {&spread, &once}) {
          LayerSettings s = lv->settings;
          s.impostors.mode = ImpostorMode::ByProjectedSize;
          s.impostors.band = 0.5f;
          s.impostors.switchPixels = sc.projected / (1.5f - share * 0.5f) * 1.001f;
          ASSERT_TRUE(setLayerSettings(*lv, s).ok());
        }
        for (int i = 0; i < 1000 && (i == 0 || spread.stats.spreadPhase != 0); ++i) {
          ASSERT_TRUE(frame().ok());
          slices += spread.reslice.slicePending;
        }
        EXPECT_EQ(spread.stats.spreadPhase, 0u) << "the spread re-slice ends";
        EXPECT_EQ(spread.stats.spreadRebuilds, 1u);
        EXPECT_GT(slices, 2u) << "drawn over several slices";
        EXPECT_EQ(spread.stats.lastImpostors, 1u);
        EXPECT_EQ(spread.stats.lastFadingBoxes, share < 1.0f ? 1u : 0u);
        g.release(dev);
      }
      ASSERT_TRUE(renderOnce(dev, once, sc.view).ok());
      EXPECT_EQ(once.stats.lastImpostors, 1u);
      size_t covered = 0;
      for (uint32_t l = 0; l < once.settings.layout.count(); ++l) {
        std::vector<glm::vec4> a, b;
        ASSERT_TRUE(readLayerColor(spread, l, &a).ok());
        ASSERT_TRUE(readLayerColor(once, l, &b).ok());
        const ImageDiff diff = compareImages(a, b);
        EXPECT_LE(diff.meanAbs, 1e-3) << "share " << share << " layer " << l;
        EXPECT_GE(diff.coverageIoU, 0.999) << "share " << share << " layer " << l;
        for (const glm::vec4& c : b) covered += c.a > 0.0f;
      }
      std::printf("%s, impostor share %.1f: %llu slices, %zu texels covered, layers equal to a re-slice at once\n",
                  mode == LayerDrawMode::SinglePass ? "single pass" : "per layer", share, (unsigned long long)slices, covered);
      EXPECT_GT(covered, 0u);
      destroyLayeredVegetation(spread);
      destroyLayeredVegetation(once);
    }
  }
}

TEST_F(ImpostorTest, FarBoxesBecomeImpostorsAndNearOnesKeepTheirLeaves) {
  // A field: from a low camera the far plants are impostors (FarRegion), the near ones leaves.
  VegetationModel m = treeWithBoxes(60000, SceneKind::Field);
  LayeredVegetationDesc d;
  d.width = 256;
  d.height = 160;
  d.impostors.enable = true;
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
  const glm::vec3 lo = m.boundsMin, hi = m.boundsMax, c = 0.5f * (lo + hi);
  const LayerView v = lookFrom(glm::vec3(c.x, lo.y + 0.15f * (hi.y - lo.y) + 1.0f, hi.z + 0.05f * (hi.z - lo.z)),
                               glm::vec3(c.x, lo.y, lo.z), d.width, d.height, 60.0f);
  LayerSettings s = lv.settings;
  s.impostors.mode = ImpostorMode::FarRegion;
  s.impostors.switchPixels = 64;
  ASSERT_TRUE(setLayerSettings(lv, s).ok());
  ASSERT_TRUE(renderOnce(dev, lv, v).ok());
  const uint64_t all = lv.stats.foliageTriangles;
  std::printf("far region: %u impostors (%u fading), %llu of %llu foliage triangles drawn\n", lv.stats.lastImpostors,
              lv.stats.lastFadingBoxes, (unsigned long long)lv.stats.lastDrawnTriangles, (unsigned long long)all);
  EXPECT_GT(lv.stats.lastImpostors, 0u);
  EXPECT_GT(lv.stats.lastDrawnTriangles, 0u);
  EXPECT_LT(lv.stats.lastDrawnTriangles, all);
  // Every impostor's root is in the far region's layers or the band before it.
  const uint32_t far = lv.settings.layout.region[0] + lv.settings.layout.region[1];
  for (const gpu::ImpostorInstance& inst : lv.visible.impostors.instances) {
    const ImpostorNode* n = nullptr;
    for (const ImpostorNode& x : lv.impostors.nodes)
      if (x.gpuIndex == inst.box) n = &x;
    ASSERT_NE(n, nullptr);
    const float z = glm::dot(lv.visible.frame.depthRow, glm::vec4(n->root, 1.0f));
    EXPECT_GE(z, lv.visible.frame.boundaries[far] - s.impostors.band * (lv.visible.frame.boundaries[5] - lv.visible.frame.boundaries[0]) / 5.0f - 1e-3f);
  }
  // The debug view colours by level (a different image, the same coverage).
  std::vector<glm::vec4> normal = flatten(lv), debug;
  s.impostors.debugView = true;
  ASSERT_TRUE(setLayerSettings(lv, s).ok());
  ASSERT_TRUE(renderOnce(dev, lv, v).ok());
  debug = flatten(lv);
  const ImageDiff diff = compareImages(normal, debug);
  EXPECT_GT(diff.meanAbs, 0.02);
  EXPECT_GE(diff.coverageIoU, 0.99);
  destroyLayeredVegetation(lv);
}

TEST_F(ImpostorTest, TheBakedViewsAreCachedBesideTheLeafRoots) {
  // A model with a path and a cache folder: the first creation bakes and writes the views, the
  // second reads them (the same texels), another light bakes again.
  VegetationModel m = treeWithBoxes();
  const std::string dir = outputDir() + "/cache";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  m.path = dir + "/tree.glb";  // names the cache files only
  LayeredVegetationDesc d;
  d.width = d.height = 64;
  d.rootCacheDir = dir;
  d.impostors.enable = true;
  std::vector<glm::vec4> first, second;
  for (int run = 0; run < 3; ++run) {
    SCOPED_TRACE(run);
    if (run == 2) d.settings.lightDirection = Float3{-0.5f, 0.6f, -0.4f};
    LayeredVegetation lv;
    ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
    EXPECT_EQ(lv.stats.impostorCacheHit, run == 1) << lv.stats.impostorCacheNote;
    EXPECT_NE(lv.stats.impostorCacheNote.find(run == 1 ? "read " : "wrote it"), std::string::npos) << lv.stats.impostorCacheNote;
    if (run == 2) EXPECT_NE(lv.stats.impostorCacheNote.find("other data"), std::string::npos) << lv.stats.impostorCacheNote;
    const ImpostorNode* top = largestBaked(lv);
    ASSERT_NE(top, nullptr);
    std::vector<glm::vec4> tile;
    for (uint32_t k = lv.impostors.firstView; k < IMPOSTOR_VIEWS; ++k) {
      const std::vector<glm::vec4> t = readTile(dev, lv, *top, k);
      tile.insert(tile.end(), t.begin(), t.end());
    }
    (run == 0 ? first : second) = tile;
    if (run == 1) {
      // A cache round trip is exact: every texel of the views as baked.
      const ImageDiff diff = compareImages(first, second);
      EXPECT_EQ(diff.meanAbs, 0.0);
      EXPECT_GT(diff.covered, 0u);
    }
    destroyLayeredVegetation(lv);
  }
  EXPECT_TRUE(std::filesystem::exists(dir + "/tree.glb.impostors"));
}

TEST_F(ImpostorTest, AHostileCacheFolderNeitherRedirectsTheWriteNorStopsTheBake) {
  // Links at the views' (and leaf roots') final and temporary names, then a damaged, a FIFO and a
  // folder at the name (docs/design.md "Files"): each creation bakes, says why the file was not
  // used, and either writes a whole new cache or says why it could not; the linked file is
  // never written. tests/cache_files_test.cpp covers the format, cache_files_cli_test.sh the programs.
  VegetationModel m = treeWithBoxes();
  const std::string dir = outputDir() + "/hostile_cache";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string victim = outputDir() + "/hostile_cache_victim.txt";
  { std::ofstream(victim, std::ios::trunc) << "the user's own file"; }
  m.path = dir + "/tree.glb";  // names the cache files only
  const std::string views = dir + "/tree.glb.impostors";
  for (const std::string& name : {views, views + ".tmp", dir + "/tree.glb.leafroots", dir + "/tree.glb.leafroots.tmp"})
    std::filesystem::create_symlink(victim, name);
  LayeredVegetationDesc d;
  d.width = d.height = 64;
  d.rootCacheDir = dir;
  d.impostors.enable = true;
  auto create = [&](const std::string& expected) {
    LayeredVegetation lv;
    const auto t0 = std::chrono::steady_clock::now();
    ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_FALSE(lv.stats.impostorCacheHit);
    EXPECT_NE(lv.stats.impostorCacheNote.find(expected), std::string::npos) << lv.stats.impostorCacheNote;
    EXPECT_GT(lv.stats.impostorBakedBoxes, 0u);
    std::printf("[  NOTE    ] %.2f s: %s\n", s, lv.stats.impostorCacheNote.c_str());
    destroyLayeredVegetation(lv);
  };
  auto slurp = [](const std::string& path) {
    std::ifstream f(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  create("a symbolic link (not followed");
  EXPECT_EQ(slurp(victim), "the user's own file");
  EXPECT_FALSE(std::filesystem::is_symlink(views));
  EXPECT_TRUE(std::filesystem::is_symlink(views + ".tmp"));
  const std::string whole = slurp(views);
  ASSERT_GT(whole.size(), 64u);
  auto plant = [&](const std::string& bytes) { std::ofstream(views, std::ios::binary | std::ios::trunc) << bytes; };
  plant(whole.substr(0, whole.size() - 5));
  create("truncated");
  std::string flipped = whole;
  flipped[whole.size() / 2] = char(flipped[whole.size() / 2] ^ 0x20);
  plant(flipped);
  create("damaged: the contents' checksum does not match; wrote it");
  plant(whole + "x");
  create("oversized");
  std::filesystem::remove(views);
  ASSERT_EQ(::mkfifo(views.c_str(), 0600), 0);
  create("not a regular file (a FIFO); wrote it");
  std::filesystem::remove(views);
  std::filesystem::create_directory(views);
  create("not a regular file (a directory); not written: cannot write '" + std::string(views) + "': Is a directory");
  EXPECT_EQ(slurp(victim), "the user's own file");
}

TEST_F(ImpostorTest, WhatImpostorsNeedIsRefusedWithTheReason) {
  VegetationModel m = treeWithBoxes();
  LayeredVegetationDesc d;
  d.width = 64;
  d.height = 48;
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
  LayerSettings s = lv.settings;
  s.impostors.mode = ImpostorMode::FarRegion;
  Status st = setLayerSettings(lv, s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("CanopyDesc.impostors.enable"), std::string::npos) << st.message();
  destroyLayeredVegetation(lv);
  d.impostors.enable = true;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
  s = lv.settings;
  s.impostors.mode = ImpostorMode::ByProjectedSize;
  s.rebuildBudgetMs = 4.0f;  // spread re-slicing draws impostors too (since 0.7)
  st = setLayerSettings(lv, s);
  EXPECT_TRUE(st.ok()) << st.message();
  s.rebuildBudgetMs = 0.0f;
  s.impostors.switchPixels = 0.0f;
  st = setLayerSettings(lv, s);
  EXPECT_NE(st.message().find("switchPixels"), std::string::npos) << st.message();
  s.impostors.switchPixels = 64.0f;
  s.impostors.band = 9.0f;
  st = setLayerSettings(lv, s);
  EXPECT_NE(st.message().find("impostors.band"), std::string::npos) << st.message();
  destroyLayeredVegetation(lv);
  // A budget that holds not even one level at 8 pixels.
  d.impostors.memoryBudget = 1 << 10;
  st = createLayeredVegetation(dev, m, d, &lv);
  EXPECT_NE(st.message().find("memoryBudget"), std::string::npos) << st.message();
  // A budget that holds the top level only at smaller tiles: halved, not refused.
  d.impostors.memoryBudget = 1 << 20;
  d.impostors.tilePixels = 512;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
  EXPECT_LT(lv.stats.impostorTilePixels, 512u);
  EXPECT_LE(lv.stats.impostorBytes, uint64_t(1) << 20);
  destroyLayeredVegetation(lv);
}

// Issue 53: impostors for copies and species. Two species (a tree crown and a shrub, each with its
// own materials and texture, each baked once at its origin) placed as copies — the tree turned and
// scaled, the shrub tinted — seen from where each copy's plant box is at its switch: the layers
// with every copy an impostor against the same layers drawn from the leaves (the switch test's
// metric), then with the switch between the two copies' sizes, one impostor and one copy's leaves.
TEST_F(ImpostorTest, CopiesOfTwoSpeciesMatchTheirLeavesAtTheSwitchDistance) {
  const uint32_t w = 256, h = 192;
  const VegetationModel tree = treeWithBoxes();
  SceneDesc sd;
  sd.kind = SceneKind::Shrub;
  sd.faces = 8000;
  sd.seed = 3;
  sd.textureSize = 64;
  sd.boxes = true;
  VegetationModel shrub;
  ASSERT_TRUE(generateScene(sd, &shrub).ok());
  const float rt = 0.5f * glm::length(tree.boundsMax - tree.boundsMin), rs = 0.5f * glm::length(shrub.boundsMax - shrub.boundsMin);
  const glm::vec3 ct = 0.5f * (tree.boundsMin + tree.boundsMax), cs = 0.5f * (shrub.boundsMin + shrub.boundsMax);
  // The tree turned 60 degrees and scaled 1.3, the shrub scaled to the tree's size, side by side.
  const glm::mat4 treeAt = glm::translate(glm::mat4(1.0f), glm::vec3(-1.4f * rt, 0.0f, 0.0f)) *
                           glm::rotate(glm::mat4(1.0f), glm::radians(60.0f), glm::vec3(0, 1, 0)) * glm::scale(glm::mat4(1.0f), glm::vec3(1.3f)) *
                           glm::translate(glm::mat4(1.0f), -ct);
  const float shrubScale = rt / rs;
  const glm::mat4 shrubAt = glm::translate(glm::mat4(1.0f), glm::vec3(1.4f * rt, 0.0f, 0.0f)) *
                            glm::scale(glm::mat4(1.0f), glm::vec3(shrubScale)) * glm::translate(glm::mat4(1.0f), -cs);
  LayeredVegetationDesc d;
  d.width = w;
  d.height = h;
  d.impostors.enable = true;
  d.impostors.maxLevel = 0;
  d.impostors.tilePixels = 128;
  d.copies.models = {treeAt, shrubAt};
  d.copies.tints = {glm::vec3(1.0f), glm::vec3(1.0f, 0.8f, 0.6f)};
  d.copies.species = {0, 1};
  LayeredVegetation lv;
  const Status made = createLayeredVegetation(dev, {SpeciesModel{&tree}, SpeciesModel{&shrub}}, d, &lv);
  ASSERT_TRUE(made.ok()) << made.message();
  EXPECT_EQ(lv.stats.species, 2u);
  ASSERT_EQ(lv.impostors.speciesBaked.size(), 2u);
  EXPECT_GE(lv.impostors.speciesBaked[0], 1u);
  EXPECT_GE(lv.impostors.speciesBaked[1], 1u) << "each species' model is baked";
  const LayerView view = lookFrom(glm::vec3(0.0f, 0.3f * rt, 9.0f * rt), glm::vec3(0.0f), w, h, 40.0f);
  // Each copy's plant box (the largest baked box of its species) projected through its transform.
  auto copyBoxPixels = [&](uint32_t species, const glm::mat4& model, float scale) {
    float best = 0;
    const ImpostorNode* top = nullptr;
    for (uint32_t i = lv.impostors.speciesNodes[species]; i < lv.impostors.speciesNodes[species + 1]; ++i) {
      const ImpostorNode& n = lv.impostors.nodes[i];
      if (n.firstTile != kNoTile && (!top || n.radius > top->radius)) top = &n;
    }
    if (!top) return best;
    const float z = -(view.view * model * glm::vec4(top->center, 1.0f)).z;
    return 2.0f * top->radius * scale * std::abs(view.proj[1][1]) * 0.5f * float(h) / z;
  };
  const float pTree = copyBoxPixels(0, treeAt, 1.3f), pShrub = copyBoxPixels(1, shrubAt, shrubScale);
  ASSERT_GT(pTree, 0.0f);
  ASSERT_GT(pShrub, 0.0f);
  ASSERT_TRUE(renderOnce(dev, lv, view).ok());
  const std::vector<glm::vec4> leaves = flatten(lv);
  EXPECT_EQ(lv.stats.lastImpostors, 0u);
  EXPECT_EQ(lv.stats.lastVisibleInstances, 2u);
  // Every copy at its switch: each an impostor of its own species, no leaf drawn.
  LayerSettings s = lv.settings;
  s.impostors.mode = ImpostorMode::ByProjectedSize;
  s.impostors.band = 0.0f;
  s.impostors.switchPixels = std::max(pTree, pShrub) * 1.001f;
  ASSERT_TRUE(setLayerSettings(lv, s).ok());
  ASSERT_TRUE(renderOnce(dev, lv, view).ok());
  EXPECT_EQ(lv.stats.lastImpostors, 2u);
  EXPECT_EQ(lv.stats.lastDrawnTriangles, 0u);
  const std::vector<glm::vec4> both = flatten(lv);
  const ImageDiff all = compareImages(both, leaves);
  std::printf("two species as copies, every copy an impostor (%.1f and %.1f px boxes): mean |d| %.4f, coverage IoU %.3f over %llu px\n",
              pTree, pShrub, all.meanAbs, all.coverageIoU, (unsigned long long)all.covered);
  // The switch test's bound (AtTheSwitchDistanceTheImpostorLayerMatchesTheLeaves): IoU >= 0.6,
  // mean |RGBA difference| <= 0.25; a copy drawn at its model's origin or turned wrongly misses
  // its leaves' coverage entirely.
  EXPECT_GE(all.coverageIoU, 0.6);
  EXPECT_LE(all.meanAbs, 0.25);
  if (all.coverageIoU < 0.6 || all.meanAbs > 0.25) writeDiff("species_copies_all", w, h, both, leaves);
  // The switch between the two sizes: the smaller copy an impostor, the larger its leaves.
  s.impostors.switchPixels = 0.5f * (pTree + pShrub);
  ASSERT_TRUE(setLayerSettings(lv, s).ok());
  ASSERT_TRUE(renderOnce(dev, lv, view).ok());
  EXPECT_EQ(lv.stats.lastImpostors, 1u);
  const uint64_t largerFoliage = pTree > pShrub ? lv.mesh.species[0].triangles : lv.mesh.species[1].triangles;
  EXPECT_GT(lv.stats.lastDrawnTriangles, 0u);
  EXPECT_LE(lv.stats.lastDrawnTriangles, largerFoliage);
  const std::vector<glm::vec4> mixed = flatten(lv);
  const ImageDiff one = compareImages(mixed, leaves);
  std::printf("two species as copies, one impostor: mean |d| %.4f, coverage IoU %.3f\n", one.meanAbs, one.coverageIoU);
  EXPECT_GE(one.coverageIoU, 0.6);
  EXPECT_LE(one.meanAbs, 0.25);
  EXPECT_GE(one.coverageIoU, all.coverageIoU) << "a copy drawn from its leaves is closer to the leaves than its impostor";
  if (one.coverageIoU < 0.6 || one.meanAbs > 0.25) writeDiff("species_copies_one", w, h, mixed, leaves);
  destroyLayeredVegetation(lv);
}

}  // namespace

// Lluch et al.'s level limit (seed 002 section 3): "if the ratio [of a node's box volume to its
// parent's] is smaller than a threshold, we do not generate textures for the node's box". With
// ImpostorDesc.minVolumeRatio every baked box below the root meets the ratio, fewer boxes are
// baked than without it, and a box it leaves out had views without it.
TEST_F(ImpostorTest, BoxesUnderTheVolumeRatioGetNoViews) {
  const VegetationModel m = treeWithBoxes();
  LayeredVegetationDesc d;
  d.width = 128;
  d.height = 96;
  d.impostors.enable = true;
  d.impostors.maxLevel = 4;
  LayeredVegetation all, limited;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &all).ok());
  std::vector<float> ratios;
  for (const ImpostorNode& n : all.impostors.nodes)
    if (n.parent != kNoTile && n.firstTile != kNoTile) ratios.push_back(volumeRatio(all.impostors.nodes[n.parent], n));
  std::sort(ratios.begin(), ratios.end());
  ASSERT_GT(ratios.size(), 4u);
  std::printf("baked boxes' volume ratios: min %.3f, median %.3f, max %.3f\n", ratios.front(), ratios[ratios.size() / 2], ratios.back());
  const float threshold = ratios[ratios.size() / 2];  // the median: about half the boxes fall under it
  d.impostors.minVolumeRatio = threshold;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &limited).ok());
  const auto& na = all.impostors.nodes;
  const auto& nl = limited.impostors.nodes;
  ASSERT_EQ(na.size(), nl.size());
  uint32_t bakedAll = 0, bakedLimited = 0, leftOut = 0;
  for (size_t i = 0; i < nl.size(); ++i) {
    bakedAll += na[i].firstTile != kNoTile;
    bakedLimited += nl[i].firstTile != kNoTile;
    if (nl[i].parent == kNoTile) continue;
    const float r = volumeRatio(nl[nl[i].parent], nl[i]);
    if (nl[i].firstTile != kNoTile) EXPECT_GE(r, threshold) << "node " << i;
    leftOut += na[i].firstTile != kNoTile && nl[i].firstTile == kNoTile && r < threshold;
  }
  std::printf("boxes baked: %u without the volume ratio, %u with %.3f (%u left out by it); atlas %llu -> %llu bytes\n", bakedAll,
              bakedLimited, threshold, leftOut, (unsigned long long)all.impostors.bytes, (unsigned long long)limited.impostors.bytes);
  EXPECT_LT(bakedLimited, bakedAll);
  EXPECT_GT(leftOut, 0u);
  destroyLayeredVegetation(all);
  destroyLayeredVegetation(limited);
}
