// Depth-sliced layer rasterization (paper 3.2) on the device, under the validation helper:
// whole leaves per layer (read back by leaf and triangle id), the per-triangle slicing that cuts
// them, single pass == per-layer fallback pixel for pixel, automatic fallback selection, alpha
// cutoff, the rigid background, and the re-slicing policy.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>

#include <glm/gtc/matrix_transform.hpp>

#include "tools/image_io.h"
#include "render/gltf_loader.h"
#include "render/layers.h"
#include "tests/gpu_test.h"
#include "tests/layer_render.h"
#include "tools/own_device.h"
#include "tools/scene_generator.h"

#include "tests/assets.h"

using namespace canopy;
using canopy::test::kAssets;
using canopy::test::GpuTest;

namespace {

constexpr uint32_t kW = 320, kH = 240;

// Leaves in a screen grid (disjoint on screen), each a quad of two triangles tilted about the
// vertical so it spans 1.2 units of depth: many straddle layer boundaries. Material 0 is the
// foliage; with `bark`, a rigid quad (material 1) stands behind them all.
VegetationModel straddlingLeaves(uint32_t cols, uint32_t rows, bool bark) {
  VegetationModel m;
  m.path = "";  // in-memory: no root cache
  m.materials.resize(3);
  m.materials[0].name = "leaf";
  m.materials[0].baseColorFactor = glm::vec4(0.3f, 0.8f, 0.3f, 1.0f);
  m.materials[1].name = "bark";
  m.materials[1].baseColorFactor = glm::vec4(0.5f, 0.3f, 0.2f, 1.0f);
  m.materials[2].name = "default";
  auto quad = [&](glm::vec3 a, glm::vec3 b, glm::vec3 c, glm::vec3 d, uint32_t mat) {
    const uint32_t base = uint32_t(m.positions.size());
    const glm::vec2 uv[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const glm::vec3 p[4] = {a, b, c, d};
    for (int i = 0; i < 4; ++i) {
      m.positions.push_back(p[i]);
      m.normals.push_back({0, 0, 1});
      m.uvs.push_back(uv[i]);
    }
    for (uint32_t i : {0u, 1u, 2u, 2u, 3u, 0u}) m.indices.push_back(base + i);
    m.triangleMaterial.push_back(mat);
    m.triangleMaterial.push_back(mat);
  };
  const float cw = 6.0f / float(cols), ch = 4.0f / float(rows);
  for (uint32_t j = 0; j < rows; ++j)
    for (uint32_t i = 0; i < cols; ++i) {
      const float x0 = -3.0f + cw * (float(i) + 0.2f), x1 = x0 + 0.6f * cw;
      const float y0 = -2.0f + ch * (float(j) + 0.2f), y1 = y0 + 0.6f * ch;
      const float zc = -2.5f + 5.0f * float((i * 7 + j * 3) % (cols * rows)) / float(cols * rows);
      quad({x0, y0, zc - 0.6f}, {x1, y0, zc + 0.6f}, {x1, y1, zc + 0.6f}, {x0, y1, zc - 0.6f}, 0);
    }
  if (bark) quad({-1, -1, -4}, {1, -1, -4}, {1, 1, -4}, {-1, 1, -4}, 1);
  m.boundsMin = glm::vec3(INFINITY);
  m.boundsMax = glm::vec3(-INFINITY);
  for (const glm::vec3& p : m.positions) {
    m.boundsMin = glm::min(m.boundsMin, p);
    m.boundsMax = glm::max(m.boundsMax, p);
  }
  return m;
}

LayerView frontView() {
  LayerView v;
  v.view = glm::mat4(1.0f);
  v.view[3][2] = -10.0f;  // camera at z = +10 looking down -Z
  v.proj = perspectiveVulkan(glm::radians(40.0f), float(kW) / float(kH), 1.0f, 30.0f);
  return v;
}

Status renderOnce(Device& dev, LayeredVegetation& lv, const LayerView& view) {
  return canopy::test::renderLayersOnce(dev, lv, view);
}

// The layer passes of one LayeredVegetation in a graph kept across frames (a spread or streamed
// re-slice runs over many), and one frame: the view update, then the passes recorded and waited for.
struct LayerFrames {
  Device& dev;
  LayeredVegetation& lv;
  rg::RenderGraph g;
  bool changed = false;  // updateLayerView's: the frame changed the visible layers
  LayerFrames(Device& d, LayeredVegetation& v) : dev(d), lv(v) {}
  ~LayerFrames() { g.release(dev); }
  Status init() {
    CANOPY_TRY(addLayerPasses(lv, g, nullptr));
    CANOPY_TRY(g.compile());
    return g.realize(dev);
  }
  Status frame(const LayerView& v) {
    CANOPY_TRY(updateLayerView(lv, v, &changed));
    return submitAndWait(dev, [&](VkCommandBuffer cmd) { return g.record(cmd); });
  }
};

LayeredVegetationDesc smallDesc(const char* layout = "5(3-1-1)") {
  LayeredVegetationDesc d;
  d.width = kW;
  d.height = kH;
  d.writeIds = true;
  EXPECT_TRUE(parseLayerLayout(layout, &d.settings.layout).ok());
  return d;
}

struct Coverage {
  std::map<uint32_t, std::set<uint32_t>> layersOfLeaf, layersOfTriangle;
};

Coverage readCoverage(LayeredVegetation& lv) {
  Coverage c;
  for (uint32_t l = 0; l < lv.settings.layout.count(); ++l) {
    std::vector<glm::uvec2> ids;
    Status s = readLayerIds(lv, l, &ids);
    EXPECT_TRUE(s.ok()) << s.message();
    for (const glm::uvec2& id : ids) {
      if (id.y == 0) continue;
      EXPECT_NE(id.x, 0u) << "a rigid triangle was drawn into layer " << l;
      c.layersOfLeaf[id.x - 1].insert(l);
      c.layersOfTriangle[lv.mesh.gpuToModelTriangle[id.y - 1]].insert(l);
    }
  }
  return c;
}

// Each leaf's root position, from the chunks' root tables.
std::map<uint32_t, glm::vec3> rootPositions(const LayeredVegetation& lv) {
  std::map<uint32_t, glm::vec3> r;
  for (const MeshChunk& c : lv.mesh.chunks)
    for (uint32_t i = 0; i < c.rootCount; ++i) r[lv.mesh.hostMesh.roots[c.firstRoot + i].leaf] = lv.mesh.hostMesh.roots[c.firstRoot + i].position;
  return r;
}

// Leaves whose own vertices lie on both sides of a layer boundary.
uint32_t countStraddlers(const LayeredVegetation& lv) {
  std::map<uint32_t, std::set<uint32_t>> layers;
  for (const MeshChunk& c : lv.mesh.chunks)
    for (uint32_t i = 0; i < c.vertexCount; ++i) {
      const gpu::LayerVertex& v = lv.mesh.hostMesh.vertices[c.firstVertex + i];
      if (chunkLeaf(v) == LAYER_CHUNK_NO_LEAF) continue;
      const float z = glm::dot(lv.visible.frame.depthRow, glm::vec4(decodePosition(c, v), 1.0f));
      layers[lv.mesh.hostMesh.roots[c.firstRoot + chunkLeaf(v)].leaf].insert(gpu::layerOfDepth(lv.visible.frame, z));
    }
  uint32_t n = 0;
  for (auto& [leaf, set] : layers) n += set.size() > 1;
  return n;
}

// Compares two float images; on any difference writes a diff PNG (red = difference) and fails.
void expectIdentical(const std::vector<float>& a, const std::vector<float>& b, uint32_t channels,
                     const std::string& what, uint32_t width = kW) {
  ASSERT_EQ(a.size(), b.size());
  double maxDiff = 0;
  size_t differing = 0;
  const size_t pixels = a.size() / channels;
  std::vector<uint8_t> diff(pixels * 4, 0);
  for (size_t p = 0; p < pixels; ++p) {
    float d = 0;
    for (uint32_t c = 0; c < channels; ++c) d = std::max(d, std::abs(a[p * channels + c] - b[p * channels + c]));
    maxDiff = std::max<double>(maxDiff, d);
    differing += d > 0;
    diff[p * 4] = d > 0 ? 255 : 0;
    diff[p * 4 + 1] = uint8_t(std::min(255.0f, 255.0f * std::abs(a[p * channels])));
    diff[p * 4 + 3] = 255;
  }
  if (differing) {
    std::filesystem::create_directories("failures");
    const std::string path = "failures/" + what + "_diff.png";
    (void)writePng(path, width, uint32_t(pixels / width), diff);
    ADD_FAILURE() << what << ": " << differing << " pixels differ, max difference " << maxDiff << " (diff image "
                  << std::filesystem::absolute(path) << ")";
  }
}

// Image metric for paths that may move an edge by a fraction of a pixel: pixels whose largest
// channel difference exceeds `tol`, as a share of the image, must stay within `maxShare`; on
// failure a diff PNG (red = over tolerance) is written.
void expectClose(const std::vector<glm::vec4>& a, const std::vector<glm::vec4>& b, float tol, double maxShare,
                 const std::string& what, uint32_t width = kW) {
  ASSERT_EQ(a.size(), b.size());
  size_t over = 0;
  float maxDiff = 0;
  std::vector<uint8_t> diff(a.size() * 4, 0);
  for (size_t p = 0; p < a.size(); ++p) {
    const glm::vec4 d = glm::abs(a[p] - b[p]);
    const float m = std::max(std::max(d.x, d.y), std::max(d.z, d.w));
    maxDiff = std::max(maxDiff, m);
    over += m > tol;
    diff[p * 4] = m > tol ? 255 : 0;
    diff[p * 4 + 1] = uint8_t(std::min(255.0f, 255.0f * a[p].a));
    diff[p * 4 + 3] = 255;
  }
  const double share = double(over) / double(std::max<size_t>(a.size(), 1));
  if (share > maxShare) {
    std::filesystem::create_directories("failures");
    const std::string path = "failures/" + what + "_diff.png";
    (void)writePng(path, width, uint32_t(a.size() / width), diff);
    ADD_FAILURE() << what << ": " << over << " pixels (" << 100.0 * share << " %) differ by more than " << tol
                  << " (allowed " << 100.0 * maxShare << " %), max " << maxDiff << "; diff image "
                  << std::filesystem::absolute(path);
  }
}

void expectSameLayers(LayeredVegetation& x, LayeredVegetation& y, const std::string& what) {
  for (uint32_t l = 0; l < x.settings.layout.count(); ++l) {
    std::vector<glm::vec4> ca, cb;
    std::vector<float> da, db;
    std::vector<glm::uvec2> ia, ib;
    ASSERT_TRUE(readLayerColor(x, l, &ca).ok());
    ASSERT_TRUE(readLayerColor(y, l, &cb).ok());
    ASSERT_TRUE(readLayerDepth(x, l, &da).ok());
    ASSERT_TRUE(readLayerDepth(y, l, &db).ok());
    std::vector<float> fa(ca.size() * 4), fb(cb.size() * 4);
    std::memcpy(fa.data(), ca.data(), fa.size() * 4);
    std::memcpy(fb.data(), cb.data(), fb.size() * 4);
    expectIdentical(fa, fb, 4, what + "_colour_layer" + std::to_string(l), x.desc.width);
    expectIdentical(da, db, 1, what + "_depth_layer" + std::to_string(l), x.desc.width);
    if (x.desc.writeIds && y.desc.writeIds) {
      ASSERT_TRUE(readLayerIds(x, l, &ia).ok());
      ASSERT_TRUE(readLayerIds(y, l, &ib).ok());
      EXPECT_TRUE(ia == ib) << what << ": leaf/triangle ids differ in layer " << l;
    }
  }
}

class LayersTest : public GpuTest {};

class LayersWithoutGlLayerTest : public GpuTest {
 protected:
  void configure(DeviceDesc& d) override { d.disableShaderOutputLayer = true; }
};

}  // namespace

TEST_F(LayersTest, EveryLeafLandsWholeInTheLayerOfItsRoot) {
  const VegetationModel m = straddlingLeaves(12, 8, true);
  LayeredVegetation lv;
  Status s = createLayeredVegetation(dev, m, smallDesc(), &lv);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(lv.pipelines.singlePass) << "lavapipe has shaderOutputLayer: the single pass is expected";
  ASSERT_TRUE(renderOnce(dev, lv, frontView()).ok());
  const uint32_t leaves = 12 * 8;
  EXPECT_EQ(lv.stats.leafCount, leaves);
  const uint32_t straddlers = countStraddlers(lv);
  EXPECT_GE(straddlers, leaves / 4) << "the test mesh must put many leaves across layer boundaries";
  Coverage c = readCoverage(lv);
  EXPECT_EQ(c.layersOfLeaf.size(), leaves) << "every leaf is visible in some layer";
  EXPECT_EQ(c.layersOfTriangle.size(), 2u * leaves) << "every foliage triangle is visible in some layer";
  std::vector<uint32_t> perLayer(lv.settings.layout.count(), 0);
  const std::map<uint32_t, glm::vec3> rootOf = rootPositions(lv);
  for (auto& [leaf, layers] : c.layersOfLeaf) {
    ASSERT_EQ(layers.size(), 1u) << "leaf " << leaf << " is cut across " << layers.size() << " layers";
    const float rootDepth = glm::dot(lv.visible.frame.depthRow, glm::vec4(rootOf.at(leaf), 1.0f));
    EXPECT_EQ(*layers.begin(), gpu::layerOfDepth(lv.visible.frame, rootDepth)) << "leaf " << leaf;
    perLayer[*layers.begin()]++;
  }
  for (auto& [tri, layers] : c.layersOfTriangle) EXPECT_EQ(layers.size(), 1u) << "triangle " << tri;
  for (uint32_t l = 0; l < perLayer.size(); ++l) {
    EXPECT_GT(perLayer[l], 0u) << "layer " << l << " is empty";
    EXPECT_EQ(perLayer[l], lv.visible.layers[l].leaves) << "the CPU placement statistics disagree in layer " << l;
  }
  destroyLayeredVegetation(lv);
}

TEST_F(LayersTest, PerTriangleSlicingCutsTheSameLeaves) {
  const VegetationModel m = straddlingLeaves(12, 8, false);
  LayeredVegetationDesc d = smallDesc();
  d.settings.slice = SliceMode::Geometry;
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
  EXPECT_FALSE(lv.pipelines.singlePass);
  ASSERT_TRUE(renderOnce(dev, lv, frontView()).ok());
  Coverage c = readCoverage(lv);
  uint32_t cut = 0, cutTriangles = 0;
  for (auto& [leaf, layers] : c.layersOfLeaf) cut += layers.size() > 1;
  for (auto& [tri, layers] : c.layersOfTriangle) cutTriangles += layers.size() > 1;
  // The near/far planes on the fragments' own depth split straddling leaves (and triangles).
  EXPECT_GE(cut, 12u * 8u / 4u) << "the simple segmentation should cut many of these leaves";
  EXPECT_GT(cutTriangles, 0u);
  destroyLayeredVegetation(lv);
}

namespace {
// The models two draw ways are compared on: the leaf grid, the generated shrub when asked (alpha-
// masked leaves, rigid branches) and the shared real plant when the assets are there (a note
// otherwise); false when a model could not be made.
bool comparisonModels(bool shrub, std::vector<std::pair<std::string, VegetationModel>>* models) {
  models->push_back({"leaves", straddlingLeaves(12, 8, true)});
  if (shrub) {
    SceneDesc sd;
    sd.kind = SceneKind::Shrub;
    sd.faces = 20000;
    sd.seed = 5;
    sd.textureSize = 32;
    VegetationModel m;
    if (!generateScene(sd, &m).ok()) return false;
    models->push_back({"shrub", std::move(m)});
  }
  const std::string plant = kAssets + "/DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf";
  if (!std::filesystem::exists(plant)) {
    std::printf("[ note ] shared assets absent: the real-model part of this test is skipped\n");
    return true;
  }
  VegetationModel m;
  if (!loadGltf(plant, {}, &m).ok()) return false;
  models->push_back({"plant", std::move(m)});
  return true;
}
}  // namespace

TEST_F(LayersTest, SinglePassEqualsPerLayerDrawsPixelForPixel) {
  std::vector<std::pair<std::string, VegetationModel>> models;
  ASSERT_TRUE(comparisonModels(false, &models));
  for (auto& [name, m] : models) {
    LayeredVegetationDesc a = smallDesc();
    a.settings.draw = LayerDrawMode::SinglePass;
    LayeredVegetationDesc b = a;
    b.settings.draw = LayerDrawMode::PerLayer;
    LayeredVegetation x, y;
    ASSERT_TRUE(createLayeredVegetation(dev, m, a, &x).ok());
    ASSERT_TRUE(createLayeredVegetation(dev, m, b, &y).ok());
    ASSERT_TRUE(x.pipelines.singlePass);
    ASSERT_FALSE(y.pipelines.singlePass);
    const LayerView view = name == "leaves" ? frontView() : orbitView(m.boundsMin, m.boundsMax, 30, 15, 40, float(kW) / kH, 0.8f);
    ASSERT_TRUE(renderOnce(dev, x, view).ok());
    ASSERT_TRUE(renderOnce(dev, y, view).ok());
    size_t covered = 0;
    for (uint32_t l = 0; l < x.settings.layout.count(); ++l) {
      std::vector<glm::vec4> c;
      ASSERT_TRUE(readLayerColor(x, l, &c).ok());
      for (const glm::vec4& p : c) covered += p.a > 0;
    }
    EXPECT_GT(covered, size_t(kW) * kH / 50) << name << ": the comparison must cover a real image";
    expectSameLayers(x, y, name);
    destroyLayeredVegetation(x);
    destroyLayeredVegetation(y);
  }
}

// Shading once (docs/design.md "Layers: shading once") changes which fragments are shaded, not
// the layers: the depth pre-pass and the EQUAL shading give the plain draw's images on both draw
// paths, for the leaf grid, the generated shrub (alpha-masked leaves, rigid branches) and a real
// plant. Colour and depth by a metric (edges of coplanar leaves may resolve a tie the other way).
TEST_F(LayersTest, ShadingOnceEqualsShadingEveryFragment) {
  std::vector<std::pair<std::string, VegetationModel>> models;
  ASSERT_TRUE(comparisonModels(true, &models));
  for (auto& [name, m] : models) {
    for (LayerDrawMode mode : {LayerDrawMode::SinglePass, LayerDrawMode::PerLayer}) {
      const std::string what = "shade_once_" + name + (mode == LayerDrawMode::SinglePass ? "_single_pass" : "_per_layer");
      SCOPED_TRACE(what);
      LayeredVegetationDesc a = smallDesc();
      a.writeIds = false;  // the id output is drawn the plain way
      a.settings.draw = mode;
      LayeredVegetationDesc b = a;
      a.settings.shadeOnce = true;
      b.settings.shadeOnce = false;
      LayeredVegetation x, y;
      ASSERT_TRUE(createLayeredVegetation(dev, m, a, &x).ok());
      ASSERT_TRUE(createLayeredVegetation(dev, m, b, &y).ok());
      ASSERT_NE(mode == LayerDrawMode::SinglePass ? x.pipelines.shaded.layeredOnce.shade.pipeline : x.pipelines.shaded.perLayerOnce.shade.pipeline,
                VK_NULL_HANDLE);
      const LayerView view = name == "leaves" ? frontView() : orbitView(m.boundsMin, m.boundsMax, 30, 15, 40, float(kW) / kH, 0.8f);
      ASSERT_TRUE(renderOnce(dev, x, view).ok());
      ASSERT_TRUE(renderOnce(dev, y, view).ok());
      size_t covered = 0;
      for (uint32_t l = 0; l < x.settings.layout.count(); ++l) {
        std::vector<glm::vec4> ca, cb;
        std::vector<float> da, db;
        ASSERT_TRUE(readLayerColor(x, l, &ca).ok());
        ASSERT_TRUE(readLayerColor(y, l, &cb).ok());
        ASSERT_TRUE(readLayerDepth(x, l, &da).ok());
        ASSERT_TRUE(readLayerDepth(y, l, &db).ok());
        for (const glm::vec4& p : cb) covered += p.a > 0;
        std::vector<glm::vec4> va(da.size()), vb(db.size());
        for (size_t i = 0; i < da.size(); ++i) va[i] = glm::vec4(da[i]), vb[i] = glm::vec4(db[i]);
        expectClose(ca, cb, 2e-3f, 0.002, what + "_colour_layer" + std::to_string(l));
        expectClose(va, vb, 1e-6f, 0.002, what + "_depth_layer" + std::to_string(l));
      }
      EXPECT_GT(covered, size_t(kW) * kH / 50) << "the comparison must cover a real image";
      if (x.mesh.hasRigid) {
        std::vector<glm::vec4> ca, cb;
        std::vector<float> da, db;
        ASSERT_TRUE(readBackground(x, &ca, &da).ok());
        ASSERT_TRUE(readBackground(y, &cb, &db).ok());
        expectClose(ca, cb, 2e-3f, 0.002, what + "_background");
      }
      destroyLayeredVegetation(x);
      destroyLayeredVegetation(y);
    }
  }
}

TEST_F(LayersWithoutGlLayerTest, FallbackIsChosenAutomaticallyAndKeepsLeavesWhole) {
  ASSERT_FALSE(dev.shaderOutputLayer);
  const VegetationModel m = straddlingLeaves(8, 6, false);
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, m, smallDesc("3(1-1-1)"), &lv).ok());
  EXPECT_FALSE(lv.pipelines.singlePass) << "Auto must pick one draw per layer without shaderOutputLayer";
  EXPECT_FALSE(lv.pipelines.shaded.layered.pipeline) << "no gl_Layer pipeline may be created on such a device";
  ASSERT_TRUE(renderOnce(dev, lv, frontView()).ok());
  Coverage c = readCoverage(lv);
  EXPECT_EQ(c.layersOfLeaf.size(), 48u);
  for (auto& [leaf, layers] : c.layersOfLeaf) EXPECT_EQ(layers.size(), 1u) << "leaf " << leaf;
  LayeredVegetationDesc forced = smallDesc();
  forced.settings.draw = LayerDrawMode::SinglePass;
  LayeredVegetation bad;
  Status s = createLayeredVegetation(dev, m, forced, &bad);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("shaderOutputLayer"), std::string::npos) << s.message();
  destroyLayeredVegetation(lv);
}

