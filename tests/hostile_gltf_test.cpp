// Hostile glTF input, one defect class at a time and its neighbours (issue "Reliability"): every
// offset and count field of accessors, sparse accessors, bufferViews, buffers and images, and the
// GLB framing, set to -1, 0, 2^31-1, 2^32-1, 2^63, 2^64-4 and 2^64-1, as .gltf with an external
// buffer and as .glb; JSON nested past the limit; a FIFO (and a link to one) as the model; a
// million-node chain; the instancing and image budgets. Built with ASan + UBSan in the test
// configuration: a crash, an out-of-bounds read or an exception fails the run; a refusal must name
// the file, and a load must give a consistent model.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <future>
#include <thread>

#include <nlohmann/json.hpp>

#include "render/gltf_loader.h"
#include "tests/model_checks.h"

using namespace canopy;
using canopy::test::expectConsistent;
using canopy::test::toGlb;
using nlohmann::json;

namespace {

// The buffer: positions (3 x vec3), uint16 indices, one sparse index, one sparse vec3 value and a
// 2x2 PPM image, each in its own bufferView.
std::vector<unsigned char> bufferBytes() {
  std::vector<unsigned char> b(84, 0);
  const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(&b[0], p, 36);
  const uint16_t idx[3] = {0, 1, 2};
  std::memcpy(&b[36], idx, 6);
  const uint16_t sparseIndex = 1;
  std::memcpy(&b[44], &sparseIndex, 2);
  const float sparseValue[3] = {0, 0, 1};
  std::memcpy(&b[48], sparseValue, 12);
  const char ppm[] = "P6\n2 2\n255\n";
  std::memcpy(&b[60], ppm, 11);
  for (int i = 0; i < 12; ++i) b[71 + size_t(i)] = uint8_t(40 * i);
  return b;
}

json baseModel(bool glb) {
  json buffer = {{"byteLength", 84}};
  if (!glb) buffer["uri"] = "tri.bin";
  json m = {
      {"asset", {{"version", "2.0"}}},
      {"scene", 0},
      {"scenes", json::array({{{"nodes", {0}}}})},
      {"nodes", json::array({{{"mesh", 0}}})},
      {"meshes", json::array({{{"primitives", json::array({{{"attributes", {{"POSITION", 0}, {"NORMAL", 2}}},
                                                            {"indices", 1},
                                                            {"material", 0}}})}}})},
      {"materials", json::array({{{"name", "leaf"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}})},
      {"textures", json::array({{{"source", 0}}})},
      {"images", json::array({{{"bufferView", 4}, {"mimeType", "image/png"}}})},
      {"buffers", json::array({buffer})},
      {"bufferViews", json::array({{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}, {"byteStride", 12}},
                                   {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 6}},
                                   {{"buffer", 0}, {"byteOffset", 44}, {"byteLength", 2}},
                                   {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 12}},
                                   {{"buffer", 0}, {"byteOffset", 60}, {"byteLength", 23}}})},
      {"accessors",
       json::array({{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
                    {{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "SCALAR"}},
                    {{"bufferView", 0},
                     {"componentType", 5126},
                     {"count", 3},
                     {"type", "VEC3"},
                     {"sparse",
                      {{"count", 1},
                       {"indices", {{"bufferView", 2}, {"componentType", 5123}, {"byteOffset", 0}}},
                       {"values", {{"bufferView", 3}, {"byteOffset", 0}}}}}}})},
  };
  return m;
}


struct Outcome {
  Status status;
  VegetationModel model;
};

Outcome load(const json& m, bool glb, const GltfLoadOptions& opt = {}) {
  Outcome o;
  const std::string text = m.dump();
  if (glb) {
    o.status = loadGltfFromMemory("case.glb", toGlb(text, bufferBytes()), {}, opt, &o.model);
  } else {
    o.status = loadGltfFromMemory("case.gltf", std::vector<unsigned char>(text.begin(), text.end()), {{"tri.bin", bufferBytes()}},
                                  opt, &o.model);
  }
  return o;
}


}  // namespace

