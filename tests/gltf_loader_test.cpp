// The glTF loader against real vegetation, the glTF-Validator corpus (its expected reports are the
// oracle), tinygltf's regression files, and hand-made hostile files. Built with AddressSanitizer
// in the test configuration: no crash and no out-of-bounds read anywhere.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

#include "render/gltf_loader.h"
#include "tests/model_checks.h"

#include "tests/assets.h"

using namespace canopy;
using canopy::test::expectConsistent;
using canopy::test::kAssets;

TEST(GltfLoader, RealVegetationLoadsWithExpectedCounts) {
  REQUIRE_ASSETS();
  struct Case { const char* file; size_t triangles; size_t images; };
  // Triangle counts from ../shared/assets/README.md.
  // Images: base colour and the leaves' transmission colour (sRGB), two normal maps (linear).
  const Case cases[] = {{"DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf", 68409, 5},
                        {"fern_02/fern_02.glb", 6232, 2},  // base colour and normal map
                        {"quaternius_CommonTree_1/CommonTree_1.glb", 2888, 0},
                        {"quaternius_PineTree_1/PineTree_1.glb", 1911, 0},
                        {"quaternius_Grass/Grass.glb", 192, 0},
                        {"polypizza_flower_bushes/flower_bushes.glb", 580, 1}};
  for (const Case& c : cases) {
    VegetationModel m;
    Status s = loadGltf(kAssets + "/" + c.file, {}, &m);
    ASSERT_TRUE(s.ok()) << s.message();
    EXPECT_EQ(m.triangleCount(), c.triangles) << c.file;
    EXPECT_EQ(m.images.size(), c.images) << c.file;
    expectConsistent(m, c.file);
    std::printf("  %-58s %7zu triangles, %6zu vertices, %zu materials, %zu images\n", c.file, m.triangleCount(),
                m.positions.size(), m.materials.size() - 1, m.images.size());
  }
}

// KHR_materials_diffuse_transmission (issue 17): the sample plant's leaves transmit 0.1 in white
// times their colour texture, with a normal map; its other materials have no transmission from
// the file (-1: the layer settings decide).
TEST(GltfLoader, DiffuseTransmissionFactorsAreRead) {
  REQUIRE_ASSETS();
  VegetationModel m;
  Status s = loadGltf(kAssets + "/DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf", {}, &m);
  ASSERT_TRUE(s.ok()) << s.message();
  bool leaves = false;
  for (const ModelMaterial& mm : m.materials) {
    if (mm.name == "leaves") {
      leaves = true;
      EXPECT_FLOAT_EQ(mm.transmissionFactor, 0.1f);
      EXPECT_EQ(mm.transmissionColor, glm::vec3(1.0f));
      ASSERT_GE(mm.transmissionColorImage, 0) << "its diffuseTransmissionColorTexture";
      EXPECT_FALSE(m.images[size_t(mm.transmissionColorImage)].linear);
      ASSERT_GE(mm.normalImage, 0) << "its normalTexture";
      EXPECT_TRUE(m.images[size_t(mm.normalImage)].linear) << "normal maps are data, not sRGB colour";
      EXPECT_EQ(mm.transmissionImage, -1);
    } else {
      EXPECT_EQ(mm.transmissionFactor, -1.0f) << mm.name;
    }
  }
  EXPECT_TRUE(leaves);
}

// Quaternius models carry node scale 100 and a -90 degree X rotation: applied, the tree stands up
// (y extent larger than z) at a few metres, not hundreds.
TEST(GltfLoader, NodeTransformsAreApplied) {
  REQUIRE_ASSETS();
  VegetationModel m;
  ASSERT_TRUE(loadGltf(kAssets + "/quaternius_CommonTree_1/CommonTree_1.glb", {}, &m).ok());
  const glm::vec3 e = m.boundsMax - m.boundsMin;
  std::printf("  CommonTree_1 extent %.2f x %.2f x %.2f\n", e.x, e.y, e.z);
  EXPECT_GT(e.y, 1.0f);
  EXPECT_LT(e.y, 50.0f);
  EXPECT_GT(e.y, e.z * 0.8f);
}

