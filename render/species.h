#pragma once
// Several species in one vegetation (docs/design.md "Species"): each species' model is prepared
// on its own (material split, leaf roots and their cache, plants), then the species are laid end
// to end into one model, each stored once however many copies name it: vertices, leaves, plants,
// materials and images numbered species after species, so a chunk (one material) belongs to one
// species and a species' leaves and plants are contiguous ranges.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "engine/status.h"
#include "render/foliage_boxes.h"
#include "render/leaf_roots.h"
#include "render/material_split.h"
#include "render/model.h"
#include "render/plants.h"
#include "shared/layers.h"

namespace canopy {

// Flexibility and response speed ranges (CanopySpecies; the scene file's species keys).
inline constexpr float kMinFlexibility = 0.0f, kMaxFlexibility = 4.0f;
inline constexpr float kMinResponseSpeed = 0.25f, kMaxResponseSpeed = 4.0f;

// One species as the vegetation is given it: its model and its wind response (docs/design.md
// "Species: wind response"): flexibility scales its displacement (eq. 6), responseSpeed divides
// its layers' delay (eq. 4).
struct SpeciesModel {
  const VegetationModel* model = nullptr;
  float flexibility = 1.0f;
  float responseSpeed = 1.0f;
};

// What the vegetation keeps of each species: its ranges in the merged numbering, its model-space
// bounds, its wind response.
struct MeshSpecies {
  uint32_t firstMaterial = 0, materialCount = 0;
  uint32_t firstLeaf = 0, leafCount = 0;
  uint32_t firstPlant = 0, plantCount = 0;
  uint64_t triangles = 0;
  glm::vec3 boundsMin{0}, boundsMax{0};
  float flexibility = 1.0f, responseSpeed = 1.0f;
  std::string name;  // the model's path (messages)
};

// Checks the species list: at least one, at most kMaxSceneSpecies, each with a model with
// triangles, the responses finite and in range; messages name "species #i".
Status checkSpecies(const std::vector<SpeciesModel>& species);

// One species' preparation (prepareLayerMesh runs it per species).
struct SpeciesParts {
  MaterialSplit split;
  std::vector<uint8_t> foliage;  // per triangle
  LeafRoots roots;               // leafOfVertex and leafRoot (rootOfVertex dropped)
  Plants plants;
  // Per vertex, a rigid vertex's anchor and share (render/rigid_flex.h rigidAnchors); empty: none.
  std::vector<gpu::LayerLeafRoot> rigidAnchors;
  // Per leaf, the position its layer is decided by (render/leaf_attach.h leafLayerRoots); empty: its root's.
  std::vector<glm::vec3> layerRoots;
  BoxHierarchy boxes;            // with impostors: its foliage boxes (render/impostors.h buildFoliageBoxes)
  std::vector<uint32_t> speciesBoxes;  // merged: where each species' boxes start, then the end
};

// The species laid end to end: `merged` gets every species' triangles, materials and images with
// their indices moved past the earlier species' (the bend hierarchy is not merged: the per-vertex
// baseline takes one species), `out` the parts renumbered alike (box hierarchies side by side, a
// forest per species), and
// `species` each one's ranges. The parts are consumed.
Status mergeSpecies(const std::vector<SpeciesModel>& in, std::vector<SpeciesParts>& parts, VegetationModel* merged,
                    SpeciesParts* out, std::vector<MeshSpecies>* species);

// The per-vertex baseline's branch hierarchy of several species (`merged` holds their vertices laid
// end to end, as mergeSpecies writes them): the branch tables one after the other (branch and parent
// indices renumbered), each vertex's BendVertex; a species without a hierarchy gets BEND_NO_BRANCH
// with its species index in w, so it bends about its own fallback trunk (shared/bend.h BendTrunk).
Status mergeBendHierarchies(const std::vector<SpeciesModel>& species, VegetationModel* merged);

// The species of each material (materials are numbered species after species).
std::vector<uint32_t> materialSpecies(const std::vector<MeshSpecies>& species);

}  // namespace canopy