TEST_F(LayersTest, AlphaCutoffAndRigidBackground) {
  VegetationModel m = straddlingLeaves(1, 1, true);
  // Replace the leaf by a flat, camera-facing quad with a texture: left texel alpha 0.3, right 1.
  for (size_t v = 0; v < 4; ++v) m.positions[v].z = 1.0f;
  m.materials[0].alphaMode = AlphaMode::Mask;
  m.materials[0].alphaCutoff = 0.5f;
  m.materials[0].baseColorImage = 0;
  ModelImage img;
  img.name = "half";
  img.width = 2;
  img.height = 1;
  img.rgba = {255, 255, 255, 77, 255, 255, 255, 255};
  m.images.push_back(img);
  for (size_t v = 0; v < 4; ++v) m.uvs[v] = glm::vec2(m.uvs[v].x * 0.5f + 0.25f, m.uvs[v].y);  // texel centres
  LayeredVegetationDesc d = smallDesc("1");
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
  EXPECT_EQ(lv.stats.rigidTriangles, 2u);
  ASSERT_TRUE(renderOnce(dev, lv, frontView()).ok());
  std::vector<glm::vec4> c;
  ASSERT_TRUE(readLayerColor(lv, 0, &c).ok());
  // Linear filtering between the texel centres (u = 0.25 and 0.75) crosses the cutoff at
  // u = 0.25 + 0.5 (0.5 - a) / (1 - a) with a = 77/255: everything left of it must be cut away.
  const glm::mat4 vp = lv.visible.frame.viewProj;
  auto screenX = [&](glm::vec3 p) {
    glm::vec4 q = vp * glm::vec4(p, 1.0f);
    return (q.x / q.w * 0.5f + 0.5f) * float(kW);
  };
  const float a = 77.0f / 255.0f, cross = (0.5f - a) / (1.0f - a);
  const float xl = screenX(m.positions[0]), xr = screenX(m.positions[1]), xm = xl + cross * (xr - xl);
  size_t left = 0, right = 0;
  for (uint32_t y = 0; y < kH; ++y)
    for (uint32_t x = 0; x < kW; ++x) {
      const glm::vec4 p = c[size_t(y) * kW + x];
      if (p.a <= 0) continue;
      EXPECT_FLOAT_EQ(p.a, 1.0f) << "masked leaves are opaque where kept";
      const float cx = float(x) + 0.5f;
      if (cx < xm - 1) ++left;
      else if (cx > xm + 1) ++right;
    }
  EXPECT_EQ(left, 0u) << "texels below alphaCutoff were drawn";
  EXPECT_GT(right, 100u);
  EXPECT_GT(xm - xl, 10.0f) << "the cut-away part must be wide enough to see";
  std::vector<glm::vec4> bg;
  std::vector<float> bgDepth;
  ASSERT_TRUE(readBackground(lv, &bg, &bgDepth).ok());
  size_t bark = 0;
  for (size_t i = 0; i < bg.size(); ++i)
    if (bg[i].a > 0) {
      ++bark;
      EXPECT_LT(bgDepth[i], 1.0f);
    }
  EXPECT_GT(bark, 500u) << "the rigid quad must be in the background";
  destroyLayeredVegetation(lv);
}