TEST(HostileGltf, TheBaseModelLoadsInBothContainers) {
  for (bool glb : {false, true}) {
    Outcome o = load(baseModel(glb), glb);
    ASSERT_TRUE(o.status.ok()) << o.status.message();
    EXPECT_EQ(o.model.triangleCount(), 1u);
    ASSERT_EQ(o.model.images.size(), 1u);
    EXPECT_EQ(o.model.images[0].width, 2u);
    // The sparse substitution reached the normals: vertex 1's normal is (0, 0, 1).
    EXPECT_NEAR(o.model.normals[1].z, 1.0f, 1e-6f);
    expectConsistent(o.model, "base");
  }
}

// Every offset, count, length and index field at the edges of its integer types. A value that no
// byte of the file can back (2^31-1 and above) must be refused naming the file; -1 and 0 may load
// (glTF gives some of them a meaning, e.g. no indices) but then give a consistent model.
TEST(HostileGltf, EveryOffsetAndCountFieldAtItsEdgesIsRefusedOrLoadsSoundly) {
  const char* fields[] = {
      "/accessors/0/count", "/accessors/0/byteOffset", "/accessors/0/bufferView", "/accessors/1/count",
      "/accessors/1/byteOffset", "/accessors/1/bufferView", "/accessors/2/count", "/accessors/2/byteOffset",
      "/accessors/2/sparse/count", "/accessors/2/sparse/indices/byteOffset", "/accessors/2/sparse/indices/bufferView",
      "/accessors/2/sparse/values/byteOffset", "/accessors/2/sparse/values/bufferView", "/bufferViews/0/byteOffset",
      "/bufferViews/0/byteLength", "/bufferViews/0/byteStride", "/bufferViews/0/buffer", "/bufferViews/1/byteOffset",
      "/bufferViews/1/byteLength", "/bufferViews/2/byteOffset", "/bufferViews/2/byteLength", "/bufferViews/3/byteOffset",
      "/bufferViews/3/byteLength", "/bufferViews/4/byteOffset", "/bufferViews/4/byteLength", "/buffers/0/byteLength",
      "/images/0/bufferView", "/textures/0/source", "/materials/0/pbrMetallicRoughness/baseColorTexture/index",
      "/meshes/0/primitives/0/indices", "/meshes/0/primitives/0/material", "/meshes/0/primitives/0/attributes/POSITION",
      "/nodes/0/mesh", "/scenes/0/nodes/0", "/scene"};
  const json values[] = {json(-1),
                         json(0),
                         json(2147483647),
                         json(uint64_t(4294967295u)),
                         json(uint64_t(1) << 63),
                         json(uint64_t(18446744073709551612u)),
                         json(uint64_t(18446744073709551615u))};
  int tried = 0, refused = 0, loaded = 0;
  for (bool glb : {false, true})
    for (const char* f : fields)
      for (const json& v : values) {
        json m = baseModel(glb);
        m[json::json_pointer(f)] = v;
        const std::string name = std::string(glb ? "glb " : "gltf ") + f + " = " + v.dump();
        Outcome o = load(m, glb);
        ++tried;
        if (!o.status.ok()) {
          ++refused;
          EXPECT_NE(o.status.message().find(glb ? "case.glb" : "case.gltf"), std::string::npos) << name << ": " << o.status.message();
          EXPECT_EQ(o.model.triangleCount(), 0u) << name;
          continue;
        }
        ++loaded;
        const bool huge = v.is_number_unsigned() && v.get<uint64_t>() >= 2147483647u;
        EXPECT_FALSE(huge) << name << " loaded";
        expectConsistent(o.model, name);
      }
  std::printf("  %d hostile variants: %d refused, %d loaded (consistent)\n", tried, refused, loaded);
}

