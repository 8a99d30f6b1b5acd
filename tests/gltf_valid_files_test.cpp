// Valid glTF files the loader once refused (issue 68), one class at a time, each beside its
// neighbour that must still be refused: a refusal comes only from what the vegetation reads
// (render/gltf_prune.h), in Canopy's words, and KHR_mesh_quantization's types load. The files are
// made here (JSON + a buffer in memory); the glTF-Validator corpus itself is in gltf_loader_test.
#include <gtest/gtest.h>

#include <cstring>

#include <nlohmann/json.hpp>

#include "render/gltf_loader.h"
#include "tests/model_checks.h"

using namespace canopy;
using canopy::test::expectConsistent;
using canopy::test::toGlb;
using nlohmann::json;

namespace {

// One triangle: 3 float positions (36 bytes) then 3 uint16 indices (6 bytes, 2 of padding).
std::vector<unsigned char> triangleBytes() {
  std::vector<unsigned char> b(44, 0);
  const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  std::memcpy(&b[0], p, 36);
  const uint16_t idx[3] = {0, 1, 2};
  std::memcpy(&b[36], idx, 6);
  return b;
}

// A triangle mesh in one node (buffer 0 = tri.bin), to which each case adds its part.
json triangleModel() {
  return {{"asset", {{"version", "2.0"}}},
          {"scene", 0},
          {"scenes", json::array({{{"nodes", {0}}}})},
          {"nodes", json::array({{{"mesh", 0}}})},
          {"meshes", json::array({{{"primitives", json::array({{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}})}}})},
          {"buffers", json::array({{{"byteLength", 44}, {"uri", "tri.bin"}}})},
          {"bufferViews", json::array({{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
                                       {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 6}}})},
          {"accessors", json::array({{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"}},
                                     {{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "SCALAR"}}})}};
}

struct Outcome {
  Status status;
  VegetationModel model;
  std::string warnings() const {
    std::string w;
    for (const std::string& s : model.warnings) w += s + "\n";
    return w;
  }
};

Outcome load(const json& m, const std::map<std::string, std::vector<unsigned char>>& files = {{"tri.bin", triangleBytes()}}) {
  Outcome o;
  const std::string text = m.dump();
  o.status = loadGltfFromMemory("case.gltf", std::vector<unsigned char>(text.begin(), text.end()), files, {}, &o.model);
  return o;
}


void expectOneTriangle(const Outcome& o, const char* what) {
  ASSERT_TRUE(o.status.ok()) << what << ": " << o.status.message();
  EXPECT_EQ(o.model.triangleCount(), 1u) << what;
  expectConsistent(o.model, what);
}

}  // namespace

// A buffer nothing reads may have any uri, or none: missing in a .gltf, an empty one, a data: URI
// that does not decode, a remote one. The same uri on the buffer the mesh reads is refused, named.
TEST(GltfValidFiles, ABufferNothingReadsDoesNotRefuseTheFile) {
  struct Case {
    const char* name;
    json buffer;
    const char* refusal;  // when the mesh reads it
  };
  const Case cases[] = {
      {"no uri", {{"byteLength", 44}}, "buffers[0] has no 'uri'"},
      {"empty uri", {{"byteLength", 44}, {"uri", ""}}, "buffers[0]: 'uri' is empty"},
      {"not a data URI", {{"byteLength", 44}, {"uri", "data:no-comma"}}, "buffers[0]: the data: URI is not"},
      {"remote", {{"byteLength", 44}, {"uri", "https://example.com/tri.bin"}}, "is remote"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    json unused = triangleModel();
    unused["buffers"].push_back(c.buffer);
    unused["bufferViews"].push_back({{"buffer", 1}, {"byteLength", 4}});  // a view of it nothing reads
    expectOneTriangle(load(unused), c.name);
    json read = triangleModel();
    read["buffers"][0] = c.buffer;
    const Outcome o = load(read);
    EXPECT_FALSE(o.status.ok());
    EXPECT_NE(o.status.message().find(c.refusal), std::string::npos) << o.status.message();
    EXPECT_NE(o.status.message().find("case.gltf"), std::string::npos) << o.status.message();
    EXPECT_EQ(o.status.message().find("absolute path"), std::string::npos) << o.status.message();
  }
}

// RFC 2397 data URIs: base64 under any media type, and percent-encoded bytes, both read.
TEST(GltfValidFiles, DataUrisOfAnyMediaTypeAndPercentEncodedLoad) {
  const std::vector<unsigned char> bytes = triangleBytes();
  std::string percent;
  for (unsigned char b : bytes) {
    char x[4];
    std::snprintf(x, sizeof x, "%%%02X", b);
    percent += x;
  }
  for (const std::string& uri : {std::string("data:application/gltf-buffer,") + percent,
                                 std::string("data:,") + percent}) {
    json m = triangleModel();
    m["buffers"][0]["uri"] = uri;
    const Outcome o = load(m, {});
    expectOneTriangle(o, uri.substr(0, 32).c_str());
    if (o.status.ok()) EXPECT_EQ(o.model.positions[1], glm::vec3(1, 0, 0));
  }
}

// A .glb may carry placeholder buffers (no uri, not its BIN chunk) for data a host supplies; only
// the first buffer is the BIN chunk, and one the mesh reads must fit it.
TEST(GltfValidFiles, AGlbPlaceholderBufferNothingReadsLoads) {
  json m = triangleModel();
  m["buffers"][0].erase("uri");
  m["buffers"].push_back({{"byteLength", 1024}});
  Outcome o;
  o.status = loadGltfFromMemory("case.glb", toGlb(m.dump(), triangleBytes()), {}, {}, &o.model);
  expectOneTriangle(o, "placeholder");
  m["bufferViews"][0]["buffer"] = 1;
  o.status = loadGltfFromMemory("case.glb", toGlb(m.dump(), triangleBytes()), {}, {}, &o.model);
  EXPECT_NE(o.status.message().find("buffers[1] has no 'uri': only a .glb's first buffer is its BIN chunk"), std::string::npos)
      << o.status.message();
  m["bufferViews"][0]["buffer"] = 0;
  m["buffers"][0]["byteLength"] = 4096;
  o.status = loadGltfFromMemory("case.glb", toGlb(m.dump(), triangleBytes()), {}, {}, &o.model);
  EXPECT_NE(o.status.message().find("is more than the .glb's BIN chunk (44 bytes)"), std::string::npos) << o.status.message();
}

// An accessor of a type glTF does not define, that nothing reads; the same one read as POSITION.
TEST(GltfValidFiles, AnAccessorOfUnknownTypeNothingReadsLoads) {
  json m = triangleModel();
  m["accessors"].push_back({{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "NotaVEC3"}});
  expectOneTriangle(load(m), "unknown type");
  m["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 2;
  EXPECT_FALSE(load(m).status.ok());
}

// glTF: an accessor without a bufferView is zeros (plus its sparse part). As indices (count 3,
// sparse 1 -> 1, 2 -> 2) it gives the triangle 0, 1, 2.
TEST(GltfValidFiles, AnIndexAccessorWithoutABufferViewIsZerosAndItsSparsePart) {
  json m = triangleModel();
  std::vector<unsigned char> b = triangleBytes();
  const uint16_t sparseIdx[2] = {1, 2}, sparseVal[2] = {1, 2};
  b.resize(52);
  std::memcpy(&b[44], sparseIdx, 4);
  std::memcpy(&b[48], sparseVal, 4);
  m["buffers"][0]["byteLength"] = 52;
  m["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 44}, {"byteLength", 4}});
  m["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 4}});
  m["accessors"][1] = {{"componentType", 5123},
                       {"count", 3},
                       {"type", "SCALAR"},
                       {"sparse",
                        {{"count", 2},
                         {"indices", {{"bufferView", 2}, {"componentType", 5123}}},
                         {"values", {{"bufferView", 3}}}}}};
  const Outcome o = load(m, {{"tri.bin", b}});
  expectOneTriangle(o, "indices without a bufferView");
  if (o.status.ok()) EXPECT_EQ(o.model.indices, (std::vector<uint32_t>{0, 1, 2}));
  // Without the sparse part: zeros, one degenerate triangle, still loaded.
  m["accessors"][1].erase("sparse");
  expectOneTriangle(load(m, {{"tri.bin", b}}), "zeros");
}

// Points and lines beside triangles: left out with a warning naming them, the triangles loaded.
TEST(GltfValidFiles, PointsAndLinesArePrimitivesLeftOutNotTheFile) {
  for (int mode : {0, 1, 2, 3}) {
    SCOPED_TRACE(mode);
    json m = triangleModel();
    m["meshes"][0]["primitives"].push_back({{"attributes", {{"POSITION", 0}}}, {"mode", mode}});
    const Outcome o = load(m);
    expectOneTriangle(o, "with points or lines");
    EXPECT_NE(o.warnings().find("meshes[0].primitives[1]: mode " + std::to_string(mode)), std::string::npos) << o.warnings();
  }
}

// A texture without `source` (glTF: an extension may supply it) is not used; one naming an image
// that does not exist is refused.
TEST(GltfValidFiles, ATextureWithoutSourceIsNotUsed) {
  json m = triangleModel();
  m["meshes"][0]["primitives"][0]["material"] = 0;
  m["materials"] = json::array({{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}});
  m["textures"] = json::array({json::object()});
  const Outcome o = load(m);
  expectOneTriangle(o, "texture without source");
  EXPECT_NE(o.warnings().find("has no source image"), std::string::npos) << o.warnings();
  m["textures"][0]["source"] = 3;
  EXPECT_NE(load(m).status.message().find("images[3], which does not exist"), std::string::npos);
}

// KHR_mesh_quantization: positions as normalized shorts under a node scale, normals as normalized
// bytes, texture coordinates as normalized unsigned shorts; required by the file and read.
TEST(GltfValidFiles, KhrMeshQuantizationLoads) {
  std::vector<unsigned char> b(40, 0);
  const int16_t pos[12] = {0, 0, 0, 0, 32767, 0, 0, 0, 0, 32767, 0, 0};  // vec3 + padding to 8 bytes each
  std::memcpy(&b[0], pos, 24);
  const int8_t nrm[12] = {0, 0, 127, 0, 0, 0, 127, 0, 0, 0, 127, 0};  // vec3 + padding to 4 bytes each
  std::memcpy(&b[24], nrm, 12);
  b.resize(48);
  const uint16_t uv[6] = {0, 0, 65535, 0, 0, 65535};
  b.resize(60);
  std::memcpy(&b[48], uv, 12);
  json m = {{"asset", {{"version", "2.0"}}},
            {"extensionsUsed", {"KHR_mesh_quantization"}},
            {"extensionsRequired", {"KHR_mesh_quantization"}},
            {"scenes", json::array({{{"nodes", {0}}}})},
            {"nodes", json::array({{{"mesh", 0}, {"scale", {2.0, 2.0, 2.0}}}})},
            {"meshes", json::array({{{"primitives", json::array({{{"attributes", {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}}}}})}}})},
            {"buffers", json::array({{{"byteLength", 60}, {"uri", "q.bin"}}})},
            {"bufferViews", json::array({{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 24}, {"byteStride", 8}},
                                         {{"buffer", 0}, {"byteOffset", 24}, {"byteLength", 12}, {"byteStride", 4}},
                                         {{"buffer", 0}, {"byteOffset", 48}, {"byteLength", 12}}})},
            {"accessors", json::array({{{"bufferView", 0}, {"componentType", 5122}, {"normalized", true}, {"count", 3}, {"type", "VEC3"}},
                                       {{"bufferView", 1}, {"componentType", 5120}, {"normalized", true}, {"count", 3}, {"type", "VEC3"}},
                                       {{"bufferView", 2}, {"componentType", 5123}, {"normalized", true}, {"count", 3}, {"type", "VEC2"}}})}};
  const Outcome o = load(m, {{"q.bin", b}});
  expectOneTriangle(o, "quantized");
  if (!o.status.ok()) return;
  EXPECT_NEAR(o.model.positions[1].x, 2.0f, 1e-4f) << "32767 normalized is 1, times the node's scale 2";
  EXPECT_NEAR(o.model.positions[2].y, 2.0f, 1e-4f);
  EXPECT_NEAR(o.model.normals[0].z, 1.0f, 1e-4f);
  EXPECT_NEAR(o.model.uvs[1].x, 1.0f, 1e-4f);
  EXPECT_NEAR(o.model.uvs[2].y, 1.0f, 1e-4f);
}

// Refusals in Canopy's words: not the JSON parser's "[json.exception...]" tag, and a file with
// neither the GLB magic nor a JSON object named as not glTF.
TEST(GltfValidFiles, RefusalsAreInCanopysWords) {
  struct Case {
    const char* name;
    std::string bytes;
    const char* expect;
  };
  const Case cases[] = {
      {"case.gltf", "{\"asset\": {\"version\": \"2.0\"}, ]", "the JSON is not well-formed"},
      {"case.gltf", "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [{\"translation\": [1e400, 0, 0]}]}", "the JSON is not well-formed"},
      {"case.glb", std::string("gLTF\x02\0\0\0", 8) + std::string(40, ' '), "not a glTF file"},
      {"case.gltf", "[]", "the JSON document is not an object"},
  };
  for (const Case& c : cases) {
    VegetationModel m;
    const Status s = loadGltfFromMemory(c.name, std::vector<unsigned char>(c.bytes.begin(), c.bytes.end()), {}, {}, &m);
    EXPECT_FALSE(s.ok()) << c.bytes;
    EXPECT_NE(s.message().find(c.expect), std::string::npos) << s.message();
    EXPECT_EQ(s.message().find("json.exception"), std::string::npos) << s.message();
  }
}

// An image nothing reads (no material of a drawn primitive names a texture of it) may be missing,
// remote or an undecodable data URI; the same image on the drawn material is refused by name.
TEST(GltfValidFiles, AnImageNothingReadsDoesNotRefuseTheFile) {
  for (const char* uri : {"missing.png", "https://example.com/leaf.png", "data:image/png;base64,@@@"}) {
    SCOPED_TRACE(uri);
    json m = triangleModel();
    m["images"] = json::array({{{"uri", uri}}});
    m["textures"] = json::array({{{"source", 0}}});
    m["materials"] = json::array({{{"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}});
    expectOneTriangle(load(m), "unused image");
    m["meshes"][0]["primitives"][0]["material"] = 0;
    const Outcome o = load(m);
    EXPECT_FALSE(o.status.ok()) << "a drawn texture's image that cannot be read";
    EXPECT_NE(o.status.message().find("case.gltf"), std::string::npos) << o.status.message();
  }
}