// Issue 16: chunks of at most 3 vertices put every triangle in a chunk of its own, so each leaf
// quad is split by a chunk border (and its root sits in two chunk tables). Leaves stay whole in
// the layer of their root, the ids are those of the default chunking, and the images differ only
// where the per-chunk quantisation moves an edge by a fraction of a pixel.
TEST_F(LayersTest, ChunkBordersInsideLeavesCutNoLeaf) {
  const VegetationModel m = straddlingLeaves(12, 8, true);
  for (LayerDrawMode mode : {LayerDrawMode::SinglePass, LayerDrawMode::PerLayer}) {
    const std::string what = mode == LayerDrawMode::SinglePass ? "single_pass" : "per_layer";
    LayeredVegetationDesc a = smallDesc();
    a.settings.draw = mode;
    LayeredVegetationDesc b = a;
    b.maxChunkVertices = 3;
    LayeredVegetation x, y;
    ASSERT_TRUE(createLayeredVegetation(dev, m, a, &x).ok());
    Status s = createLayeredVegetation(dev, m, b, &y);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_LE(x.mesh.chunks.size(), 2u) << "default chunking: one foliage and one rigid chunk";
    EXPECT_EQ(y.mesh.chunks.size(), size_t(2 * 12 * 8 + 2)) << "one triangle per chunk";
    EXPECT_EQ(y.stats.meshChunks, y.mesh.chunks.size());
    ASSERT_TRUE(renderOnce(dev, x, frontView()).ok());
    ASSERT_TRUE(renderOnce(dev, y, frontView()).ok());
    Coverage c = readCoverage(y);
    EXPECT_EQ(c.layersOfLeaf.size(), 12u * 8u) << what;
    const std::map<uint32_t, glm::vec3> rootOf = rootPositions(y);
    for (auto& [leaf, layers] : c.layersOfLeaf) {
      ASSERT_EQ(layers.size(), 1u) << what << ": leaf " << leaf << " is cut across " << layers.size() << " layers";
      const float rootDepth = glm::dot(y.visible.frame.depthRow, glm::vec4(rootOf.at(leaf), 1.0f));
      EXPECT_EQ(*layers.begin(), gpu::layerOfDepth(y.visible.frame, rootDepth)) << what << ": leaf " << leaf;
    }
    Coverage cx = readCoverage(x);
    EXPECT_EQ(c.layersOfLeaf, cx.layersOfLeaf) << what << ": leaves land in other layers than with one chunk";
    for (uint32_t l = 0; l < x.settings.layout.count(); ++l) {
      std::vector<glm::vec4> ca, cb;
      ASSERT_TRUE(readLayerColor(x, l, &ca).ok());
      ASSERT_TRUE(readLayerColor(y, l, &cb).ok());
      expectClose(ca, cb, 0.02f, 0.005, what + "_chunks_layer" + std::to_string(l));
    }
    destroyLayeredVegetation(x);
    destroyLayeredVegetation(y);
  }
}