// The cases, each at its root: a count no view can back, negative sparse offsets, an
// offset near 2^64.
TEST(HostileGltf, TheReportedDefectsAreRefusedNamingTheField) {
  struct Case {
    const char* pointer;
    json value;
    const char* mentions;
  };
  const Case cases[] = {
      {"/accessors/0/count", json(2147483647), "accessors[0]"},
      {"/accessors/2/sparse/indices/byteOffset", json(-4), "accessors[2].sparse.indices.byteOffset = -4"},
      {"/accessors/2/sparse/values/byteOffset", json(-12), "accessors[2].sparse.values.byteOffset = -12"},
      {"/accessors/0/byteOffset", json(uint64_t(18446744073709551612u)), "accessors[0]"},
      {"/accessors/0/byteOffset", json(uint64_t(18446744073709551615u) - (1u << 20) + 1), "accessors[0]"},
  };
  for (bool glb : {false, true})
    for (const Case& c : cases) {
      json m = baseModel(glb);
      m[json::json_pointer(c.pointer)] = c.value;
      Outcome o = load(m, glb);
      std::printf("  %s %s = %s: %s\n", glb ? "glb " : "gltf", c.pointer, c.value.dump().c_str(),
                  o.status.ok() ? "LOADED" : o.status.message().c_str());
      EXPECT_FALSE(o.status.ok()) << c.pointer;
      EXPECT_NE(o.status.message().find(c.mentions), std::string::npos) << o.status.message();
    }
  // An accessor with no bufferView (zeros + sparse) cannot allocate past the vertex budget.
  json m = baseModel(false);
  m["accessors"][2].erase("bufferView");
  m["accessors"][2]["count"] = 2147483647;
  Outcome o = load(m, false);
  EXPECT_FALSE(o.status.ok());
  EXPECT_NE(o.status.message().find("maxVertices"), std::string::npos) << o.status.message();
}

TEST(HostileGltf, GlbFramingFieldsAtTheirEdgesAreRefused) {
  const std::string text = baseModel(true).dump();
  const std::vector<unsigned char> good = toGlb(text, bufferBytes());
  uint32_t jsonLen;
  std::memcpy(&jsonLen, &good[12], 4);
  const size_t fields[] = {4, 8, 12, 16, 20 + size_t(jsonLen), 24 + size_t(jsonLen)};  // version, length, chunk lengths, types
  const uint32_t values[] = {0u, 3u, 0x7fffffffu, 0xffffffffu, 0xfffffffcu};
  int refused = 0, tried = 0;
  for (size_t f : fields)
    for (uint32_t v : values) {
      std::vector<unsigned char> b = good;
      std::memcpy(&b[f], &v, 4);
      VegetationModel model;
      Status s = loadGltfFromMemory("case.glb", b, {}, {}, &model);
      ++tried;
      if (s.ok()) {
        expectConsistent(model, "glb field " + std::to_string(f));
      } else {
        ++refused;
        EXPECT_NE(s.message().find("case.glb"), std::string::npos) << s.message();
      }
      if (v >= 0x7fffffffu) EXPECT_FALSE(s.ok()) << "GLB field at byte " << f << " = " << v;
    }
  std::printf("  %d GLB framing variants, %d refused\n", tried, refused);
}

// tinygltf converts extras recursively: the depth limit stops such a file before it does.
TEST(HostileGltf, DeeplyNestedJsonIsRefusedBeforeParsing) {
  for (int depth : {15000, 65}) {
    std::string extras(size_t(depth), '[');
    extras += std::string(size_t(depth), ']');
    std::string text = baseModel(false).dump();
    text.insert(text.find("\"version\""), "\"extras\":" + extras + ",");
    VegetationModel m;
    Status s = loadGltfFromMemory("deep.gltf", std::vector<unsigned char>(text.begin(), text.end()), {{"tri.bin", bufferBytes()}}, {},
                                  &m);
    EXPECT_FALSE(s.ok()) << depth;
    EXPECT_NE(s.message().find("maxJsonDepth"), std::string::npos) << s.message();
  }
  // Nesting inside strings is not nesting; a reasonable depth loads.
  std::string text = baseModel(false).dump();
  text.insert(text.find("\"version\""), "\"extras\":{\"s\":\"" + std::string(200, '[') + "\\\"[[[\",\"a\":[[[[[[[[[[1]]]]]]]]]]},");
  VegetationModel m;
  Status s = loadGltfFromMemory("ok.gltf", std::vector<unsigned char>(text.begin(), text.end()), {{"tri.bin", bufferBytes()}}, {}, &m);
  EXPECT_TRUE(s.ok()) << s.message();
}

