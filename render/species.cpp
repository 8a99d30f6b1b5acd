#include "render/species.h"

#include <algorithm>
#include <cmath>

#include <canopy/canopy_params.h>

#include "shared/layers.h"

namespace canopy {

Status checkSpecies(const std::vector<SpeciesModel>& species) {
  if (species.empty()) return Status::error(Result::InvalidArgument, "species: at least one species is needed");
  if (species.size() > kMaxSceneSpecies)
    return Status::error(Result::InvalidArgument, "species: " + std::to_string(species.size()) + " species, at most " +
                                                      std::to_string(kMaxSceneSpecies));
  for (size_t i = 0; i < species.size(); ++i) {
    const SpeciesModel& s = species[i];
    const std::string name = "species #" + std::to_string(i);
    if (!s.model) return Status::error(Result::InvalidArgument, name + ": no model");
    if (!(s.flexibility >= kMinFlexibility && s.flexibility <= kMaxFlexibility))
      return Status::error(Result::InvalidArgument, name + ".flexibility = " + std::to_string(s.flexibility) + " is outside [0, 4]");
    if (!(s.responseSpeed >= kMinResponseSpeed && s.responseSpeed <= kMaxResponseSpeed))
      return Status::error(Result::InvalidArgument,
                           name + ".responseSpeed = " + std::to_string(s.responseSpeed) + " is outside [0.25, 4]");
  }
  return Status();
}

namespace {
template <typename T>
void append(std::vector<T>& to, const std::vector<T>& from) {
  to.insert(to.end(), from.begin(), from.end());
}
}  // namespace

Status mergeSpecies(const std::vector<SpeciesModel>& in, std::vector<SpeciesParts>& parts, VegetationModel* merged,
                    SpeciesParts* out, std::vector<MeshSpecies>* species) {
  if (parts.size() != in.size()) return Status::error("species: parts for " + std::to_string(parts.size()) + " of " +
                                                      std::to_string(in.size()) + " species");
  *out = SpeciesParts{};
  species->clear();
  const bool several = in.size() > 1;
  uint64_t vertices = 0, triangles = 0, leaves = 0, plants = 0;
  for (size_t s = 0; s < in.size(); ++s) {
    vertices += in[s].model->positions.size();
    triangles += in[s].model->triangleCount();
    leaves += parts[s].roots.leafCount();
    plants += parts[s].plants.count();
  }
  // Indices, leaves and plants are 32-bit across the merged model.
  if (vertices >= kNoLeaf || triangles >= kNoLeaf || leaves >= kNoLeaf || plants >= kNoPlant)
    return Status::error(Result::InvalidArgument, "species: together " + std::to_string(vertices) + " vertices and " +
                                                      std::to_string(triangles) + " triangles, more than 32-bit indices hold");
  if (several) {
    *merged = VegetationModel{};
    merged->path = "the species";
    merged->positions.reserve(vertices);
    merged->normals.reserve(vertices);
    merged->uvs.reserve(vertices);
    merged->indices.reserve(3 * triangles);
    merged->triangleMaterial.reserve(triangles);
    merged->boundsMin = glm::vec3(INFINITY);
    merged->boundsMax = glm::vec3(-INFINITY);
  }
  uint32_t vertexBase = 0, leafBase = 0, plantBase = 0, materialBase = 0, imageBase = 0, triangleBase = 0;
  for (size_t s = 0; s < in.size(); ++s) {
    const VegetationModel& m = *in[s].model;
    SpeciesParts& p = parts[s];
    MeshSpecies ms;
    ms.firstMaterial = materialBase;
    ms.materialCount = uint32_t(m.materials.size());
    ms.firstLeaf = leafBase;
    ms.leafCount = p.roots.leafCount();
    ms.firstPlant = plantBase;
    ms.plantCount = p.plants.count();
    ms.triangles = m.triangleCount();
    ms.boundsMin = m.boundsMin;
    ms.boundsMax = m.boundsMax;
    ms.flexibility = in[s].flexibility;
    ms.responseSpeed = in[s].responseSpeed;
    ms.name = m.path.empty() ? "species #" + std::to_string(s) : m.path;
    species->push_back(ms);
    // The parts, renumbered past the earlier species'.
    append(out->split.role, p.split.role);
    append(out->split.reason, p.split.reason);
    for (PartReport r : p.split.parts) {
      r.material += materialBase;
      out->split.parts.push_back(std::move(r));
    }
    out->split.rigidTriangles += p.split.rigidTriangles;
    out->split.foliageTriangles += p.split.foliageTriangles;
    append(out->foliage, p.foliage);
    if (!p.rigidAnchors.empty() || !out->rigidAnchors.empty()) {
      // A species without rigid parts: its vertices' own positions (never read: no rigid chunk).
      for (size_t v = out->rigidAnchors.size(); v < vertexBase; ++v) out->rigidAnchors.push_back({glm::vec3(0.0f), LAYER_RIGID_FULL});
      if (p.rigidAnchors.size() == m.positions.size()) append(out->rigidAnchors, p.rigidAnchors);
      else
        for (const glm::vec3& q : m.positions) out->rigidAnchors.push_back({q, LAYER_RIGID_FULL});
    }
    if (p.layerRoots.size() == p.roots.leafCount()) append(out->layerRoots, p.layerRoots);
    else
      for (uint32_t v : p.roots.leafRoot) out->layerRoots.push_back(m.positions[v]);
    for (uint32_t l : p.roots.leafOfVertex) out->roots.leafOfVertex.push_back(l == kNoLeaf ? kNoLeaf : l + leafBase);
    for (uint32_t v : p.roots.leafRoot) out->roots.leafRoot.push_back(v + vertexBase);
    for (uint32_t pl : p.plants.leafPlant) out->plants.leafPlant.push_back(pl == kNoPlant ? kNoPlant : pl + plantBase);
    // Boxes: triangles past the earlier species', parents past their boxes.
    const uint32_t boxBase = uint32_t(out->boxes.boxes.size());
    out->speciesBoxes.push_back(boxBase);
    for (FoliageBox b : p.boxes.boxes) {
      if (b.parent != kNoBox) b.parent += boxBase;
      b.firstTriangle += out->boxes.triangles.size();
      out->boxes.boxes.push_back(b);
    }
    for (uint32_t t : p.boxes.triangles) out->boxes.triangles.push_back(t + triangleBase);
    append(out->plants.boundsMin, p.plants.boundsMin);
    append(out->plants.boundsMax, p.plants.boundsMax);
    append(out->plants.footMin, p.plants.footMin);
    append(out->plants.footMax, p.plants.footMax);
    p.plants.sway.resize(p.plants.count(), 1.0f);
    append(out->plants.sway, p.plants.sway);
    p.plants.rigid.resize(p.plants.count(), 0);
    append(out->plants.rigid, p.plants.rigid);
    if (several) {
      append(merged->positions, m.positions);
      append(merged->normals, m.normals);
      append(merged->uvs, m.uvs);
      for (uint32_t i : m.indices) merged->indices.push_back(i + vertexBase);
      for (uint32_t t : m.triangleMaterial) merged->triangleMaterial.push_back(t + materialBase);
      for (ModelMaterial mat : m.materials) {
        for (int32_t* image : {&mat.baseColorImage, &mat.normalImage, &mat.transmissionImage, &mat.transmissionColorImage})
          if (*image >= 0) *image += int32_t(imageBase);
        merged->materials.push_back(std::move(mat));
      }
      append(merged->images, m.images);
      merged->boundsMin = glm::min(merged->boundsMin, m.boundsMin);
      merged->boundsMax = glm::max(merged->boundsMax, m.boundsMax);
      for (const std::string& w : m.warnings) merged->warnings.push_back(ms.name + ": " + w);
    }
    vertexBase += uint32_t(m.positions.size());
    triangleBase += uint32_t(m.triangleCount());
    leafBase += ms.leafCount;
    plantBase += ms.plantCount;
    materialBase += ms.materialCount;
    imageBase += uint32_t(m.images.size());
    p = SpeciesParts{};
  }
  out->speciesBoxes.push_back(uint32_t(out->boxes.boxes.size()));
  return Status();
}

Status mergeBendHierarchies(const std::vector<SpeciesModel>& species, VegetationModel* merged) {
  size_t vertices = 0, branches = 0;
  for (const SpeciesModel& sp : species) {
    vertices += sp.model->positions.size();
    branches += sp.model->branches.size();
  }
  if (merged->positions.size() != vertices)
    return Status::error("species: the merged model holds " + std::to_string(merged->positions.size()) + " vertices, the species " +
                         std::to_string(vertices));
  if (branches >= BEND_LEAF_ONLY)
    return Status::error(Result::InvalidArgument, "species: together " + std::to_string(branches) + " branches, more than 32-bit indices hold");
  merged->bend.clear();
  merged->branches.clear();
  merged->bend.reserve(vertices);
  merged->branches.reserve(branches);
  for (uint32_t s = 0; s < species.size(); ++s) {
    const VegetationModel& m = *species[s].model;
    const uint32_t base = uint32_t(merged->branches.size());
    for (gpu::BendBranch b : m.branches) {
      if (b.parent != BEND_NO_PARENT) b.parent += base;
      merged->branches.push_back(b);
    }
    if (m.bend.empty()) {
      merged->bend.insert(merged->bend.end(), m.positions.size(), gpu::BendVertex{BEND_NO_BRANCH, s});
      continue;
    }
    for (gpu::BendVertex v : m.bend) {
      if (v.branch == BEND_NO_BRANCH) v.w = s;
      else if (v.branch != BEND_LEAF_ONLY) v.branch += base;
      merged->bend.push_back(v);
    }
  }
  return Status();
}

std::vector<uint32_t> materialSpecies(const std::vector<MeshSpecies>& species) {
  std::vector<uint32_t> out;
  for (uint32_t s = 0; s < species.size(); ++s) out.insert(out.end(), species[s].materialCount, s);
  return out;
}

}  // namespace canopy