TEST_F(LayersTest, ReslicingFollowsThePolicy) {
  const VegetationModel m = straddlingLeaves(4, 3, false);
  LayeredVegetationDesc d = smallDesc("3(1-1-1)");
  d.settings.errorThresholdPixels = 1.0f;
  d.settings.turnThresholdDegrees = 2.0f;
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, m, d, &lv).ok());
  bool rebuild = false;
  LayerView v = frontView();
  ASSERT_TRUE(updateLayerView(lv, v, &rebuild).ok());
  EXPECT_TRUE(rebuild);
  ASSERT_TRUE(updateLayerView(lv, v, &rebuild).ok());
  EXPECT_FALSE(rebuild) << "a still camera must not rebuild";
  const float radius = 0.5f * glm::length(m.boundsMax - m.boundsMin);
  // Issue 34: re-slices driven by the reprojection's estimated error, not by fixed angles.
  LayerView small = v;
  small.view[3][0] += 0.001f * radius;  // a strafe whose parallax stays far below a pixel
  ASSERT_TRUE(updateLayerView(lv, small, &rebuild).ok());
  EXPECT_FALSE(rebuild) << lv.stats.lastRebuildReason;
  LayerView moved = v;
  moved.view[3][0] += 0.5f * radius;  // the slabs' parallax: pixels
  ASSERT_TRUE(updateLayerView(lv, moved, &rebuild).ok());
  EXPECT_TRUE(rebuild);
  EXPECT_NE(lv.stats.lastRebuildReason.find("parallax"), std::string::npos) << lv.stats.lastRebuildReason;
  LayerView turned = moved;  // a pure rotation (the eye stays): no parallax, the vegetation in view
  turned.view = glm::rotate(glm::mat4(1.0f), glm::radians(-1.0f), glm::vec3(0, 1, 0)) * moved.view;
  ASSERT_TRUE(updateLayerView(lv, turned, &rebuild).ok());
  EXPECT_FALSE(rebuild) << "a pure rotation is reprojected exactly: " << lv.stats.lastRebuildReason;
  LayerView orbited = turned;  // the eye moves around the vegetation: the baked shading's angle
  orbited.view = turned.view * glm::rotate(glm::mat4(1.0f), glm::radians(3.0f), glm::vec3(0, 1, 0));
  ASSERT_TRUE(updateLayerView(lv, orbited, &rebuild).ok());
  EXPECT_TRUE(rebuild);
  LayerView zoomed = orbited;  // 40 to 30 degrees: layer texels magnified 1.35x
  zoomed.proj = perspectiveVulkan(glm::radians(30.0f), float(kW) / kH, 1.0f, 30.0f);
  ASSERT_TRUE(updateLayerView(lv, zoomed, &rebuild).ok());
  EXPECT_TRUE(rebuild);
  EXPECT_NE(lv.stats.lastRebuildReason.find("magnified"), std::string::npos) << lv.stats.lastRebuildReason;
  EXPECT_EQ(lv.stats.rebuilds, 4u);
  EXPECT_EQ(lv.stats.viewUpdates, 7u);
  LayerSettings every = lv.settings;
  every.policy = ReslicePolicy::EveryFrame;
  ASSERT_TRUE(setLayerSettings(lv, every).ok());
  for (int i = 0; i < 3; ++i) {
    ASSERT_TRUE(updateLayerView(lv, zoomed, &rebuild).ok());
    EXPECT_TRUE(rebuild);
  }
  EXPECT_EQ(lv.stats.rebuilds, 7u);
  // A new layer count recreates the images; the next frame rebuilds with it.
  LayerSettings five = every;
  ASSERT_TRUE(parseLayerLayout("5(3-1-1)", &five.layout).ok());
  five.policy = ReslicePolicy::OnViewChange;
  ASSERT_TRUE(setLayerSettings(lv, five).ok());
  EXPECT_EQ(lv.targets.color.layers, 5u);
  ASSERT_TRUE(renderOnce(dev, lv, zoomed).ok());
  EXPECT_EQ(lv.stats.lastRebuildReason, "settings changed");
  LayerSettings bad = five;
  bad.ambient = 2.0f;
  Status s = setLayerSettings(lv, bad);
  EXPECT_NE(s.message().find("ambient"), std::string::npos) << s.message();
  destroyLayeredVegetation(lv);
}

// Issue 16: a re-slice spread over frames (slices of 7 triangles through chunks of at most 16
// vertices, so slices end inside chunks and chunk borders fall inside leaves) leaves exactly the
// layers a re-slice at once draws, for both draw paths; until its cross-fade the visible layers
// and their placement stay the old ones; the cross-fade starts the frame after the frame that
// unites the occupancy, which follows the last slice, and lasts crossFadeFrames frames, each
// visible layer moving towards the new one by the step's weight.
TEST_F(LayersTest, SpreadReslicingEqualsReslicingAtOnce) {
  const VegetationModel m = straddlingLeaves(12, 8, true);
  constexpr uint32_t kSlice = 7, kFade = 5;
  for (LayerDrawMode mode : {LayerDrawMode::SinglePass, LayerDrawMode::PerLayer}) {
    const std::string what = mode == LayerDrawMode::SinglePass ? "spread_single_pass" : "spread_per_layer";
    LayeredVegetationDesc d = smallDesc();
    d.writeIds = false;
    d.settings.draw = mode;
    d.maxChunkVertices = 16;
    d.fixedSliceTriangles = kSlice;
    d.settings.rebuildBudgetMs = 2.0f;
    d.settings.crossFadeFrames = kFade;
    LayeredVegetationDesc once = d;
    once.settings.rebuildBudgetMs = 0.0f;
    LayeredVegetation x, y;
    ASSERT_TRUE(createLayeredVegetation(dev, m, d, &x).ok());
    ASSERT_TRUE(createLayeredVegetation(dev, m, once, &y).ok());
    ASSERT_NE(x.targets.next.color.image, VkImage(VK_NULL_HANDLE)) << "spread re-slicing draws into a second layer set";
    EXPECT_EQ(y.targets.next.color.image, VkImage(VK_NULL_HANDLE));
    auto run = std::make_unique<LayerFrames>(dev, x);
    ASSERT_TRUE(run->init().ok());
    const bool& changed = run->changed;
    auto frame = [&](const LayerView& v) { return run->frame(v); };
    const uint32_t n = x.settings.layout.count();
    auto readAll = [&](LayeredVegetation& lv, std::vector<std::vector<glm::vec4>>* c) {
      c->resize(n);
      for (uint32_t l = 0; l < n; ++l) ASSERT_TRUE(readLayerColor(lv, l, &(*c)[l]).ok());
    };
    // The first view is drawn at once.
    const LayerView a = frontView();
    ASSERT_TRUE(frame(a).ok());
    EXPECT_TRUE(changed);
    EXPECT_EQ(x.stats.spreadPhase, 0u);
    std::vector<std::vector<glm::vec4>> oldColor, newColor, mid;
    readAll(x, &oldColor);
    const std::vector<LayerInfo> oldLayers = x.visible.layers;
    // A light change (the same camera, so the new set fades in; sets drawn from two cameras are
    // swapped in one copy): placement, slices, the occupancy frame, the fade.
    const LayerView b = a;
    LayerSettings lit = x.settings;
    lit.lightDirection = Float3{-0.6f, 0.5f, 0.4f};
    ASSERT_TRUE(setLayerSettings(x, lit).ok());
    LayerSettings litOnce = y.settings;
    litOnce.lightDirection = lit.lightDirection;
    ASSERT_TRUE(setLayerSettings(y, litOnce).ok());
    ASSERT_TRUE(renderOnce(dev, y, b).ok());
    readAll(y, &newColor);
    uint64_t triangles = 0;
    for (const MeshChunk& c : x.mesh.chunks) triangles += c.triangleCount;
    const uint32_t slices = uint32_t((triangles + kSlice - 1) / kSlice);
    ASSERT_GT(slices, 20u);
    ASSERT_TRUE(frame(b).ok());  // placement (the mesh is small: done in this frame)
    EXPECT_FALSE(changed);
    EXPECT_EQ(x.stats.spreadPhase, uint32_t(SpreadPhase::Drawing)) << "placement done, drawing from the next frame";
    for (uint32_t i = 0; i < slices; ++i) {
      ASSERT_TRUE(frame(b).ok());
      EXPECT_FALSE(changed) << what << ": slice " << i << " changed the visible layers";
      EXPECT_TRUE(x.reslice.slicePending);
      EXPECT_LE(x.stats.lastSliceTriangles, kSlice);
      if (i == slices / 2) {
        // Halfway: the visible layers and their placement are the old ones.
        readAll(x, &mid);
        for (uint32_t l = 0; l < n; ++l) expectClose(mid[l], oldColor[l], 0.0f, 0.0, what + "_halfway_layer" + std::to_string(l));
        for (uint32_t l = 0; l < n; ++l) EXPECT_EQ(x.visible.layers[l].slab.depth, oldLayers[l].slab.depth);
      }
    }
    EXPECT_EQ(x.stats.spreadPhase, uint32_t(SpreadPhase::CrossFading)) << what << ": the last slice was drawn";
    ASSERT_TRUE(frame(b).ok());  // unites the occupancy, no fade yet
    EXPECT_FALSE(changed);
    EXPECT_TRUE(x.reslice.occupancyUniteNext);
    EXPECT_EQ(x.stats.crossFade, 0.0f);
    for (uint32_t k = 1; k <= kFade; ++k) {
      ASSERT_TRUE(frame(b).ok());
      EXPECT_TRUE(changed) << what << ": fade step " << k;
      EXPECT_FLOAT_EQ(x.stats.crossFade, float(k) / float(kFade));
      if (k < kFade) {
        EXPECT_EQ(x.stats.spreadPhase, uint32_t(SpreadPhase::CrossFading));
        // Layer info moves linearly with the share.
        const float t = float(k) / float(kFade);
        EXPECT_NEAR(x.visible.layers[0].slab.depth, glm::mix(oldLayers[0].slab.depth, y.visible.layers[0].slab.depth, t), 1e-4f);
      }
      if (k == 2) {
        // Image i has had j = floor((k + (i odd)) / 2) of its H blends (H = blends of its parity):
        // the first I = ceil(H / 2) lay the new set over the old with weight 1 / (I + 1 - b), the
        // rest mix towards it with 1 / (H + 1 - b); up to half-float rounding.
        readAll(x, &mid);
        for (uint32_t l = 0; l < n; ++l) {
          const uint32_t blends = kFade - 1, h = l % 2 == 0 ? blends / 2 : (blends + 1) / 2, j = (k + l % 2) / 2, in = (h + 1) / 2;
          std::vector<glm::vec4> expect = oldColor[l];
          for (uint32_t b = 1; b <= j; ++b)
            for (size_t p = 0; p < expect.size(); ++p) {
              const glm::vec4 nc = newColor[l][p];
              expect[p] = b <= in ? nc / float(in + 1 - b) + expect[p] * (1.0f - nc.a / float(in + 1 - b))
                                  : glm::mix(expect[p], nc, 1.0f / float(h + 1 - b));
            }
          expectClose(mid[l], expect, 4e-3f, 0.0, what + "_fade_layer" + std::to_string(l));
        }
      }
    }
    EXPECT_EQ(x.stats.spreadPhase, 0u);
    EXPECT_EQ(x.stats.spreadRebuilds, 1u);
    EXPECT_EQ(x.stats.lastSpreadFrames, 1 + slices + 1 + kFade);
    ASSERT_TRUE(frame(b).ok());
    EXPECT_FALSE(changed);
    EXPECT_TRUE(x.reslice.occupancyDirty) << "the frame after the fade recomputes the occupancy";
    // Exactly the layers drawn at once: colour and depth of every layer, and the background.
    expectSameLayers(x, y, what);
    std::vector<glm::vec4> bx, by;
    std::vector<float> zx, zy;
    ASSERT_TRUE(readBackground(x, &bx, &zx).ok());
    ASSERT_TRUE(readBackground(y, &by, &zy).ok());
    expectClose(bx, by, 0.0f, 0.0, what + "_background");
    expectIdentical(zx, zy, 1, what + "_background_depth");
    for (uint32_t l = 0; l < n; ++l) {
      EXPECT_EQ(x.visible.layers[l].slab.depth, y.visible.layers[l].slab.depth);
      EXPECT_EQ(x.visible.layers[l].leaves, y.visible.layers[l].leaves);
      EXPECT_EQ(x.visible.layers[l].triangles, y.visible.layers[l].triangles);
    }
    run.reset();
    destroyLayeredVegetation(x);
    destroyLayeredVegetation(y);
  }
}

