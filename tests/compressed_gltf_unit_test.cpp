// Compressed glTF against hostile data (issue 78; render/gltf_compressed.h): the files of
// tests/data/compressed/ (scripts/make_compressed_gltf.sh) load, and each with its compressed
// bytes, counts or parameters broken is refused naming the element; KHR_texture_basisu is refused
// by name. CPU only: the drawn comparison with the originals is CompressedGltfTest (GPU).
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>

#include <nlohmann/json.hpp>

#include "render/gltf_loader.h"
#include "tests/model_checks.h"

using namespace canopy;
using nlohmann::json;

namespace {

const std::string kDir = std::string(CANOPY_SOURCE_DIR) + "/tests/data/compressed/";

std::vector<unsigned char> readAll(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return std::vector<unsigned char>(std::istreambuf_iterator<char>(f), {});
}

// A GLB as its JSON and its BIN chunk, and back.
struct Glb {
  json doc;
  std::vector<unsigned char> bin;
};
Glb split(const std::vector<unsigned char>& b) {
  Glb g;
  uint32_t jsonLen = 0, binLen = 0;
  std::memcpy(&jsonLen, b.data() + 12, 4);
  g.doc = json::parse(b.begin() + 20, b.begin() + 20 + jsonLen);
  const size_t at = 20 + jsonLen;
  std::memcpy(&binLen, b.data() + at, 4);
  g.bin.assign(b.begin() + long(at + 8), b.begin() + long(at + 8 + binLen));
  return g;
}
std::vector<unsigned char> join(const Glb& g) { return canopy::test::toGlb(g.doc.dump(), g.bin); }

Status loadGlb(const Glb& g, VegetationModel* m) { return loadGltfFromMemory("case.glb", join(g), {}, {}, m); }

// The first bufferView with EXT_meshopt_compression.
json& firstMeshoptView(json& doc) {
  for (json& v : doc["bufferViews"])
    if (v.contains("extensions") && v["extensions"].contains("EXT_meshopt_compression")) return v;
  throw std::runtime_error("no meshopt view");
}

TEST(CompressedGltf, TheToolsFilesLoad) {
  for (const char* name : {"kaykit_draco.glb", "kaykit_meshopt.glb", "kaykit_quantized.glb", "kaykit_webp.glb"}) {
    VegetationModel m;
    const Status s = loadGltf(kDir + name, {}, &m);
    ASSERT_TRUE(s.ok()) << name << ": " << s.message();
    EXPECT_EQ(m.triangleCount(), 1364u) << name;
    EXPECT_EQ(m.images.size(), 1u) << name;
    canopy::test::expectConsistent(m, name);
  }
}

TEST(CompressedGltf, BrokenMeshoptDataIsRefusedByName) {
  const Glb good = split(readAll(kDir + "kaykit_meshopt.glb"));
  VegetationModel m;
  {  // the codec's header byte
    Glb g = good;
    const json& mo = firstMeshoptView(g.doc)["extensions"]["EXT_meshopt_compression"];
    g.bin[mo.value("byteOffset", size_t(0))] ^= 0xff;
    const Status s = loadGlb(g, &m);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("EXT_meshopt_compression: the compressed data does not decode"), std::string::npos) << s.message();
  }
  {  // truncated
    Glb g = good;
    firstMeshoptView(g.doc)["extensions"]["EXT_meshopt_compression"]["byteLength"] = 3;
    const Status s = loadGlb(g, &m);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("EXT_meshopt_compression"), std::string::npos) << s.message();
  }
  {  // a count no compressed data can hold (no allocation of it)
    Glb g = good;
    firstMeshoptView(g.doc)["extensions"]["EXT_meshopt_compression"]["count"] = 100000000;
    const Status s = loadGlb(g, &m);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("cannot come from"), std::string::npos) << s.message();
  }
  for (const auto& [key, value, named] : {std::tuple<const char*, json, const char*>{"byteStride", 6, ".byteStride = 6"},
                                         {"mode", "POINTS", ".mode must be"},
                                         {"filter", "WAVELET", ".filter must be"},
                                         {"buffer", 9, ".buffer = 9 does not exist"}}) {
    Glb g = good;
    firstMeshoptView(g.doc)["extensions"]["EXT_meshopt_compression"][key] = value;
    const Status s = loadGlb(g, &m);
    EXPECT_FALSE(s.ok()) << key;
    EXPECT_NE(s.message().find(named), std::string::npos) << s.message();
  }
}