// Files the validator finds no error in load, every one (issue 68: a part the vegetation does not
// read no longer refuses the file; render/gltf_prune.h).
TEST(GltfLoader, ValidatorCorpusFollowsItsReports) {
  REQUIRE_ASSETS();
  const std::string dir = kAssets + "/malformed/gltf-validator/";
  std::ifstream index(dir + "INDEX.tsv");
  ASSERT_TRUE(index.good());
  std::string line;
  std::getline(index, line);
  int valid = 0, refused = 0, loadedWithErrors = 0;
  while (std::getline(index, line)) {
    std::istringstream ls(line);
    std::string file, errors;
    std::getline(ls, file, '\t');
    std::getline(ls, errors, '\t');
    VegetationModel m;
    Status s = loadGltf(dir + file, {}, &m);
    if (std::stoi(errors) == 0) {
      ++valid;
      EXPECT_TRUE(s.ok()) << file << " has no validator error but was refused: " << s.message();
    } else if (!s.ok()) {
      ++refused;
      EXPECT_NE(s.message().find(file), std::string::npos) << "the message must name the file: " << s.message();
    } else {
      ++loadedWithErrors;  // only an unused part is broken: what was loaded must be sound
    }
    if (s.ok()) expectConsistent(m, file);
  }
  std::printf("  %d files without validator errors; of the files with errors %d refused, %d loaded without the broken part\n",
              valid, refused, loadedWithErrors);
}

// tinygltf's own regression files, as ../shared/assets/malformed/LICENSE.md describes them.
TEST(GltfLoader, TinygltfRegressionFiles) {
  REQUIRE_ASSETS();
  const std::string dir = kAssets + "/malformed/tinygltf/";
  struct Case { const char* file; bool loads; const char* mentions; };
  const Case cases[] = {
      // Their broken mesh (or image) is in no scene (no nodes): nothing of it is read, so it
      // refuses nothing (issue 68) and the model is empty.
      {"models/BoundsChecking/invalid-primitive-indices.gltf", true, ""},
      {"models/BoundsChecking/invalid-buffer-view-index.gltf", true, ""},
      {"models/BoundsChecking/invalid-buffer-index.gltf", true, ""},  // the broken image: no material reads it
      {"models/BoundsChecking/integer-out-of-bounds.gltf", false, ""},
      {"tests/issue-416.gltf", false, ""},  // URI naming a directory: refused, no huge allocation
      {"tests/issue-492.glb", true, ""},    // valid: skin without inverseBindMatrices
  };
  for (const Case& c : cases) {
    VegetationModel m;
    Status s = loadGltf(dir + c.file, {}, &m);
    std::printf("  %-55s %s\n", c.file, s.ok() ? "loaded" : s.message().c_str());
    EXPECT_EQ(s.ok(), c.loads) << c.file << ": " << s.message();
    if (!s.ok()) EXPECT_NE(s.message().find(c.mentions), std::string::npos) << s.message();
    if (s.ok()) expectConsistent(m, c.file);
  }
  // Valid per the spec but refused by tinygltf 2.7.0 (accepted upstream only since 2024): a clear
  // refusal or a load are both acceptable; a crash is not.
  VegetationModel m;
  Status s = loadGltf(dir + "models/regression/zero-sized-bin-chunk-issue-440.glb", {}, &m);
  std::printf("  zero-sized-bin-chunk-issue-440.glb: %s\n", s.ok() ? "loaded" : s.message().c_str());
  if (s.ok()) expectConsistent(m, "issue-440");
}