// The policy with spreading on: a camera cut, a new layer count and the EveryFrame policy
// re-slice at once; a turn while a spread re-slice runs waits for it; bad values are refused.
// Spread re-slicing in slices of 4 triangles (many frames a re-slice) on a small model.
Status createSlowSpread(Device& dev, const VegetationModel& m, LayeredVegetation* lv) {
  LayeredVegetationDesc d = smallDesc();
  d.writeIds = false;
  d.fixedSliceTriangles = 4;
  d.settings.rebuildBudgetMs = 1.0f;
  return createLayeredVegetation(dev, m, d, lv);
}

TEST_F(LayersTest, SpreadReslicingFollowsThePolicy) {
  const VegetationModel m = straddlingLeaves(6, 4, false);
  LayeredVegetation lv;
  ASSERT_TRUE(createSlowSpread(dev, m, &lv).ok());
  bool changed = false;
  const LayerView a = frontView();
  ASSERT_TRUE(updateLayerView(lv, a, &changed).ok());
  EXPECT_TRUE(changed) << "first view: at once";
  LayerView b = a;
  b.view = a.view * glm::rotate(glm::mat4(1.0f), glm::radians(3.0f), glm::vec3(0, 1, 0));  // an orbit
  ASSERT_TRUE(updateLayerView(lv, b, &changed).ok());
  EXPECT_FALSE(changed);
  EXPECT_NE(lv.stats.spreadPhase, 0u);
  EXPECT_EQ(lv.stats.rebuilds, 2u);
  LayerView c = b;
  c.view = b.view * glm::rotate(glm::mat4(1.0f), glm::radians(0.3f), glm::vec3(0, 1, 0));
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_EQ(lv.stats.rebuilds, 2u) << "a turn during a spread re-slice waits for it";
  EXPECT_NE(lv.stats.spreadPhase, 0u);
  // ... unless the camera outruns it: the visible set's error past twice the thresholds (here the
  // view direction turned 7.3 degrees from the visible set's, twice 2 degrees) re-slices at once.
  c.view = c.view * glm::rotate(glm::mat4(1.0f), glm::radians(4.0f), glm::vec3(0, 1, 0));
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_TRUE(changed);
  EXPECT_EQ(lv.stats.rebuilds, 3u);
  EXPECT_EQ(lv.stats.spreadPhase, 0u);
  EXPECT_EQ(lv.stats.outrunSpreads, 1u);
  EXPECT_NE(lv.stats.lastRebuildReason.find("a spread re-slice fell behind the camera"), std::string::npos)
      << lv.stats.lastRebuildReason;
  // A camera that keeps moving re-slices at once from then on (a spread one would be outrun again).
  c.view = c.view * glm::rotate(glm::mat4(1.0f), glm::radians(4.5f), glm::vec3(0, 1, 0));
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_TRUE(changed);
  EXPECT_EQ(lv.stats.rebuilds, 4u);
  EXPECT_EQ(lv.stats.spreadPhase, 0u);
  // Standing still ends that; the next move spreads again.
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_FALSE(lv.reslice.outrun);
  LayerView e = c;
  e.view = c.view * glm::rotate(glm::mat4(1.0f), glm::radians(3.0f), glm::vec3(0, 1, 0));
  ASSERT_TRUE(updateLayerView(lv, e, &changed).ok());
  EXPECT_FALSE(changed);
  EXPECT_NE(lv.stats.spreadPhase, 0u) << lv.stats.lastRebuildReason;
  EXPECT_EQ(lv.stats.rebuilds, 5u);
  lv.reslice.forcedReason = "camera cut";
  lv.reslice.forceImmediate = true;
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_TRUE(changed);
  EXPECT_TRUE(lv.reslice.rebuildPending);
  EXPECT_EQ(lv.stats.spreadPhase, 0u) << "a camera cut re-slices at once and ends the spread one";
  EXPECT_EQ(lv.stats.lastRebuildReason, "camera cut");
  LayerSettings slower = lv.settings;
  slower.crossFadeFrames = 12;
  slower.rebuildBudgetMs = 3.0f;
  ASSERT_TRUE(setLayerSettings(lv, slower).ok());
  const uint64_t rebuilds = lv.stats.rebuilds;
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_FALSE(changed);
  EXPECT_EQ(lv.stats.rebuilds, rebuilds) << "a new budget or fade length changes no layer: no re-slice";
  LayerSettings every = lv.settings;
  every.policy = ReslicePolicy::EveryFrame;
  ASSERT_TRUE(setLayerSettings(lv, every).ok());
  for (int i = 0; i < 2; ++i) {
    ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
    EXPECT_TRUE(changed && lv.reslice.rebuildPending) << "EveryFrame re-slices at once";
  }
  LayerSettings three = lv.settings;
  three.policy = ReslicePolicy::OnViewChange;
  ASSERT_TRUE(parseLayerLayout("3(1-1-1)", &three.layout).ok());
  bool recreated = false;
  ASSERT_TRUE(setLayerSettings(lv, three, &recreated).ok());
  EXPECT_TRUE(recreated);
  EXPECT_EQ(lv.targets.next.color.layers, 3u);
  ASSERT_TRUE(updateLayerView(lv, c, &changed).ok());
  EXPECT_TRUE(changed && lv.reslice.rebuildPending) << "new layer images: nothing to fade from";
  LayerSettings off = three;
  off.rebuildBudgetMs = 0.0f;
  ASSERT_TRUE(setLayerSettings(lv, off, &recreated).ok());
  EXPECT_TRUE(recreated);
  EXPECT_EQ(lv.targets.next.color.image, VkImage(VK_NULL_HANDLE)) << "no second set without spreading";
  LayerSettings bad = three;
  bad.rebuildBudgetMs = -1.0f;
  Status s = setLayerSettings(lv, bad);
  EXPECT_NE(s.message().find("rebuildBudgetMs"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("[0, 1000]"), std::string::npos) << s.message();
  bad = three;
  bad.crossFadeFrames = 0;
  s = setLayerSettings(lv, bad);
  EXPECT_NE(s.message().find("crossFadeFrames"), std::string::npos) << s.message();
  destroyLayeredVegetation(lv);
}

// A camera that keeps moving (issue 34): the first re-slice it causes is not spread when, at the
// pace its error grows, the spread one would fall behind (slices of 4 triangles take many frames);
// the error at that re-slice is the threshold's, not more.
TEST_F(LayersTest, ASteadilyMovingCameraIsNotOutrunByASpreadReslice) {
  const VegetationModel m = straddlingLeaves(6, 4, false);
  LayeredVegetation lv;
  ASSERT_TRUE(createSlowSpread(dev, m, &lv).ok());
  bool changed = false;
  LayerView v = frontView();
  ASSERT_TRUE(updateLayerView(lv, v, &changed).ok());
  int frame = 0;
  for (; frame < 200 && lv.stats.rebuilds == 1; ++frame) {
    v.view = v.view * glm::rotate(glm::mat4(1.0f), glm::radians(0.2f), glm::vec3(0, 1, 0));  // an orbit
    ASSERT_TRUE(updateLayerView(lv, v, &changed).ok());
  }
  ASSERT_EQ(lv.stats.rebuilds, 2u) << "the orbit re-slices within 200 frames";
  EXPECT_TRUE(changed && lv.reslice.rebuildPending) << "at once, frame " << frame;
  EXPECT_EQ(lv.stats.spreadPhase, 0u);
  EXPECT_EQ(lv.stats.outrunSpreads, 1u);
  EXPECT_NE(lv.stats.lastRebuildReason.find("a spread re-slice would fall behind the camera"), std::string::npos)
      << lv.stats.lastRebuildReason;
  std::printf("re-sliced at once after %d frames of 0.2 degrees: %s\n", frame, lv.stats.lastRebuildReason.c_str());
  destroyLayeredVegetation(lv);
}

namespace {

// A view of the whole model from in front of it (+Z), at three radii.
LayerView viewOfModel(const VegetationModel& m, uint32_t w, uint32_t h) {
  const glm::vec3 c = 0.5f * (m.boundsMin + m.boundsMax);
  const float r = std::max(0.5f * glm::length(m.boundsMax - m.boundsMin), 1e-3f);
  LayerView v;
  v.view = glm::lookAt(c + glm::vec3(0.0f, 0.2f * r, 3.0f * r), c, glm::vec3(0, 1, 0));
  v.proj = perspectiveVulkan(glm::radians(45.0f), float(w) / float(h), 0.5f * r, 6.0f * r);
  return v;
}

// Bytes of the three mesh buffers (resident: the mesh; streamed: the rings).
uint64_t meshBufferBytes(const LayeredVegetation& lv) {
  return lv.mesh.vertices.allocation.size + lv.mesh.indexBuffer.allocation.size + lv.mesh.leafRoots.allocation.size;
}

}  // namespace

// issue 16: a mesh over the device-memory budget stays in host memory and reaches the GPU through
// the staging ring, a slice a frame. The layers equal those of the resident mesh pixel for pixel
// (both draw paths; chunks small enough that chunk borders fall inside leaves' neighbourhoods), for
// a re-slice asked at once (the first view: slices as large as the ring allows, copied in without a
// fade) and for a spread one; and the allocator's own counters stay within the budget.
TEST_F(LayersTest, StreamedMeshEqualsResidentMeshWithinTheBudget) {
  struct Case {
    std::string name;
    VegetationModel model;
    uint32_t width, height, chunkVertices;
    const char* layout;
  };
  std::vector<Case> cases;
  cases.push_back({"grid", straddlingLeaves(12, 8, true), kW, kH, 16, "5(3-1-1)"});
  {
    SceneDesc sd;
    sd.kind = SceneKind::Shrub;
    sd.faces = 80000;
    sd.seed = 5;
    sd.textureSize = 32;
    VegetationModel shrub;
    ASSERT_TRUE(generateScene(sd, &shrub).ok());
    cases.push_back({"shrub", std::move(shrub), 96, 72, 2048, "3(1-1-1)"});
  }
  for (Case& k : cases) {
    for (LayerDrawMode mode : {LayerDrawMode::SinglePass, LayerDrawMode::PerLayer}) {
      const std::string what = "streamed_" + k.name + (mode == LayerDrawMode::SinglePass ? "_single_pass" : "_per_layer");
      SCOPED_TRACE(what);
      LayeredVegetationDesc d;
      d.width = k.width;
      d.height = k.height;
      ASSERT_TRUE(parseLayerLayout(k.layout, &d.settings.layout).ok());
      d.settings.draw = mode;
      d.maxChunkVertices = k.chunkVertices;
      // The resident reference, with both layer sets (what the budget plans for).
      LayeredVegetationDesc rd = d;
      rd.settings.rebuildBudgetMs = 2.0f;
      const uint64_t before = dev.allocator->liveBytes;
      LayeredVegetation y;
      ASSERT_TRUE(createLayeredVegetation(dev, k.model, rd, &y).ok());
      ASSERT_TRUE(y.stats.meshResident);
      const uint64_t residentBytes = dev.allocator->liveBytes - before;
      const uint64_t mesh = y.stats.meshBytes;
      // Budget: everything but the mesh, plus half the mesh; the ring gets a quarter of the mesh.
      const uint64_t otherBytes = residentBytes - meshBufferBytes(y);
      d.deviceMemoryBudget = otherBytes + mesh / 2;
      d.stagingRingBytes = mesh / 4;
      if (k.name == "shrub") {
        // The mesh several times what is left for it.
        EXPECT_GT(mesh, 3 * (d.deviceMemoryBudget - otherBytes) / 2);
      }
      const LayerView a = viewOfModel(k.model, k.width, k.height);
      ASSERT_TRUE(renderOnce(dev, y, a).ok());
      dev.allocator->peakLiveBytes = dev.allocator->liveBytes;  // this test's peak from here
      const uint64_t start = dev.allocator->liveBytes;
      LayeredVegetation x;
      Status made = createLayeredVegetation(dev, k.model, d, &x);
      ASSERT_TRUE(made.ok()) << made.message();
      EXPECT_FALSE(x.stats.meshResident);
      EXPECT_TRUE(x.mesh.streamed);
      EXPECT_GT(x.stats.meshRingBytes, 0u);
      EXPECT_LT(x.stats.meshRingBytes, mesh) << "the ring is smaller than the mesh";
      EXPECT_EQ(x.stats.meshBytes, mesh);
      EXPECT_EQ(meshBufferBytes(x) >= x.stats.meshRingBytes, true);
      auto run = std::make_unique<LayerFrames>(dev, x);
      ASSERT_TRUE(run->init().ok());
      const bool& changed = run->changed;
      auto frame = [&](const LayerView& v) { return run->frame(v); };
      // The first view, asked at once: slices until the whole mesh is drawn, the copy with the last.
      uint32_t frames = 0;
      uint64_t drawn = 0;
      do {
        ASSERT_TRUE(frame(a).ok());
        ++frames;
        drawn += x.stats.lastSliceTriangles;
        if (x.stats.spreadRebuilds == 0) EXPECT_FALSE(changed) << "frame " << frames << " changed the visible layers early";
        ASSERT_LT(frames, 100000u);
      } while (x.stats.spreadRebuilds == 0);
      EXPECT_TRUE(changed) << "the last slice's frame copies the new layers in";
      EXPECT_TRUE(x.reslice.occupancyDirty) << "and recomputes the occupancy in that frame";
      EXPECT_GT(frames, 2u) << "the ring holds less than the mesh: several slices";
      EXPECT_EQ(drawn, y.stats.foliageTriangles + y.stats.rigidTriangles);
      EXPECT_EQ(x.stats.lastSpreadFrames, frames);
      // Canopy's allocator: the streamed object never held more than its budget (checked before
      // the readbacks, whose staging buffers are the test's).
      EXPECT_LE(dev.allocator->peakLiveBytes - start, d.deviceMemoryBudget)
          << "peak " << dev.allocator->peakLiveBytes - start << " bytes, budget " << d.deviceMemoryBudget;
      expectSameLayers(x, y, what + "_at_once");
      std::vector<glm::vec4> bx, by;
      std::vector<float> zx, zy;
      ASSERT_TRUE(readBackground(x, &bx, &zx).ok());
      ASSERT_TRUE(readBackground(y, &by, &zy).ok());
      expectClose(bx, by, 0.0f, 0.0, what + "_background", k.width);
      expectIdentical(zx, zy, 1, what + "_background_depth", k.width);
      for (uint32_t l = 0; l < x.settings.layout.count(); ++l) EXPECT_EQ(x.visible.layers[l].slab.depth, y.visible.layers[l].slab.depth);
      // A spread re-slice (a 3-degree orbit with a budget): the same layers once it is done.
      LayerSettings s = x.settings;
      s.rebuildBudgetMs = 2.0f;
      s.crossFadeFrames = 3;
      bool recreated = true;
      ASSERT_TRUE(setLayerSettings(x, s, &recreated).ok());
      EXPECT_FALSE(recreated) << "a streamed mesh has the second set already";
      LayerView b = a;
      b.view = a.view * glm::rotate(glm::mat4(1.0f), glm::radians(3.0f), glm::vec3(0, 1, 0));
      dev.allocator->peakLiveBytes = dev.allocator->liveBytes;
      frames = 0;
      do {
        ASSERT_TRUE(frame(b).ok());
        ++frames;
        ASSERT_LT(frames, 100000u);
      } while (x.stats.spreadRebuilds == 1);
      EXPECT_GT(x.stats.lastSpreadFrames, 3u);
      EXPECT_LE(dev.allocator->peakLiveBytes - start, d.deviceMemoryBudget);
      y.reslice.forceImmediate = true;  // the reference at once (it has spreading on for its second set)
      ASSERT_TRUE(renderOnce(dev, y, b).ok());
      expectSameLayers(x, y, what + "_spread");
      run.reset();
      destroyLayeredVegetation(x);
      destroyLayeredVegetation(y);
    }
  }
}

// A budget the ring cannot fit in, and the id output over the budget, are refused naming the budget.
TEST_F(LayersTest, MeshBudgetRefusals) {
  const VegetationModel m = straddlingLeaves(12, 8, true);
  LayeredVegetationDesc d = smallDesc();
  d.writeIds = false;
  d.deviceMemoryBudget = 1 << 20;  // less than the layer images
  LayeredVegetation lv;
  Status s = createLayeredVegetation(dev, m, d, &lv);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("deviceMemoryBudget 1.0 MiB"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("raise the budget"), std::string::npos) << s.message();
  d.writeIds = true;
  s = createLayeredVegetation(dev, m, d, &lv);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("id output"), std::string::npos) << s.message();
  d.writeIds = false;
  d.deviceMemoryBudget = 0;
  d.stagingRingBytes = 0;
  s = createLayeredVegetation(dev, m, d, &lv);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("stagingRingBytes"), std::string::npos) << s.message();
}

