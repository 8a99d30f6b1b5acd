// Scene files (readCanopyScene, parseCanopyScene; docs/scene-files.md): the documented keys read
// into species and copies, scatters the same for a seed, every class of bad input refused naming
// the file and the JSON pointer, species' files checked to be regular files, the example scenes in
// demo/scenes/ read (the six-species one with its models loaded, skipped without the assets).
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include <glm/glm.hpp>
#include <gtest/gtest.h>

#include <canopy/canopy.h>

#include "engine/camera.h"

namespace canopy {
namespace {

Status parse(const std::string& text, CanopyScene* out, const std::string& folder = "scenes") {
  return parseCanopyScene("test.json", text, folder, out);
}

glm::mat4 matrixOf(const CanopyInstance& c) {
  glm::mat4 m;
  for (int i = 0; i < 16; ++i) (&m[0][0])[i] = c.transform.m[i];
  return m;
}

// The issue's example, with a generated species in place of a file.
const char* kExample = R"({
  "species":   [ { "name": "oak", "gltf": "trees/oak.glb", "flexibility": 0.6 },
                 { "name": "grass", "generated": "grass", "faces": 20000, "seed": 3, "responseSpeed": 2 } ],
  "instances": [ { "species": "oak", "position": [1, 0, 2], "yawDegrees": 30,
                   "scale": 1.5, "tint": [1.0, 0.95, 0.9], "windPhase": 0.25 } ],
  "scatter":   [ { "species": "grass", "count": 400, "center": [0, 0, 0],
                   "radius": 12.0, "seed": 1, "scale": [0.8, 1.2] } ] })";

TEST(SceneFile, TheDocumentedKeysAreRead) {
  CanopyScene s;
  const Status st = parse(kExample, &s);
  ASSERT_TRUE(st.ok()) << st.message();
  ASSERT_EQ(s.species.size(), 2u);
  EXPECT_EQ(s.species[0].name, "oak");
  EXPECT_EQ(s.species[0].gltf, "scenes/trees/oak.glb");  // relative to the scene file's folder
  EXPECT_FLOAT_EQ(s.species[0].flexibility, 0.6f);
  EXPECT_FLOAT_EQ(s.species[0].responseSpeed, 1.0f);
  EXPECT_EQ(s.species[1].generated, "grass");
  EXPECT_EQ(s.species[1].faces, 20000u);
  EXPECT_EQ(s.species[1].seed, 3u);
  EXPECT_FLOAT_EQ(s.species[1].responseSpeed, 2.0f);
  ASSERT_EQ(s.instances.size(), 401u);
  const CanopySceneInstance& oak = s.instances[0];
  EXPECT_EQ(oak.species, 0u);
  // Translation, then 30 degrees about +Y, then the scale: the model's +X lands at 1.5 (cos 30, 0, -sin 30).
  const glm::vec4 x = matrixOf(oak.placement) * glm::vec4(1, 0, 0, 1);
  EXPECT_NEAR(x.x, 1.0f + 1.5f * std::cos(glm::radians(30.0f)), 1e-5f);
  EXPECT_NEAR(x.y, 0.0f, 1e-5f);
  EXPECT_NEAR(x.z, 2.0f - 1.5f * std::sin(glm::radians(30.0f)), 1e-5f);
  EXPECT_FLOAT_EQ(oak.placement.tint.y, 0.95f);
  EXPECT_FLOAT_EQ(oak.placement.windPhase, 0.25f);
  for (size_t i = 1; i < s.instances.size(); ++i) {
    const glm::mat4 m = matrixOf(s.instances[i].placement);
    EXPECT_EQ(s.instances[i].species, 1u);
    EXPECT_LE(glm::length(glm::vec3(m[3])), 12.0f + 1e-4f) << i;
    EXPECT_EQ(m[3].y, 0.0f);
    const float scale = glm::length(glm::vec3(m[1]));  // uniform: the +Y column's length
    EXPECT_GE(scale, 0.8f - 1e-5f);
    EXPECT_LE(scale, 1.2f + 1e-5f);
  }
}

