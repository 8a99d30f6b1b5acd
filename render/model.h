#pragma once
// The vegetation model Canopy animates, as the loader (render/gltf_loader.h) and the scene
// generator (tools/) produce it and the runtime consumes it: one triangle list in world space
// with per-triangle materials, decoded images, and the optional branch and box hierarchies.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include <canopy/canopy_params.h>

#include "shared/bend.h"

namespace canopy {

// AlphaMode: <canopy/canopy_params.h>.
struct ModelMaterial {
  std::string name;
  glm::vec4 baseColorFactor{1.0f};
  int32_t baseColorImage = -1;  // index into VegetationModel::images, -1: none
  AlphaMode alphaMode = AlphaMode::Opaque;
  float alphaCutoff = 0.5f;
  bool doubleSided = false;
  // Diffuse transmission of a leaf (docs/design.md "Layers: leaf shading"), from
  // KHR_materials_diffuse_transmission (its factor and colour factor) or, where only that is
  // present, KHR_materials_transmission's factor; -1 when the file has neither: a foliage material
  // then takes LayerSettings.leafTransmission and glows in its own base colour.
  float transmissionFactor = -1.0f;
  glm::vec3 transmissionColor{1.0f};
  int32_t transmissionImage = -1;       // its factor texture (alpha channel), -1: none
  int32_t transmissionColorImage = -1;  // its colour texture (RGB), -1: none
  int32_t normalImage = -1;             // tangent-space normal map (glTF normalTexture), -1: none
  float normalScale = 1.0f;             // glTF normalTexture.scale
  // KHR_materials_volume (Habel's translucency: Beer-Lambert through the leaf): thickness in the
  // mesh's units, and the distance at which light falls to attenuationColor (infinite: none). A
  // negative thickness: the file has no volume (LayerSettings.leafOpticalDepth applies).
  float thicknessFactor = -1.0f;
  float attenuationDistance = INFINITY;
  glm::vec3 attenuationColor{1.0f};
  // The leaf's gloss (docs/design.md "Layers: leaf shading"): glTF's perceptual roughness,
  // roughnessFactor x the mean of its metallicRoughnessTexture's green channel (the Beckmann sigma
  // of the lobe is its square, as GGX's alpha); -1: the model gives none (LayerSettings.leafRoughness).
  float roughness = -1.0f;
  // The lobe's weight: KHR_materials_specular's specularFactor x the largest of its colour factor.
  float specularFactor = 1.0f;
};

struct ModelImage {
  std::string name;
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> rgba;  // 8-bit RGBA, rows top to bottom
  bool linear = false;        // data, not colour (normal maps): uploaded UNORM, not sRGB
};

inline constexpr uint32_t kNoPlant = 0xffffffffu;

struct VegetationModel {
  std::string path;
  std::vector<glm::vec3> positions;  // world space (node transforms applied)
  std::vector<glm::vec3> normals;    // world space, unit length (computed when the file has none)
  std::vector<glm::vec2> uvs;        // texcoord 0 ((0,0) when absent)
  std::vector<uint32_t> indices;     // triangle list
  std::vector<uint32_t> triangleMaterial;  // per triangle: index into materials
  std::vector<ModelMaterial> materials;    // the file's materials, then one default material last
  std::vector<ModelImage> images;          // decoded base-colour images (only those used)
  glm::vec3 boundsMin{0.0f}, boundsMax{0.0f};
  // Optional branch hierarchy for the per-vertex wind baseline (shared/bend.h): per vertex its
  // innermost branch and Habel's w, and the branch table (parents before children). Empty: none
  // (glTF files; the baseline then derives a trunk and radial branches from the positions).
  std::vector<gpu::BendVertex> bend;
  std::vector<gpu::BendBranch> branches;
  // Optional bounding-box hierarchy of the foliage (Lluch et al.; render/foliage_boxes.h): each
  // box's parent (an earlier box, or 0xffffffff), and per triangle the box that owns it (foliage
  // triangles; others 0xffffffff). Empty: none (a k-d split of the leaf roots stands in).
  std::vector<uint32_t> boxParent;
  std::vector<uint32_t> triangleBox;
  // Optional plant of each triangle (eq. 7 per plant, docs/design.md "Per-plant roots"): plants
  // numbered from 0, kNoPlant for parts of none (the ground). Empty: the whole model is one plant.
  // mergeOverlappingPlants: plants whose bounds overlap on the ground plane (x, z) are one plant (a
  // glTF file's root nodes, which may be the parts of one plant rather than plants of a field).
  std::vector<uint32_t> trianglePlant;
  bool mergeOverlappingPlants = false;
  // The plants bend through a branch hierarchy of their own in the per-vertex baseline (generated
  // plants, a host mesh with MeshDesc.branches), whether or not this copy carries it (`bend`): their
  // sway scale is 1 (render/plant_sway.h); otherwise it comes from their levers.
  bool ownHierarchy = false;
  std::vector<std::string> warnings;       // parts skipped (unused broken parts, ignored features)
  size_t triangleCount() const { return indices.size() / 3; }
};

}  // namespace canopy