// Leaf shading (issue 17, seed 004 section III; shared/leaf_shading.h): one large leaf quad seen
// head-on through an orthographic camera, lit from several directions, against the CPU evaluation
// of the same terms. Tolerance: 2e-3 relative plus 1e-3 (the R16G16B16A16_SFLOAT layer's rounding).
namespace {

VegetationModel oneLeaf(glm::vec3 normal) {
  VegetationModel m = straddlingLeaves(1, 1, false);
  const glm::vec3 p[4] = {{-2, -2, 0}, {2, -2, 0}, {2, 2, 0}, {-2, 2, 0}};
  for (size_t v = 0; v < 4; ++v) {
    m.positions[v] = p[v];
    m.normals[v] = normal;
  }
  m.boundsMin = glm::vec3(-2, -2, 0);
  m.boundsMax = glm::vec3(2, 2, 0);
  return m;
}

LayerView orthoFront() {
  LayerView v;
  v.view = glm::mat4(1.0f);
  v.view[3][2] = -10.0f;  // camera at z = +10 looking down -Z
  v.proj = glm::orthoRH_ZO(-4.0f, 4.0f, -3.0f, 3.0f, 1.0f, 30.0f);
  v.proj[1][1] *= -1.0f;  // Vulkan: y down
  return v;
}

// Draws `m` with `d` seen through orthoFront(): layer 0's centre pixel and the first vertex's normal
// as the vertex shader decodes it.
Status shadeCentre(Device& dev, const VegetationModel& m, const LayeredVegetationDesc& d, glm::vec4* pixel,
                   glm::vec3* normal = nullptr) {
  LayeredVegetation lv;
  Status s = createLayeredVegetation(dev, m, d, &lv);
  std::vector<glm::vec4> c;
  if (s.ok()) s = renderOnce(dev, lv, orthoFront());
  if (s.ok()) s = readLayerColor(lv, 0, &c);
  if (s.ok()) *pixel = c[(kH / 2) * kW + kW / 2];
  if (s.ok() && normal) *normal = decodeNormal(lv.mesh.hostMesh.vertices[0]);
  destroyLayeredVegetation(lv);
  return s;
}

}  // namespace