// ---- hand-made hostile files ------------------------------------------------------------------------
namespace {

struct TempDir {
  std::string path;
  TempDir() {
    char tmpl[] = "/tmp/canopy-gltf-XXXXXX";
    path = mkdtemp(tmpl);
    mkdir((path + "/model").c_str(), 0755);
  }
  ~TempDir() { std::system(("rm -rf '" + path + "'").c_str()); }
  void write(const std::string& name, const std::string& data) const { std::ofstream(path + "/" + name, std::ios::binary) << data; }
};

// One triangle: 3 float3 positions (36 bytes) + 3 uint16 indices (6 bytes, padded to 8).
std::string triangleBin() {
  std::string b(44, '\0');
  const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(&b[0], p, 36);
  const uint16_t idx[3] = {0, 1, 2};
  std::memcpy(&b[36], idx, 6);
  return b;
}

// A minimal glTF with placeholders to break one thing at a time.
std::string gltfJson(const std::string& uri, const std::string& posAccessor, const std::string& idxView,
                     const std::string& extra = "", int mode = 4, const std::string& nodes = R"([{"mesh":0}])") {
  return R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":)" + nodes +
         R"(,"meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"mode":)" + std::to_string(mode) +
         R"(}]}],"buffers":[{"uri":")" + uri + R"(","byteLength":44}],"bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":36},)" +
         idxView + R"(],"accessors":[)" + posAccessor +
         R"(,{"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}])" + extra + "}";
}
const std::string kPos = R"({"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]})";
const std::string kIdxView = R"({"buffer":0,"byteOffset":36,"byteLength":6})";

}  // namespace

