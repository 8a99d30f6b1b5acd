#pragma once
// Vegetation input: glTF 2.0 (.gltf with external or embedded buffers, and .glb) flattened into
// one triangle list in world space (node transforms applied) with positions, normals, texcoord 0,
// per-triangle materials, base-colour textures and factors, alphaMode and alphaCutoff; the
// instances of EXT_mesh_gpu_instancing as copies; a required extension it does not implement
// refused by name (docs/design.md "Instances", "Errors and hostile input").
//
// Every file is treated as hostile: tinygltf 2.7.0 parses the JSON, but success is decided by
// Canopy's own checks (buffer views inside their buffers, accessors inside their views, index
// values inside the vertex range, node hierarchy acyclic, textures decodable, external paths
// relative and inside the model's folder). A refusal is a Status naming the file and the glTF
// element; nothing is read out of bounds.
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <canopy/canopy_params.h>

#include "engine/status.h"
#include "render/model.h"

namespace canopy {

// GltfLoadOptions: <canopy/canopy_params.h>; the model type: render/model.h.
// Loads `path` (.gltf or .glb, decided by the file's first bytes). On failure `out` is empty and
// the Status names the file and the element ("meshes[2].primitives[0]: accessor 7 ...").
// Never throws; a file that is not a regular file (FIFO, device, folder) is refused without
// blocking; every limit of `options` holds before anything is allocated from the file's numbers.
Status loadGltf(const std::string& path, const GltfLoadOptions& options, VegetationModel* out);

// The same from memory (the fuzz target): `bytes` is the model, `files` its external files by URI
// relative to the model (the same path rules as on disk: no absolute paths, no "..").
Status loadGltfFromMemory(const std::string& name, const std::vector<unsigned char>& bytes,
                          const std::map<std::string, std::vector<unsigned char>>& files, const GltfLoadOptions& options,
                          VegetationModel* out);

}  // namespace canopy