// A chain of nodes 200,000 deep is a valid tree: loaded without recursion (and the loop check is
// linear). A loop far down the chain is still found.
TEST(HostileGltf, AVeryDeepNodeChainLoadsAndALoopInItIsFound) {
  const int n = 200000;
  for (bool loop : {false, true}) {
    json m = baseModel(false);
    json nodes = json::array();
    for (int i = 0; i < n; ++i) {
      json node = json::object();
      if (i + 1 < n) node["children"] = {i + 1};
      else if (loop) node["children"] = {n / 2};
      else node["mesh"] = 0;
      nodes.push_back(node);
    }
    m["nodes"] = nodes;
    const auto t0 = std::chrono::steady_clock::now();
    Outcome o = load(m, false);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    std::printf("  %d-node chain%s: %s in %.2f s\n", n, loop ? " with a loop" : "", o.status.ok() ? "loaded" : o.status.message().c_str(), s);
    EXPECT_EQ(o.status.ok(), !loop) << o.status.message();
    if (!loop) EXPECT_EQ(o.model.triangleCount(), 1u);
  }
}

// A mesh instanced by many nodes counts every instance against the budgets; images against the
// pixel budget.
TEST(HostileGltf, InstancingAndImagesAreBoundedByTheBudgets) {
  json m = baseModel(false);
  json roots = json::array();
  json nodes = json::array();
  for (int i = 0; i < 50; ++i) {
    nodes.push_back({{"mesh", 0}});
    roots.push_back(i);
  }
  m["nodes"] = nodes;
  m["scenes"][0]["nodes"] = roots;
  GltfLoadOptions opt;
  Outcome all = load(m, false, opt);
  ASSERT_TRUE(all.status.ok()) << all.status.message();
  EXPECT_EQ(all.model.triangleCount(), 50u);
  opt.maxVertices = 100;
  Outcome o = load(m, false, opt);
  EXPECT_FALSE(o.status.ok());
  EXPECT_NE(o.status.message().find("maxVertices"), std::string::npos) << o.status.message();
  opt = {};
  opt.maxTriangles = 20;
  o = load(m, false, opt);
  EXPECT_NE(o.status.message().find("maxTriangles"), std::string::npos) << o.status.message();
  opt = {};
  opt.maxImagePixels = 3;  // the image has 4
  o = load(baseModel(false), false, opt);
  EXPECT_NE(o.status.message().find("maxImagePixels"), std::string::npos) << o.status.message();
}

// Nothing but a regular file is ever read: a FIFO (or a link to one) as the model, or as its
// buffer, is refused at once instead of blocking in open().
TEST(HostileGltf, AFifoIsRefusedWithoutBlocking) {
  char tmpl[] = "/tmp/canopy-fifo-XXXXXX";
  const std::string dir = mkdtemp(tmpl);
  ASSERT_EQ(mkfifo((dir + "/model.gltf").c_str(), 0600), 0);
  ASSERT_EQ(symlink((dir + "/model.gltf").c_str(), (dir + "/link.gltf").c_str()), 0);
  ASSERT_EQ(mkfifo((dir + "/tri.bin").c_str(), 0600), 0);
  {
    const std::string text = baseModel(false).dump();
    FILE* f = std::fopen((dir + "/buffer-fifo.gltf").c_str(), "wb");
    ASSERT_NE(f, nullptr);
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
  }
  for (const char* name : {"model.gltf", "link.gltf", "buffer-fifo.gltf"}) {
    auto result = std::make_shared<std::promise<std::string>>();
    std::future<std::string> done = result->get_future();
    const std::string path = dir + "/" + name;
    std::thread([result, path] {
      VegetationModel m;
      Status s = loadGltf(path, {}, &m);
      result->set_value(s.ok() ? "LOADED" : s.message());
    }).detach();
    if (done.wait_for(std::chrono::seconds(20)) != std::future_status::ready) {
      ADD_FAILURE() << name << ": loadGltf blocked";
      std::_Exit(1);  // the blocked thread cannot be joined
    }
    const std::string msg = done.get();
    std::printf("  %s: %s\n", name, msg.c_str());
    EXPECT_NE(msg.find("not a regular file"), std::string::npos) << msg;
  }
  std::system(("rm -rf '" + dir + "'").c_str());
}