TEST(SceneFile, AScatterIsTheSameForItsSeedAndCoversItsDisc) {
  CanopyScene a, b, c;
  ASSERT_TRUE(parse(kExample, &a).ok());
  ASSERT_TRUE(parse(kExample, &b).ok());
  std::string other = kExample;
  other.replace(other.find("\"seed\": 1"), 9, "\"seed\": 2");
  ASSERT_TRUE(parse(other, &c).ok());
  int differ = 0, outer = 0;
  for (size_t i = 1; i < a.instances.size(); ++i) {
    const glm::mat4 ma = matrixOf(a.instances[i].placement), mb = matrixOf(b.instances[i].placement),
                    mc = matrixOf(c.instances[i].placement);
    EXPECT_EQ(ma, mb) << i;
    differ += ma != mc;
    outer += glm::length(glm::vec3(ma[3])) > 12.0f * std::sqrt(0.5f);  // uniform by area: half outside
  }
  EXPECT_EQ(differ, 400);
  EXPECT_GT(outer, 160);
  EXPECT_LT(outer, 240);
}

TEST(SceneFile, EveryBadInputIsRefusedNamingThePointer) {
  const std::string sp = R"("species": [{"name": "oak", "generated": "tree"}])";
  const std::string inst = R"("instances": [{"species": "oak", "position": [0, 0, 0]}])";
  struct Case {
    std::string text, mentions;
  };
  const std::string longName(65, 'n');
  const Case cases[] = {
      {"{ not json", "not JSON"},
      {"[1, 2]", "/: expected an object, got an array"},
      {"{" + sp + ", " + inst + R"(, "sky": 1})", "/sky: unknown key"},
      {"{" + inst + "}", "/species: missing"},
      {R"({"species": []})", "/species: empty"},
      {R"({"species": {"name": "oak"}})", "/species: expected an array, got an object"},
      {R"({"species": [{"name": "oak", "generated": "tree", "colour": 1}], )" + inst + "}", "/species/0/colour: unknown key"},
      {R"({"species": [{"generated": "tree"}], )" + inst + "}", "/species/0/name: missing"},
      {R"({"species": [{"name": ")" + longName + R"(", "generated": "tree"}], )" + inst + "}", "/species/0/name: expected 1..64 characters"},
      {R"({"species": [{"name": "oak", "gltf": "a.glb", "generated": "tree"}], )" + inst + "}", "/species/0: needs exactly one"},
      {R"({"species": [{"name": "oak"}], )" + inst + "}", "/species/0: needs exactly one"},
      {R"({"species": [{"name": "oak", "generated": "cactus"}], )" + inst + "}", "/species/0/generated: unknown plant 'cactus'"},
      {R"({"species": [{"name": "oak", "gltf": "a.glb", "faces": 5000}], )" + inst + "}", "/species/0/faces: only a generated species"},
      {R"({"species": [{"name": "oak", "generated": "tree", "faces": 10}], )" + inst + "}", "/species/0/faces: expected an integer in [2000, 200000000]"},
      {R"({"species": [{"name": "oak", "generated": "tree", "faces": 1e300}], )" + inst + "}", "/species/0/faces"},
      {R"({"species": [{"name": "oak", "generated": "tree", "seed": -1}], )" + inst + "}", "/species/0/seed"},
      {R"({"species": [{"name": "oak", "generated": "tree"}, {"name": "oak", "generated": "shrub"}], )" + inst + "}",
       "/species/1/name: 'oak' names a species twice"},
      {R"({"species": [{"name": "oak", "generated": "tree", "flexibility": 5}], )" + inst + "}", "/species/0/flexibility: expected a number in [0, 4]"},
      {R"({"species": [{"name": "oak", "generated": "tree", "flexibility": "soft"}], )" + inst + "}", "/species/0/flexibility: expected a number in [0, 4], got a string"},
      {R"({"species": [{"name": "oak", "generated": "tree", "responseSpeed": 0}], )" + inst + "}", "/species/0/responseSpeed"},
      {"{" + sp + R"(, "instances": [{"species": "elm", "position": [0, 0, 0]}]})", "/instances/0/species: 'elm' is not a species"},
      {"{" + sp + R"(, "instances": [{"species": "oak"}]})", "/instances/0/position: missing"},
      {"{" + sp + R"(, "instances": [{"species": "oak", "position": [0, 0]}]})", "/instances/0/position: expected an array of 3 numbers"},
      {"{" + sp + R"(, "instances": [{"species": "oak", "position": [0, 1e300, 0]}]})", "/instances/0/position/1: expected a number in [-1e+06, 1e+06]"},
      {"{" + sp + R"(, "instances": [{"species": "oak", "position": [0, null, 0]}]})", "/instances/0/position/1: expected a number in [-1e+06, 1e+06], got null"},
      {"{" + sp + R"(, "instances": [{"species": "oak", "position": [0, 0, 0]}, {"species": "oak", "position": [0, 0, 0]},
          {"species": "oak", "position": [0, 0, 0]}, {"species": "oak", "position": [0, 0, 0], "scale": 0}]})",
       "/instances/3/scale: expected a number in [0.001, 1000], got 0"},
      {"{" + sp + R"(, "instances": [{"species": "oak", "position": [0, 0, 0], "tint": [1, 1, 17]}]})", "/instances/0/tint/2"},
      {"{" + sp + R"(, "instances": [{"species": "oak", "position": [0, 0, 0], "yawDegrees": true}]})", "/instances/0/yawDegrees: expected a number"},
      {"{" + sp + R"(, "scatter": [{"species": "oak", "count": 100001, "radius": 1}]})", "/scatter/0/count: expected an integer in [1, 100000]"},
      {"{" + sp + R"(, "scatter": [{"species": "oak", "count": 60000, "radius": 1}, {"species": "oak", "count": 60000, "radius": 1}]})",
       "/scatter/1/count: 60000 more copies after 60000 pass the file's cap of 100000"},
      {"{" + sp + R"(, "scatter": [{"species": "oak", "count": 4, "radius": 0}]})", "/scatter/0/radius: expected a number in (0, 1e+06]"},
      {"{" + sp + R"(, "scatter": [{"species": "oak", "count": 4, "radius": 1, "scale": [2, 1]}]})", "/scatter/0/scale: expected [low, high]"},
      {"{" + sp + R"(, "scatter": [{"species": "oak", "radius": 1}]})", "/scatter/0/count: missing"},
      {"{" + sp + R"(, "scatter": [{"species": "oak", "count": 2, "radius": 1, "wind": 3}]})", "/scatter/0/wind: unknown key"},
      {"{" + sp + "}", "places nothing"},
      {"{" + sp + R"(, "instances": [{"species": "oak", "position": [0, 0, 0], "a/b~c": 1}]})", "/instances/0/a~1b~0c: unknown key"},
      {std::string(100, '[') + std::string(100, ']'), "nests deeper than 16 levels"},
  };
  for (const Case& c : cases) {
    CanopyScene s;
    const Status st = parse(c.text, &s);
    std::printf("  %s\n", st.ok() ? ("LOADED: " + c.text.substr(0, 60)).c_str() : st.message().c_str());
    EXPECT_FALSE(st.ok()) << c.text;
    EXPECT_EQ(st.message().rfind("'test.json': ", 0), 0u) << st.message();
    EXPECT_NE(st.message().find(c.mentions), std::string::npos) << "expected '" << c.mentions << "' in: " << st.message();
    EXPECT_TRUE(s.species.empty() && s.instances.empty());
  }
}