TEST_F(LayersTest, LeafShadingMatchesTheCpuEvaluation) {
  struct Case {
    const char* what;
    glm::vec3 normal, light;
    float ior, roughness, transmission;  // transmission: LayerSettings.leafTransmission
  };
  const Case cases[] = {
      {"front lit from above", {0, 0, 1}, {0.3f, 0.5f, 0.8f}, 1.45f, 0.25f, 0.35f},
      {"front near the mirror direction, glossy", {0, 0, 1}, {0.15f, 0.0f, 1.0f}, 1.7f, 0.078f, 0.35f},
      {"front near the mirror direction, rough", {0, 0, 1}, {0.15f, 0.0f, 1.0f}, 1.2f, 0.5f, 0.35f},
      {"front at a grazing light", {0, 0, 1}, {0.95f, 0.0f, 0.2f}, 1.45f, 0.3f, 0.0f},
      {"tilted leaf, front lit", {0, 0.6f, 0.8f}, {0.0f, -0.2f, 1.0f}, 1.45f, 0.15f, 0.5f},
      {"front seen, light behind: transmission", {0, 0, 1}, {0.2f, 0.3f, -0.9f}, 1.45f, 0.25f, 0.6f},
      {"back seen, light in front of it: diffuse only", {0, 0, -1}, {0.3f, 0.4f, 0.8f}, 1.45f, 0.25f, 0.35f},
      {"back seen, light behind it: transmission", {0, 0, -1}, {-0.3f, 0.1f, -0.9f}, 1.45f, 0.25f, 0.8f},
  };
  for (TranslucencyModel model : {TranslucencyModel::Habel, TranslucencyModel::DiffuseBtdf})
  for (const Case& k : cases) {
    SCOPED_TRACE(model == TranslucencyModel::Habel ? "Habel's translucency" : "diffuse BTDF");
    const VegetationModel m = oneLeaf(glm::normalize(k.normal));
    LayeredVegetationDesc d = smallDesc("1");
    d.settings.translucencyModel = model;
    d.settings.leafOpticalDepth = 0.4f;
    d.settings.lightDirection = {k.light.x, k.light.y, k.light.z};
    d.settings.lightColor = {1.5f, 1.2f, 1.0f};
    d.settings.ambient = 0.2f;
    d.settings.leafRefractiveIndex = k.ior;
    d.settings.leafRoughness = k.roughness;
    d.settings.leafTransmission = k.transmission;
    glm::vec4 got;
    glm::vec3 n;  // the CPU side: the same decoded normal the vertex shader reads, the viewer +Z
    const Status s = shadeCentre(dev, m, d, &got, &n);
    ASSERT_TRUE(s.ok()) << s.message();
    const glm::vec3 v(0, 0, 1), l = glm::normalize(k.light);
    const bool front = glm::dot(n, v) >= 0.0f;
    if (!front) n = -n;
    const glm::vec3 base = glm::vec3(m.materials[0].baseColorFactor);
    const glm::vec3 want =
        model == TranslucencyModel::Habel
            ? gpu::leafShadeHabel(base, n, n, front, v, l, glm::vec3(1.5f, 1.2f, 1.0f), 0.2f, k.ior, k.roughness, 1.0f, k.transmission,
                                  gpu::leafTransmissionTint(base), glm::vec3(0.4f))
            : gpu::leafShade(base, n, front, v, l, glm::vec3(1.5f, 1.2f, 1.0f), 0.2f, k.ior, k.roughness, 1.0f, k.transmission,
                             gpu::leafTransmissionTint(base));
    EXPECT_NEAR(got.a, 1.0f, 1e-3f) << k.what;
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(got[i], want[i], 2e-3f * std::max(1.0f, want[i]) + 1e-3f) << k.what << ", channel " << i;
  }
}

TEST_F(LayersTest, ABacklitLeafGlowsOnItsUnlitSideAndOutOfRangeLeafParametersAreRefused) {
  const VegetationModel m = oneLeaf({0, 0, 1});
  auto centre = [&](bool translucency, float transmission, glm::vec4* out) {
    LayeredVegetationDesc d = smallDesc("1");
    d.settings.lightDirection = {0.1f, 0.2f, -1.0f};  // behind the leaf, seen from the front
    d.settings.translucency = translucency;
    d.settings.leafTransmission = transmission;
    const Status s = shadeCentre(dev, m, d, out);
    ASSERT_TRUE(s.ok()) << s.message();
  };
  glm::vec4 on, off;
  centre(true, 0.5f, &on);
  centre(false, 0.5f, &off);
  const glm::vec3 base = glm::vec3(m.materials[0].baseColorFactor);
  // Without translucency the unlit side has the ambient term only.
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(off[i], base[i] * 0.35f, 2e-3f) << "channel " << i;
  EXPECT_GT(on.g, 1.5f * off.g) << "the backlit leaf must glow";
  // The measured ranges of Habel's section III.B, refused with the range.
  LayerSettings s;
  s.leafRefractiveIndex = 1.1f;
  Status st = validateLayerSettings(s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("leafRefractiveIndex = 1.1"), std::string::npos) << st.message();
  EXPECT_NE(st.message().find("[1.2, 1.7]"), std::string::npos) << st.message();
  s = LayerSettings{};
  s.leafRoughness = 0.6f;
  st = validateLayerSettings(s);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("[0.078, 0.5]"), std::string::npos) << st.message();
  s = LayerSettings{};
  s.leafRoughness = NAN;
  EXPECT_FALSE(validateLayerSettings(s).ok());
  s = LayerSettings{};
  s.leafTransmission = -0.1f;
  EXPECT_FALSE(validateLayerSettings(s).ok());
}

// Normal maps and the transmission textures (issue 17): a 1x1 normal map tilting the normal
// towards +u and +v, and a transmission factor texture of alpha 0.5, against the CPU evaluation with the
// tilted normal (t = +x along +u, b = n x t, as the shader builds them) and the halved factor.
TEST_F(LayersTest, NormalMapsAndTransmissionTexturesEnterTheShading) {
  VegetationModel m = oneLeaf({0, 0, 1});
  const uint8_t enc[4] = {204, 166, 220, 255};  // about (0.6, 0.3, 0.73) in unit range
  ModelImage normals;
  normals.name = "normal map";
  normals.width = normals.height = 1;
  normals.rgba.assign(enc, enc + 4);
  normals.linear = true;
  ModelImage thickness;
  thickness.name = "transmission factor";
  thickness.width = thickness.height = 1;
  thickness.rgba = {255, 255, 255, 128};
  m.images = {normals, thickness};
  m.materials[0].normalImage = 0;
  m.materials[0].normalScale = 1.0f;
  m.materials[0].transmissionImage = 1;
  m.materials[0].transmissionFactor = 0.8f;
  m.materials[0].transmissionColor = glm::vec3(0.9f, 1.0f, 0.5f);
  const glm::vec3 mapped = glm::vec3(enc[0], enc[1], enc[2]) / 255.0f * 2.0f - 1.0f;
  const glm::vec3 tilted = glm::normalize(mapped.x * glm::vec3(1, 0, 0) + mapped.y * glm::vec3(0, 1, 0) + mapped.z * glm::vec3(0, 0, 1));
  const glm::vec3 base = glm::vec3(m.materials[0].baseColorFactor);
  struct Case {
    const char* what;
    glm::vec3 light;
  };
  for (const Case& k : {Case{"front lit from +x+y: the tilted normal catches more light", {0.7f, 0.5f, 0.6f}},
                        Case{"backlit: the factor texture halves the transmission", {0.2f, 0.1f, -1.0f}}}) {
    LayeredVegetationDesc d = smallDesc("1");
    d.settings.lightDirection = {k.light.x, k.light.y, k.light.z};
    d.settings.ambient = 0.2f;
    d.settings.translucencyModel = TranslucencyModel::DiffuseBtdf;  // Habel's: LayersTest.HabelsTranslucency*
    glm::vec4 got;
    const Status s = shadeCentre(dev, m, d, &got);
    ASSERT_TRUE(s.ok()) << s.message();
    const float t = 0.8f * 128.0f / 255.0f;
    const glm::vec3 want = gpu::leafShade(base, tilted, true, glm::vec3(0, 0, 1), glm::normalize(k.light), glm::vec3(1.0f), 0.2f,
                                          1.45f, 0.25f, 1.0f, t, glm::vec3(0.9f, 1.0f, 0.5f));
    const glm::vec3 flat = gpu::leafShade(base, glm::vec3(0, 0, 1), true, glm::vec3(0, 0, 1), glm::normalize(k.light), glm::vec3(1.0f),
                                          0.2f, 1.45f, 0.25f, 1.0f, t, glm::vec3(0.9f, 1.0f, 0.5f));
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(got[i], want[i], 3e-3f * std::max(1.0f, want[i]) + 2e-3f) << k.what << ", channel " << i;
    EXPECT_GT(std::abs(want.g - flat.g), 0.02f) << k.what << ": the case must tell a mapped normal from the flat one";
  }
  // A material naming an image the model does not have is refused, not read out of bounds.
  m.materials[0].normalImage = 7;
  LayeredVegetation bad;
  Status s = createLayeredVegetation(dev, m, smallDesc("1"), &bad);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("names image 7 of 2"), std::string::npos) << s.message();
}

