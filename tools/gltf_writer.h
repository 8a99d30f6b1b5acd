#pragma once
// Writes a VegetationModel as a binary glTF 2.0 file (.glb): one mesh, one primitive per used
// material (sharing the vertex accessors), metallic-roughness materials with baseColorFactor,
// alphaMode/alphaCutoff/doubleSided and embedded PNG base-colour textures. loadGltf() reads it
// back to the same triangles (grouped by material), materials and images.
#include <string>

#include "engine/status.h"
#include "render/model.h"

namespace canopy {

// The model's last material is skipped when no triangle uses it (the loader's own default
// material). Refused: inconsistent arrays, or a file over the .glb format's 4 GiB.
Status writeGlb(const std::string& path, const VegetationModel& model);

}  // namespace canopy