// A folder holding a scene and what its species name, removed at the end.
struct SceneFolder {
  std::string dir;
  SceneFolder() {
    char t[] = "/tmp/canopy-scene-XXXXXX";
    dir = mkdtemp(t);
  }
  ~SceneFolder() { std::system(("rm -rf '" + dir + "'").c_str()); }
  std::string write(const std::string& name, const std::string& text) const {
    std::ofstream(dir + "/" + name) << text;
    return dir + "/" + name;
  }
};

TEST(SceneFile, ASpeciesFileMustBeARegularFile) {
  SceneFolder f;
  f.write("plant.glb", "not read here");
  const std::string ok = f.write("ok.json", R"({"species": [{"name": "p", "gltf": "plant.glb"}],
      "instances": [{"species": "p", "position": [0, 0, 0]}]})");
  CanopyScene s;
  Status st = readCanopyScene(ok, &s);
  ASSERT_TRUE(st.ok()) << st.message();
  EXPECT_EQ(s.species[0].gltf, f.dir + "/plant.glb");
  mkdir((f.dir + "/adir").c_str(), 0700);
  mkfifo((f.dir + "/fifo.glb").c_str(), 0600);
  for (const char* target : {"missing.glb", "adir", "fifo.glb"}) {
    const std::string path = f.write("bad.json", std::string(R"({"species": [{"name": "p", "gltf": ")") + target +
                                                     R"("}], "instances": [{"species": "p", "position": [0, 0, 0]}]})");
    st = readCanopyScene(path, &s);  // a FIFO is refused at once, not waited on
    std::printf("  %s: %s\n", target, st.message().c_str());
    EXPECT_EQ(st.code(), Result::FileError);
    EXPECT_NE(st.message().find("/species/0/gltf"), std::string::npos) << st.message();
    EXPECT_NE(st.message().find(target), std::string::npos) << st.message();
  }
  st = readCanopyScene(f.dir + "/fifo.glb", &s);  // the scene itself a FIFO
  EXPECT_FALSE(st.ok());
}

