#pragma once
// The layer tests' models, views and fixtures (tests/layers_test.cpp, tests/layers_mesh_test.cpp).
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

namespace canopy::test::layers {

using namespace canopy;
using canopy::test::kAssets;
using canopy::test::GpuTest;

constexpr uint32_t kW = 320, kH = 240;

// Leaves in a screen grid (disjoint on screen), each a quad of two triangles tilted about the
// vertical so it spans 1.2 units of depth: many straddle layer boundaries. Material 0 is the
// foliage; with `bark`, a rigid quad (material 1) stands behind them all.
inline VegetationModel straddlingLeaves(uint32_t cols, uint32_t rows, bool bark) {
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

inline LayerView frontView() {
  LayerView v;
  v.view = glm::mat4(1.0f);
  v.view[3][2] = -10.0f;  // camera at z = +10 looking down -Z
  v.proj = perspectiveVulkan(glm::radians(40.0f), float(kW) / float(kH), 1.0f, 30.0f);
  return v;
}

inline Status renderOnce(Device& dev, LayeredVegetation& lv, const LayerView& view) {
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

inline LayeredVegetationDesc smallDesc(const char* layout = "5(3-1-1)") {
  LayeredVegetationDesc d;
  d.width = kW;
  d.height = kH;
  d.writeIds = true;
  // The layers' own background (these tests read it); rigid parts drawn every frame: RigidMotionTest.
  d.settings.rigidMotion = RigidMotion::Still;
  EXPECT_TRUE(parseLayerLayout(layout, &d.settings.layout).ok());
  return d;
}

struct Coverage {
  std::map<uint32_t, std::set<uint32_t>> layersOfLeaf, layersOfTriangle;
};

inline Coverage readCoverage(LayeredVegetation& lv) {
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
inline std::map<uint32_t, glm::vec3> rootPositions(const LayeredVegetation& lv) {
  std::map<uint32_t, glm::vec3> r;
  for (const MeshChunk& c : lv.mesh.chunks)
    for (uint32_t i = 0; i < c.rootCount; ++i) r[lv.mesh.hostMesh.roots[c.firstRoot + i].leaf] = lv.mesh.hostMesh.roots[c.firstRoot + i].position;
  return r;
}

// Leaves whose own vertices lie on both sides of a layer boundary.
inline uint32_t countStraddlers(const LayeredVegetation& lv) {
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
inline void expectIdentical(const std::vector<float>& a, const std::vector<float>& b, uint32_t channels,
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
inline void expectClose(const std::vector<glm::vec4>& a, const std::vector<glm::vec4>& b, float tol, double maxShare,
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

inline void expectSameLayers(LayeredVegetation& x, LayeredVegetation& y, const std::string& what) {
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

}  // namespace canopy::test::layers