// The layer draws' fragment shader is specialised for what the model and the settings can meet
// (docs/lab/performance-notebook.md "Specialised shading"): a settings change that changes it switches to
// pipelines made for the new settings, keeps the old ones, and a switch back reuses them; each
// switch shades as the CPU evaluation of the model in force.
TEST_F(LayersTest, SpecialisedShadingFollowsTheModelAndTheSettings) {
  const glm::vec3 light = glm::normalize(glm::vec3(0.2f, 0.3f, -0.9f));  // behind the leaf: transmission
  const VegetationModel plain = oneLeaf({0, 0, 1});
  VegetationModel mapped = plain;
  ModelImage normals;
  normals.name = "normal map";
  normals.width = normals.height = 1;
  normals.rgba = {128, 128, 255, 255};
  normals.linear = true;
  mapped.images = {normals};
  mapped.materials[0].normalImage = 0;
  mapped.materials[0].normalScale = 1.0f;
  LayeredVegetationDesc d = smallDesc("1");
  d.settings.lightDirection = {light.x, light.y, light.z};
  d.settings.ambient = 0.2f;
  d.settings.leafOpticalDepth = 0.4f;
  {
    LayeredVegetation lv;
    ASSERT_TRUE(createLayeredVegetation(dev, mapped, d, &lv).ok());
    EXPECT_EQ(lv.pipelines.shaded.features, LAYER_FEATURE_HABEL | LAYER_FEATURE_NORMAL_MAP);
    destroyLayeredVegetation(lv);
  }
  LayeredVegetation lv;
  ASSERT_TRUE(createLayeredVegetation(dev, plain, d, &lv).ok());
  EXPECT_EQ(lv.pipelines.shaded.features, LAYER_FEATURE_HABEL) << "no texture, no level colours: only Habel's model is compiled";
  const VkPipeline habelPipeline = lv.pipelines.shaded.layered.pipeline ? lv.pipelines.shaded.layered.pipeline : lv.pipelines.shaded.perLayer.pipeline;
  const glm::vec3 base = glm::vec3(plain.materials[0].baseColorFactor);
  const float t = d.settings.leafTransmission;
  const glm::vec3 tint = gpu::leafTransmissionTint(base);
  auto expectCentre = [&](const glm::vec3& want, const char* what) {
    std::vector<glm::vec4> c;
    Status s = renderOnce(dev, lv, orthoFront());
    if (s.ok()) s = readLayerColor(lv, 0, &c);
    ASSERT_TRUE(s.ok()) << s.message();
    const glm::vec4 got = c[(kH / 2) * kW + kW / 2];
    for (int i = 0; i < 3; ++i) EXPECT_NEAR(got[i], want[i], 3e-3f * std::max(1.0f, want[i]) + 2e-3f) << what << ", channel " << i;
  };
  const glm::vec3 habel = gpu::leafShadeHabel(base, glm::vec3(0, 0, 1), glm::vec3(0, 0, 1), true, glm::vec3(0, 0, 1), light, glm::vec3(1.0f),
                                              0.2f, 1.45f, 0.25f, 1.0f, t, tint, glm::vec3(0.4f));
  const glm::vec3 diffuse = gpu::leafShade(base, glm::vec3(0, 0, 1), true, glm::vec3(0, 0, 1), light, glm::vec3(1.0f), 0.2f, 1.45f, 0.25f,
                                           1.0f, t, tint);
  ASSERT_GT(glm::length(habel - diffuse), 0.01f) << "the case must tell the two models apart";
  expectCentre(habel, "Habel's model");
  LayerSettings s = d.settings;
  s.translucencyModel = TranslucencyModel::DiffuseBtdf;
  ASSERT_TRUE(setLayerSettings(lv, s).ok());
  EXPECT_EQ(lv.pipelines.shaded.features, LAYER_FEATURE_DIFFUSE_BTDF);
  EXPECT_EQ(lv.pipelines.otherShading.size(), 1u) << "Habel's pipelines kept: a frame in flight may use them";
  expectCentre(diffuse, "the diffuse BTDF");
  s.translucencyModel = TranslucencyModel::Habel;
  ASSERT_TRUE(setLayerSettings(lv, s).ok());
  EXPECT_EQ(lv.pipelines.shaded.features, LAYER_FEATURE_HABEL);
  EXPECT_EQ(lv.pipelines.otherShading.size(), 1u) << "switched back: the kept pipelines, none made";
  EXPECT_EQ(lv.pipelines.shaded.layered.pipeline ? lv.pipelines.shaded.layered.pipeline : lv.pipelines.shaded.perLayer.pipeline, habelPipeline);
  expectCentre(habel, "Habel's model again");
  destroyLayeredVegetation(lv);
}

// Habel's translucency (seed 004 III.C) against the CPU evaluation on a backlit leaf with a normal
// map and a KHR_materials_volume thickness: the light-facing side's relief and its Fresnel entry,
// its self-shadowing at grazing light and Beer-Lambert through the thickness. The relief's effect
// grows from steep to grazing light (seed Figure 5); the thickness darkens and tints.
TEST_F(LayersTest, HabelsTranslucencyMatchesTheCpuEvaluation) {
  VegetationModel m = oneLeaf({0, 0, 1});
  const uint8_t enc[4] = {204, 166, 220, 255};  // about (0.6, 0.3, 0.73): a facet of a vein's flank
  ModelImage normals;
  normals.name = "normal map";
  normals.width = normals.height = 1;
  normals.rgba.assign(enc, enc + 4);
  normals.linear = true;
  m.images = {normals};
  m.materials[0].normalImage = 0;
  m.materials[0].normalScale = 1.0f;
  m.materials[0].transmissionFactor = 0.7f;
  m.materials[0].transmissionColor = glm::vec3(0.8f, 1.0f, 0.4f);
  m.materials[0].thicknessFactor = 0.002f;  // 2 mm (KHR_materials_volume)
  m.materials[0].attenuationDistance = 0.004f;
  m.materials[0].attenuationColor = glm::vec3(0.5f, 0.9f, 0.3f);
  const glm::vec3 tau = 0.002f * -glm::log(glm::vec3(0.5f, 0.9f, 0.3f)) / 0.004f;
  const glm::vec3 mapped = glm::vec3(enc[0], enc[1], enc[2]) / 255.0f * 2.0f - 1.0f;
  const glm::vec3 tilted = glm::normalize(mapped);
  const glm::vec3 base = glm::vec3(m.materials[0].baseColorFactor);
  float reliefSteep = 0, reliefGrazing = 0;
  for (float elevation : {80.0f, 45.0f, 20.0f, 8.0f}) {
    // The light behind the leaf (seen from +z, its front), from steep to grazing.
    const float e = glm::radians(elevation);
    const glm::vec3 l(-std::cos(e), 0.0f, -std::sin(e));
    LayeredVegetationDesc d = smallDesc("1");
    d.settings.lightDirection = {l.x, l.y, l.z};
    d.settings.ambient = 0.2f;
    glm::vec4 got;
    const Status s = shadeCentre(dev, m, d, &got);
    ASSERT_TRUE(s.ok()) << s.message();
    const glm::vec3 want = gpu::leafShadeHabel(base, tilted, glm::vec3(0, 0, 1), true, glm::vec3(0, 0, 1), l, glm::vec3(1.0f), 0.2f,
                                               1.45f, 0.25f, 1.0f, 0.7f, glm::vec3(0.8f, 1.0f, 0.4f), tau);
    const glm::vec3 flat = gpu::leafShadeHabel(base, glm::vec3(0, 0, 1), glm::vec3(0, 0, 1), true, glm::vec3(0, 0, 1), l, glm::vec3(1.0f),
                                               0.2f, 1.45f, 0.25f, 1.0f, 0.7f, glm::vec3(0.8f, 1.0f, 0.4f), tau);
    const glm::vec3 btdf = gpu::leafShade(base, tilted, true, glm::vec3(0, 0, 1), l, glm::vec3(1.0f), 0.2f, 1.45f, 0.25f, 1.0f, 0.7f,
                                          glm::vec3(0.8f, 1.0f, 0.4f));
    std::printf("light %2.0f deg above the leaf's plane: Habel (%.4f %.4f %.4f), flat relief (%.4f %.4f %.4f), diffuse BTDF (%.4f %.4f %.4f)\n",
                elevation, want.r, want.g, want.b, flat.r, flat.g, flat.b, btdf.r, btdf.g, btdf.b);
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(got[i], want[i], 3e-3f * std::max(1.0f, want[i]) + 2e-3f) << elevation << " deg, channel " << i;
    const float ambient = 0.2f * base.g;
    const float relief = std::abs((want.g - ambient) / std::max(flat.g - ambient, 1e-6f) - 1.0f);
    if (elevation == 80.0f) reliefSteep = relief;
    if (elevation == 8.0f) reliefGrazing = relief;
    // Beer-Lambert: the red and blue channels (attenuated more) fall below what the colour alone gives.
    EXPECT_LT((want.b - 0.2f * base.b) / 0.4f, (want.g - 0.2f * base.g) / 1.0f) << elevation;
  }
  EXPECT_GT(reliefGrazing, 2.0f * reliefSteep) << "the relief shows at grazing light, not at steep light";
}

// Habel's translucency on the shared plant with a thickness added (KHR_materials_volume's values
// set on its foliage materials): the backlit leaves transmit less; the diffuse BTDF ignores the
// thickness.
TEST_F(LayersTest, ThePlantWithAThicknessAddedTransmitsLess) {
  const std::string path = kAssets + "/DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << "shared assets folder absent (" << kAssets << "): skipped";
  VegetationModel plain;
  ASSERT_TRUE(loadGltf(path, {}, &plain).ok());
  VegetationModel thick = plain;
  for (ModelMaterial& mat : thick.materials)
    if (mat.transmissionFactor > 0.0f) {
      mat.thicknessFactor = 0.002f;
      mat.attenuationDistance = 0.002f;
      mat.attenuationColor = glm::vec3(0.3f, 0.8f, 0.2f);
    }
  const LayerView view = orbitView(plain.boundsMin, plain.boundsMax, 0.0f, 10.0f, 40.0f, float(kW) / float(kH), 1.0f);
  // Mean colour of layer 0's covered texels, the light behind the plant.
  auto mean = [&](const VegetationModel& m, TranslucencyModel model) {
    LayeredVegetationDesc d = smallDesc("1");
    d.settings.lightDirection = {0.2f, 0.4f, -1.0f};
    d.settings.translucencyModel = model;
    d.settings.leafTransmission = 0.8f;
    LayeredVegetation lv;
    Status s = createLayeredVegetation(dev, m, d, &lv);
    std::vector<glm::vec4> c;
    if (s.ok()) s = renderOnce(dev, lv, view);
    if (s.ok()) s = readLayerColor(lv, 0, &c);
    EXPECT_TRUE(s.ok()) << s.message();
    destroyLayeredVegetation(lv);
    glm::dvec3 sum(0.0);
    size_t n = 0;
    for (const glm::vec4& p : c)
      if (p.a > 0.5f) sum += glm::dvec3(p) / double(p.a), ++n;
    EXPECT_GT(n, 1000u);
    return glm::vec3(sum / double(std::max<size_t>(n, 1)));
  };
  const glm::vec3 a = mean(plain, TranslucencyModel::Habel), b = mean(thick, TranslucencyModel::Habel);
  const glm::vec3 c = mean(plain, TranslucencyModel::DiffuseBtdf), e = mean(thick, TranslucencyModel::DiffuseBtdf);
  std::printf("backlit plant, mean leaf colour: Habel (%.4f %.4f %.4f) -> with thickness (%.4f %.4f %.4f); diffuse BTDF (%.4f %.4f %.4f) -> (%.4f %.4f %.4f)\n",
              a.r, a.g, a.b, b.r, b.g, b.b, c.r, c.g, c.b, e.r, e.g, e.b);
  // The file's transmission colour texture passes mostly red: the glow, and so what the thickness
  // takes away, is in the channels the leaves transmit; no channel gains.
  for (int k = 0; k < 3; ++k) {
    EXPECT_LE(b[k], a[k] + 1e-5f) << "channel " << k << ": the thickness absorbs";
    EXPECT_NEAR(e[k], c[k], 1e-4f) << "channel " << k << ": the BTDF has no thickness";
  }
  EXPECT_LT(b.r + b.g + b.b, a.r + a.g + a.b - 0.003f) << "the backlit plant transmits less through a thickness";
}
