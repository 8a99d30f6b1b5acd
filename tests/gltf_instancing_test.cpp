// EXT_mesh_gpu_instancing and extensionsRequired in the glTF loader (issue 53; render/gltf_loader.cpp
// readInstancing): a node's mesh drawn once per instance at the node's transform times the
// instance's TRANSLATION x ROTATION x SCALE, the same model as N explicit nodes with those
// transforms; malformed instancing accessors refused by name; a file that requires an extension
// the loader lacks refused naming it. Files are written here by hand, not by Canopy's writer.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <glm/glm.hpp>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "render/gltf_loader.h"
#include "tests/model_checks.h"

namespace canopy {
namespace {
using nlohmann::json;

constexpr int kInstances = 3;
const float kTranslation[kInstances][3] = {{0, 0, 0}, {2, 0, 0}, {0, 0, -3}};
// x, y, z, w: none, 90 degrees about +Y, 180 degrees about +Z.
const float kRotation[kInstances][4] = {{0, 0, 0, 1}, {0, 0.70710678f, 0, 0.70710678f}, {0, 0, 1, 0}};
const float kScale[kInstances][3] = {{1, 1, 1}, {2, 2, 2}, {1, 0.5f, 1}};

// The buffer: a triangle's positions, its uint16 indices (padded), then the three instancing arrays.
std::vector<unsigned char> bufferBytes() {
  std::vector<unsigned char> b(164, 0);
  const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(&b[0], p, 36);
  const uint16_t idx[3] = {0, 1, 2};
  std::memcpy(&b[36], idx, 6);
  std::memcpy(&b[44], kTranslation, 36);
  std::memcpy(&b[80], kRotation, 48);
  std::memcpy(&b[128], kScale, 36);
  return b;
}

json accessor(int view, int count, const char* type) {
  return {{"bufferView", view}, {"componentType", 5126}, {"count", count}, {"type", type}};
}

json baseFile() {
  return {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", json::array({{{"nodes", {0}}}})},
      {"meshes", json::array({{{"primitives", json::array({{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}})}}})},
      {"buffers", json::array({{{"byteLength", 164}, {"uri", "inst.bin"}}})},
      {"bufferViews", json::array({{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
                                   {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 6}},
                                   {{"buffer", 0}, {"byteOffset", 44}, {"byteLength", 36}},
                                   {{"buffer", 0}, {"byteOffset", 80}, {"byteLength", 48}},
                                   {{"buffer", 0}, {"byteOffset", 128}, {"byteLength", 36}}})},
      {"accessors", json::array({accessor(0, 3, "VEC3"),
                                 {{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "SCALAR"}},
                                 accessor(2, kInstances, "VEC3"), accessor(3, kInstances, "VEC4"), accessor(4, kInstances, "VEC3")})},
  };
}

// The node at `offset` (a translation of the whole set) instancing the mesh three times.
json instancedFile(const glm::vec3& offset = glm::vec3(0.0f)) {
  json f = baseFile();
  f["extensionsUsed"] = {"EXT_mesh_gpu_instancing"};
  f["nodes"] = json::array({{{"mesh", 0},
                             {"translation", {offset.x, offset.y, offset.z}},
                             {"extensions", {{"EXT_mesh_gpu_instancing", {{"attributes", {{"TRANSLATION", 2}, {"ROTATION", 3}, {"SCALE", 4}}}}}}}}});
  return f;
}

// The same as explicit nodes: a parent at `offset`, one child per instance with its TRS.
json explicitFile(const glm::vec3& offset = glm::vec3(0.0f)) {
  json f = baseFile();
  json nodes = json::array({{{"translation", {offset.x, offset.y, offset.z}}, {"children", {1, 2, 3}}}});
  for (int i = 0; i < kInstances; ++i)
    nodes.push_back({{"mesh", 0},
                     {"translation", {kTranslation[i][0], kTranslation[i][1], kTranslation[i][2]}},
                     {"rotation", {kRotation[i][0], kRotation[i][1], kRotation[i][2], kRotation[i][3]}},
                     {"scale", {kScale[i][0], kScale[i][1], kScale[i][2]}}});
  f["nodes"] = nodes;
  return f;
}

Status load(const json& f, VegetationModel* out, std::vector<unsigned char> bin = bufferBytes()) {
  const std::string text = f.dump();
  return loadGltfFromMemory("instanced.gltf", std::vector<unsigned char>(text.begin(), text.end()), {{"inst.bin", bin}}, {}, out);
}

TEST(GltfInstancing, InstancesLoadAsTheExplicitNodesWould) {
  const glm::vec3 offset(5.0f, 1.0f, 0.0f);
  VegetationModel inst, expl;
  ASSERT_TRUE(load(instancedFile(offset), &inst).ok());
  ASSERT_TRUE(load(explicitFile(offset), &expl).ok());
  test::expectConsistent(inst, "instanced");
  ASSERT_EQ(inst.triangleCount(), size_t(kInstances));
  ASSERT_EQ(inst.positions.size(), expl.positions.size());
  for (size_t v = 0; v < inst.positions.size(); ++v)
    EXPECT_LT(glm::length(inst.positions[v] - expl.positions[v]), 1e-5f) << "vertex " << v;
  // Instance 1: node offset + (2, 0, 0) + 2 x R_y(90) of (1, 0, 0) = offset + (2, 0, -2).
  EXPECT_LT(glm::length(inst.positions[4] - (offset + glm::vec3(2.0f, 0.0f, -2.0f))), 1e-5f);
  // Each instance a plant of its own (per-plant roots).
  EXPECT_NE(inst.trianglePlant[0], inst.trianglePlant[1]);
  EXPECT_NE(inst.trianglePlant[1], inst.trianglePlant[2]);
  // Required, and implemented: loads the same.
  json req = instancedFile(offset);
  req["extensionsRequired"] = {"EXT_mesh_gpu_instancing"};
  VegetationModel r;
  EXPECT_TRUE(load(req, &r).ok());
  EXPECT_EQ(r.triangleCount(), size_t(kInstances));
}

TEST(GltfInstancing, AbsentAttributesAreTheIdentity) {
  json f = instancedFile();
  f["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = {{"TRANSLATION", 2}};
  VegetationModel m;
  ASSERT_TRUE(load(f, &m).ok());
  ASSERT_EQ(m.triangleCount(), size_t(kInstances));
  EXPECT_LT(glm::length(m.positions[3 * 2 + 1] - glm::vec3(1.0f, 0.0f, -3.0f)), 1e-6f);  // (1,0,0) moved by (0,0,-3)
}

TEST(GltfInstancing, MalformedInstancingIsRefusedByName) {
  struct Case {
    const char* what;
    std::string pointer;
    json value;
    const char* mentions;
  };
  const std::string attrs = "/nodes/0/extensions/EXT_mesh_gpu_instancing/attributes";
  const Case cases[] = {
      {"accessor that does not exist", attrs + "/SCALE", json(99), "accessors[99] does not exist"},
      {"negative accessor index", attrs + "/SCALE", json(-1), "EXT_mesh_gpu_instancing.attributes.SCALE = -1"},
      {"huge accessor index", attrs + "/TRANSLATION", json(uint64_t(1) << 40), "EXT_mesh_gpu_instancing.attributes.TRANSLATION"},
      {"accessor index not a number", attrs + "/ROTATION", json("three"), "EXT_mesh_gpu_instancing.attributes.ROTATION"},
      {"rotation of the wrong type", attrs + "/ROTATION", json(2), "ROTATION: accessors[2]: type"},
      {"counts that disagree", "/accessors/4/count", json(2), "2 values where the other attributes have 3"},
      {"count past its bufferView", "/accessors/2/count", json(4), "do not fit bufferViews[2]"},
      {"attributes not an object", attrs, json::array({1, 2}), "'attributes' must be an object"},
      {"no attribute it knows", attrs, json::object({{"_ID", 2}}), "none of TRANSLATION, ROTATION, SCALE"},
  };
  for (const Case& c : cases) {
    json f = instancedFile();
    f[json::json_pointer(c.pointer)] = c.value;
    VegetationModel m;
    const Status s = load(f, &m);
    std::printf("  %s: %s\n", c.what, s.ok() ? "LOADED" : s.message().c_str());
    EXPECT_FALSE(s.ok()) << c.what;
    EXPECT_NE(s.message().find("instanced.gltf"), std::string::npos) << s.message();
    EXPECT_NE(s.message().find(c.mentions), std::string::npos) << c.what << ": " << s.message();
    EXPECT_EQ(m.triangleCount(), 0u);
  }
  // Values in the buffer: a NaN translation, a zero quaternion.
  std::vector<unsigned char> bin = bufferBytes();
  const float nan = std::nanf("");
  std::memcpy(&bin[44 + 12], &nan, 4);
  VegetationModel m;
  Status s = load(instancedFile(), &m, bin);
  EXPECT_NE(s.message().find("TRANSLATION: accessors[2]: contains NaN or infinity"), std::string::npos) << s.message();
  bin = bufferBytes();
  std::memset(&bin[80 + 16], 0, 16);
  s = load(instancedFile(), &m, bin);
  EXPECT_NE(s.message().find("ROTATION[1]: not a unit quaternion"), std::string::npos) << s.message();
}

TEST(GltfInstancing, InstancesCountAgainstTheTriangleBudget) {
  GltfLoadOptions opt;
  opt.maxTriangles = 2;  // three instances of one triangle
  const std::string text = instancedFile().dump();
  VegetationModel m;
  const Status s =
      loadGltfFromMemory("instanced.gltf", std::vector<unsigned char>(text.begin(), text.end()), {{"inst.bin", bufferBytes()}}, opt, &m);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("maxTriangles"), std::string::npos) << s.message();
}

TEST(GltfExtensions, AnUnimplementedRequiredExtensionIsRefusedNamingIt) {
  json f = explicitFile();
  f["extensionsUsed"] = {"KHR_materials_variants"};
  f["extensionsRequired"] = {"KHR_materials_variants"};
  VegetationModel m;
  const Status s = load(f, &m);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("extensionsRequired names 'KHR_materials_variants'"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("instanced.gltf"), std::string::npos) << s.message();
  // Used but not required: the file is readable without it (glTF 2.0), so it loads.
  f.erase("extensionsRequired");
  EXPECT_TRUE(load(f, &m).ok());
}

}  // namespace
}  // namespace canopy