TEST(GltfLoader, HandMadeBrokenFilesAreRefused) {
  TempDir t;
  t.write("model/tri.bin", triangleBin());
  t.write("secret.bin", triangleBin());
  mkdir((t.path + "/model/adir").c_str(), 0755);
  // Sanity: the unbroken file loads.
  t.write("model/ok.gltf", gltfJson("tri.bin", kPos, kIdxView));
  VegetationModel m;
  Status s = loadGltf(t.path + "/model/ok.gltf", {}, &m);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(m.triangleCount(), 1u);

  std::string badIndexBin = triangleBin();
  const uint16_t bigIdx = 7;
  std::memcpy(&badIndexBin[38], &bigIdx, 2);
  t.write("model/badidx.bin", badIndexBin);

  struct Case { const char* name; std::string json; const char* mentions; };
  const Case cases[] = {
      {"accessor past its view", gltfJson("tri.bin", R"({"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"})", kIdxView), "accessors[0]"},
      {"view past its buffer", gltfJson("tri.bin", kPos, R"({"buffer":0,"byteOffset":40,"byteLength":6})"), "bufferViews[1]"},
      {"index past the vertex count", gltfJson("badidx.bin", kPos, kIdxView), "indices[1] = 7"},
      {"parent escape", gltfJson("../secret.bin", kPos, kIdxView), "leaves the model's folder"},
      {"absolute path", gltfJson(t.path + "/secret.bin", kPos, kIdxView), "absolute"},
      {"directory uri", gltfJson("adir", kPos, kIdxView), "not a regular file"},
      {"missing buffer", gltfJson("nope.bin", kPos, kIdxView), "nope.bin"},
      {"node loop", gltfJson("tri.bin", kPos, kIdxView, "", 4, R"([{"mesh":0,"children":[1]},{"children":[0]}])"), "nodes["},
      {"missing mesh", gltfJson("tri.bin", kPos, kIdxView, "", 4, R"([{"mesh":5}])"), "mesh 5"},
      {"broken texture", gltfJson("tri.bin", kPos, kIdxView, R"(,"materials":[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}],"textures":[{"source":0}],"images":[{"uri":"junk.png"}])"), "images[0]"},
      {"transmission factor out of range", gltfJson("tri.bin", kPos, kIdxView, R"(,"materials":[{"extensions":{"KHR_materials_diffuse_transmission":{"diffuseTransmissionFactor":2}}}])"), "KHR_materials_diffuse_transmission.diffuseTransmissionFactor must be a number in [0, 1]"},
      {"transmission colour not 3 numbers", gltfJson("tri.bin", kPos, kIdxView, R"(,"materials":[{"extensions":{"KHR_materials_diffuse_transmission":{"diffuseTransmissionColorFactor":[1,"x",1]}}}])"), "diffuseTransmissionColorFactor must be 3 numbers"},
      {"transmission factor a string", gltfJson("tri.bin", kPos, kIdxView, R"(,"materials":[{"extensions":{"KHR_materials_transmission":{"transmissionFactor":"1"}}}])"), "KHR_materials_transmission.transmissionFactor"},
      {"transmission volume thickness negative", gltfJson("tri.bin", kPos, kIdxView, R"(,"materials":[{"extensions":{"KHR_materials_volume":{"thicknessFactor":-1}}}])"), "KHR_materials_volume.thicknessFactor must be a number"},
      {"transmission volume attenuation zero", gltfJson("tri.bin", kPos, kIdxView, R"(,"materials":[{"extensions":{"KHR_materials_volume":{"attenuationDistance":0}}}])"), "KHR_materials_volume.attenuationDistance"},
      {"transmission volume colour", gltfJson("tri.bin", kPos, kIdxView, R"(,"materials":[{"extensions":{"KHR_materials_volume":{"attenuationColor":[1,2,1]}}}])"), "KHR_materials_volume.attenuationColor must be 3 numbers in [0, 1]"},
  };
  t.write("model/junk.png", "this is not a png");
  // KHR_materials_volume read (Habel's translucency: the leaf's thickness and attenuation).
  {
    std::string json = gltfJson("tri.bin", kPos, kIdxView,
                                R"(,"materials":[{"extensions":{"KHR_materials_volume":{"thicknessFactor":0.002,"attenuationDistance":0.004,"attenuationColor":[0.5,0.9,0.3]}}}])");
    json.replace(json.find(R"("indices":1)"), 11, R"("indices":1,"material":0)");
    t.write("model/volume.gltf", json);
    ASSERT_TRUE(loadGltf(t.path + "/model/volume.gltf", {}, &m).ok());
    EXPECT_FLOAT_EQ(m.materials[0].thicknessFactor, 0.002f);
    EXPECT_FLOAT_EQ(m.materials[0].attenuationDistance, 0.004f);
    EXPECT_FLOAT_EQ(m.materials[0].attenuationColor.z, 0.3f);
    EXPECT_LT(m.materials[1].thicknessFactor, 0.0f) << "the default material has no volume";
  }
  // Lines are not refused: left out with a warning (issue 68), here leaving no triangle.
  t.write("model/lines.gltf", gltfJson("tri.bin", kPos, kIdxView, "", 1));
  s = loadGltf(t.path + "/model/lines.gltf", {}, &m);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(m.triangleCount(), 0u);
  ASSERT_FALSE(m.warnings.empty());
  EXPECT_NE(m.warnings[0].find("mode 1 (lines) is not drawn as triangles (skipped)"), std::string::npos) << m.warnings[0];
  for (const Case& c : cases) {
    std::string json = c.json;
    if (std::string(c.name) == "broken texture" || std::string(c.name).rfind("transmission", 0) == 0)
      json.replace(json.find(R"("indices":1)"), 11, R"("indices":1,"material":0)");
    t.write("model/case.gltf", json);
    s = loadGltf(t.path + "/model/case.gltf", {}, &m);
    std::printf("  %-28s %s\n", c.name, s.ok() ? "LOADED" : s.message().c_str());
    EXPECT_FALSE(s.ok()) << c.name;
    EXPECT_NE(s.message().find(c.mentions), std::string::npos) << c.name << ": " << s.message();
    EXPECT_NE(s.message().find("case.gltf"), std::string::npos) << "the message names the file";
    EXPECT_EQ(m.triangleCount(), 0u);
  }
}

TEST(GltfLoader, TruncatedGlbIsRefused) {
  REQUIRE_ASSETS();
  std::ifstream in(kAssets + "/quaternius_Grass/Grass.glb", std::ios::binary);
  std::string glb((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_GT(glb.size(), 100u);
  TempDir t;
  for (size_t cut : {size_t(12), size_t(19), glb.size() / 2, glb.size() - 4}) {
    t.write("model/cut.glb", glb.substr(0, cut));
    VegetationModel m;
    Status s = loadGltf(t.path + "/model/cut.glb", {}, &m);
    std::printf("  cut at %zu bytes: %s\n", cut, s.message().c_str());
    EXPECT_FALSE(s.ok()) << "cut at " << cut;
  }
  // Every prefix length refuses cleanly (no read past the end under AddressSanitizer).
  for (size_t cut = 0; cut < glb.size(); cut += 97) {
    t.write("model/cut.glb", glb.substr(0, cut));
    VegetationModel m;
    EXPECT_FALSE(loadGltf(t.path + "/model/cut.glb", {}, &m).ok()) << cut;
  }
}