// The inputs scripts/fuzz.sh scene kept (tests/fuzz/scenes): refused naming the file, or sound.
TEST(SceneFile, KeptFuzzInputsAreRefusedOrSound) {
  const std::string dir = std::string(CANOPY_SOURCE_DIR) + "/tests/fuzz/scenes/";
  int inputs = 0;
  for (const char* name : {"two-species.json"}) {
    std::ifstream in(dir + name, std::ios::binary);
    ASSERT_TRUE(in.good()) << dir + name;
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    CanopyScene s;
    const Status st = parse(text, &s);
    ++inputs;
    if (!st.ok()) {
      EXPECT_EQ(st.message().rfind("'test.json': ", 0), 0u) << st.message();
      continue;
    }
    for (const CanopySceneInstance& c : s.instances) {
      ASSERT_LT(c.species, s.species.size());
      const glm::mat4 m = matrixOf(c.placement);
      EXPECT_NE(glm::determinant(glm::mat3(m)), 0.0f) << name;
    }
  }
  EXPECT_GT(inputs, 0);
}

TEST(SceneFile, TheExampleScenesRead) {
  CanopyScene s;
  const std::string scenes = std::string(CANOPY_SOURCE_DIR) + "/demo/scenes/";
  Status st = readCanopyScene(scenes + "forest_clearing.json", &s);
  ASSERT_TRUE(st.ok()) << st.message();
  EXPECT_GE(s.species.size(), 4u);
  EXPECT_EQ(s.instances.size(), 69u);  // 5 explicit, 24 ferns and 40 grass patches scattered
  struct stat info;
  if (stat(CANOPY_SHARED_ASSETS, &info) != 0) GTEST_SKIP() << CANOPY_SHARED_ASSETS << " is absent: the six-species scene is not read";
  st = readCanopyScene(scenes + "six_species.json", &s);
  ASSERT_TRUE(st.ok()) << st.message();
  EXPECT_EQ(s.species.size(), 6u);
  for (const CanopySceneSpecies& sp : s.species) {
    Model* m = nullptr;
    st = loadModel(sp.gltf, GltfLoadOptions{}, &m);
    EXPECT_TRUE(st.ok()) << sp.name << ": " << st.message();
    EXPECT_GT(modelTriangleCount(m), 0u) << sp.name;
    destroyModel(m);
  }
}

}  // namespace
}  // namespace canopy
