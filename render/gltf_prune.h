#pragma once
// What of a glTF document the vegetation reads (render/gltf_loader.cpp), found on the JSON before
// tinygltf parses it, so that only that can refuse the file (issue 68; glTF 2.0 lets a file carry
// parts a loader does not use): the scene's nodes, their meshes' triangle primitives (POSITION,
// NORMAL, TEXCOORD_0, indices), EXT_mesh_gpu_instancing's attributes, the materials' textures and
// images, and the bufferViews and buffers behind them. Everything else is replaced by a stub
// tinygltf accepts (array positions kept, so messages name the file's own indices); animations and
// skins are dropped. The buffers that are read are checked here with Canopy's messages (a missing,
// remote or placeholder uri) and RFC 2397 data URIs that are not base64 re-encoded for tinygltf.
#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "engine/status.h"

namespace canopy {

struct GltfReadParts {
  std::vector<std::string> warnings;  // what was left out and why (points, lines)
  // Index accessors without a bufferView (glTF: all zeros, plus a sparse part): tinygltf refuses
  // them, so they are taken off their primitive here and read by the loader. (mesh, primitive) ->
  // accessor.
  std::map<std::pair<int, int>, int> indicesWithoutView;
  // The indices of primitives with KHR_draco_mesh_compression, taken off them likewise (they have
  // no bufferView until decodeDraco gives them one and puts them back).
  std::map<std::pair<int, int>, int> dracoIndices;
};

// Rewrites `doc` as above. `glb`: the document is a GLB's JSON chunk, whose BIN chunk holds
// `binBytes` bytes (0: none).
Status keepReadParts(nlohmann::json& doc, bool glb, uint64_t binBytes, GltfReadParts* out);

}  // namespace canopy