TEST(CompressedGltf, BrokenDracoDataIsRefusedByName) {
  const Glb good = split(readAll(kDir + "kaykit_draco.glb"));
  VegetationModel m;
  const json& prim = good.doc["meshes"][0]["primitives"][0];
  const size_t view = prim["extensions"]["KHR_draco_mesh_compression"]["bufferView"].get<size_t>();
  {  // truncated
    Glb g = good;
    g.doc["bufferViews"][view]["byteLength"] = 20;
    const Status s = loadGlb(g, &m);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("KHR_draco_mesh_compression"), std::string::npos) << s.message();
  }
  {  // not Draco at all
    Glb g = good;
    const size_t at = g.doc["bufferViews"][view].value("byteOffset", size_t(0));
    std::memset(g.bin.data() + at, 0x5a, 16);
    const Status s = loadGlb(g, &m);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("is not a Draco triangle mesh"), std::string::npos) << s.message();
  }
  {  // an accessor whose count is not the decoded one
    Glb g = good;
    g.doc["accessors"][prim["attributes"]["POSITION"].get<size_t>()]["count"] = 7;
    const Status s = loadGlb(g, &m);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("(POSITION) counts 7"), std::string::npos) << s.message();
  }
  {  // an attribute id the data does not have
    Glb g = good;
    g.doc["meshes"][0]["primitives"][0]["extensions"]["KHR_draco_mesh_compression"]["attributes"]["POSITION"] = 77;
    const Status s = loadGlb(g, &m);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("attributes.POSITION = 77 is not in the Draco data"), std::string::npos) << s.message();
  }
}

TEST(CompressedGltf, BrokenWebpAndTextureTransformAreRefusedByName) {
  VegetationModel m;
  {
    Glb g = split(readAll(kDir + "kaykit_webp.glb"));
    const size_t view = g.doc["images"][0]["bufferView"].get<size_t>();
    const size_t at = g.doc["bufferViews"][view].value("byteOffset", size_t(0));
    std::memset(g.bin.data() + at + 12, 0, 64);  // RIFF....WEBP kept, the chunks zeroed
    const Status s = loadGlb(g, &m);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.message().find("images[0]"), std::string::npos) << s.message();
    EXPECT_NE(s.message().find("WebP"), std::string::npos) << s.message();
  }
  for (const auto& [key, value, named] : {std::tuple<const char*, json, const char*>{"rotation", "a quarter", ".rotation must be"},
                                         {"scale", json::array({1, 2, 3}), ".scale must be 2 numbers"},
                                         {"offset", json::array({1e300, 0}), ".offset must be finite"},
                                         {"texCoord", -1, ".texCoord must be"}}) {
    Glb g = split(readAll(kDir + "kaykit_quantized.glb"));
    g.doc["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]["KHR_texture_transform"][key] = value;
    const Status s = loadGlb(g, &m);
    EXPECT_FALSE(s.ok()) << key;
    EXPECT_NE(s.message().find("KHR_texture_transform" + std::string(named)), std::string::npos) << s.message();
  }
}

TEST(CompressedGltf, BasisuIsRefusedByName) {
  Glb g = split(readAll(kDir + "kaykit_webp.glb"));
  g.doc["extensionsUsed"] = {"KHR_texture_basisu"};
  g.doc["extensionsRequired"] = {"KHR_texture_basisu"};
  VegetationModel m;
  const Status s = loadGlb(g, &m);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("'KHR_texture_basisu' (KTX2 / Basis Universal textures), which Canopy does not read"), std::string::npos)
      << s.message();
}

}  // namespace
