// Compressed glTF as the public tools write it (issue 78; render/gltf_compressed.h): the files in
// tests/data/compressed/ were made from ../shared/assets' KayKit tree by
// scripts/make_compressed_gltf.sh (gltf-transform: Draco, WebP; gltfpack: meshopt, and quantization
// with KHR_texture_transform). Each draws the frame its original draws (silhouette IoU >= 0.97,
// colour within the lossy codecs' error), on lavapipe with validation (GpuTest). The originals are
// read from ../shared/assets: without it the comparison skips with a message.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "engine/camera.h"
#include "render/canopy.h"
#include "render/gltf_loader.h"
#include "tests/assets.h"
#include "tests/gpu_test.h"
#include "tests/test_host.h"

using namespace canopy;

namespace {

const std::string kCompressed = std::string(CANOPY_SOURCE_DIR) + "/tests/data/compressed/";

class CompressedGltfTest : public canopy::test::GpuTest {
 protected:
  void configure(DeviceDesc& d) override { d.deferUploads = true; }
  uint64_t frameNumber = 0;
};

TEST_F(CompressedGltfTest, EachToolsFileDrawsTheFrameOfItsOriginal) {
  REQUIRE_ASSETS();
  VegetationModel original;
  Status s = loadGltf(test::kAssets + "/kaykit_tree_1_c/Tree_1_C_Color1.gltf", {}, &original);
  ASSERT_TRUE(s.ok()) << s.message();
  const LayerView view = orbitView(original.boundsMin, original.boundsMax, 30.0f, 10.0f, 40.0f, 160.0f / 120.0f, 1.05f);
  std::vector<glm::vec4> c0;
  std::vector<float> z0;
  s = test::renderHostFrames(dev, frameNumber, {SpeciesModel{&original}}, {}, view, 2, &c0, &z0, nullptr, false, 0.0f);
  ASSERT_TRUE(s.ok()) << s.message();
  size_t covered0 = 0;
  for (float z : z0) covered0 += z < 1.0f;
  ASSERT_GT(covered0, c0.size() / 10) << "the tree fills part of the frame";
  for (const char* name : {"kaykit_draco.glb", "kaykit_meshopt.glb", "kaykit_quantized.glb", "kaykit_webp.glb"}) {
    SCOPED_TRACE(name);
    VegetationModel m;
    s = loadGltf(kCompressed + name, {}, &m);
    ASSERT_TRUE(s.ok()) << s.message();
    for (const std::string& w : m.warnings) std::printf("%s: warning: %s\n", name, w.c_str());
    std::vector<glm::vec4> c;
    std::vector<float> z;
    s = test::renderHostFrames(dev, frameNumber, {SpeciesModel{&m}}, {}, view, 2, &c, &z, nullptr, false, 0.0f);
    ASSERT_TRUE(s.ok()) << s.message();
    size_t both = 0, either = 0;
    double colour = 0;
    for (size_t i = 0; i < z.size(); ++i) {
      const bool a = z0[i] < 1.0f, b = z[i] < 1.0f;
      both += a && b;
      either += a || b;
      if (a && b) colour += test::maxDiff(c[i], c0[i]);
    }
    const double iou = double(both) / double(std::max<size_t>(either, 1)), meanColour = colour / double(std::max<size_t>(both, 1));
    std::printf("%s: %zu triangles (original %zu), silhouette IoU %.4f, mean colour difference %.4f\n", name, m.triangleCount(),
                original.triangleCount(), iou, meanColour);
    EXPECT_GE(iou, 0.97);
    // Quantized positions and coordinates, WebP's lossy texels: a few hundredths at most; a texture
    // transform left out (or a WebP not decoded) reads the wrong texels of the atlas: tenths.
    EXPECT_LE(meanColour, 0.03);
  }
}

}  // namespace
