#pragma once
// Compressed glTF (issue 78), decoded into plain buffers before the loader reads a byte
// (render/gltf_loader.cpp), each through Debian's library (third_party_notes/compressed-gltf.md):
// EXT_meshopt_compression (meshoptimizer), KHR_draco_mesh_compression (draco), EXT_texture_webp
// (libwebp); KHR_texture_transform's matrix for the texture coordinates. Every count is checked
// against the loader's budgets before anything is allocated, and every failure names the element.
#include <cstdint>
#include <map>
#include <utility>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>
#include <tiny_gltf.h>

#include "engine/status.h"

namespace canopy {

struct GltfLoadOptions;

// One bufferView of EXT_meshopt_compression, as the JSON stage left it: pointed at its compressed
// bytes (the extension's buffer, offset and length), to be decoded into `count` x `stride` bytes.
struct MeshoptView {
  int view = -1;
  uint64_t count = 0;
  uint32_t stride = 0;
  int mode = 0;    // 0 ATTRIBUTES, 1 TRIANGLES, 2 INDICES
  int filter = 0;  // 0 NONE, 1 OCTAHEDRAL, 2 QUATERNION, 3 EXPONENTIAL
};

// The JSON stage, before tinygltf: each bufferView with EXT_meshopt_compression pointed at its
// compressed bytes and listed in *views; each fallback buffer (no data of its own) replaced by a
// one-byte stand-in, so tinygltf loads nothing for it.
Status prepareMeshopt(nlohmann::json& doc, const GltfLoadOptions& opt, std::vector<MeshoptView>* views);

// After tinygltf: every listed view decoded into a new buffer of `m`, the view pointed at it.
Status decodeMeshopt(tinygltf::Model& m, const std::vector<MeshoptView>& views);

// Every primitive with KHR_draco_mesh_compression decoded: its attributes' and indices' accessors
// pointed at new float (indices: uint32) buffers; counts checked against the accessors and budgets.
// `indices`: (mesh, primitive) -> the indices accessor the JSON stage took off a Draco primitive
// (GltfReadParts::dracoIndices), put back once decoded.
Status decodeDraco(tinygltf::Model& m, const GltfLoadOptions& opt, const std::map<std::pair<int, int>, int>& indices);

// The image a texture shows: EXT_texture_webp's source when the texture has one, else `source`.
int textureImage(const tinygltf::Texture& t);

// Whether `data` is a WebP file (RIFF....WEBP), and its decode into RGBA8 after the size checks
// (`maxDimension` per side; *pixelsLeft the budget, reduced by its pixels).
bool isWebp(const unsigned char* data, uint64_t size);
Status decodeWebp(const unsigned char* data, uint64_t size, uint32_t maxDimension, uint64_t* pixelsLeft, uint32_t* width,
                  uint32_t* height, std::vector<unsigned char>* rgba);

// KHR_texture_transform of a textureInfo's extensions (glTF: translation x rotation x scale); the
// identity without one. `texCoord`: the extension's texCoord override, else -1.
struct TextureTransform {
  double m[6] = {1, 0, 0, 0, 1, 0};  // u' = m0 u + m1 v + m2, v' = m3 u + m4 v + m5
  int texCoord = -1;
  bool identity = true;
};
Status textureTransform(const tinygltf::ExtensionMap& extensions, const std::string& what, TextureTransform* out);

}  // namespace canopy
