// The context's scene and size after creation (<canopy/canopy.h>: setCanopyInstances,
// setCanopySpecies, resizeCanopy) and the helpers createCanopy shares with them.
#include "render/canopy_context.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "engine/memory.h"

namespace canopy {

// CanopyDesc.guardBand in pixels for a target side of `size`: a multiple of 16 (whole occupancy
// tiles and default warp cells, so a still camera's layer pixel is its output pixel plus whole
// cells), at most what keeps the layers within 16384 pixels.
uint32_t guardPixels(float fraction, uint32_t size) {
  const uint32_t g = 16u * uint32_t(std::lround(double(fraction) * size / 16.0));
  return std::min(g, (16384u - std::min(size, 16384u)) / 32u * 16u);
}

Status checkRange(const char* name, uint32_t v, uint32_t lo, uint32_t hi) {
  if (v < lo || v > hi)
    return Status::error(std::string(name) + " = " + std::to_string(v) + " is outside [" + std::to_string(lo) + ", " +
                         std::to_string(hi) + "]");
  return Status();
}

// The size-dependent parts (compositor, dynamics) and the graphs recorded from them, freed once no
// frame in flight reads them.
void retireSizeDependentParts(CanopyContext& c) {
  Device* d = c.device;
  retireRecordGraphs(c, std::move(c.recordGraphs));
  c.recordGraphs.clear();
  auto comp = std::make_shared<Compositor>();
  auto dyn = std::make_shared<LayerDynamics>();
  std::swap(*comp, c.compositor);
  std::swap(*dyn, c.dynamics);
  deferRelease(*d, [comp, dyn] {
    destroyCompositor(*comp);
    destroyLayerDynamics(*dyn);
  });
}

Status makeRigidFollow(CanopyContext& c) {
  if (c.rigid.device) {
    auto old = std::make_shared<RigidFollow>();
    std::swap(*old, c.rigid);
    deferRelease(*c.device, [old] { destroyRigidFollow(*old); });
  }
  if (!c.layers.mesh.hasRigid || c.layers.mesh.streamed) return Status();
  return createRigidFollow(*c.device, c.layers, c.compositor.desc, &c.rigid);
}

// The copies as the layers take them (CanopyInstance's fields side by side).
InstanceInputs instanceInputs(const std::vector<CanopyInstance>& instances) {
  InstanceInputs in;
  for (const CanopyInstance& i : instances) {
    in.models.push_back(toGlm(i.transform));
    in.tints.push_back(toGlm(i.tint));
    in.windPhases.push_back(i.windPhase);
    in.species.push_back(i.species);
  }
  return in;
}

// The species as the layers take them; a species without a model or triangles is refused by its
// index (checkSpecies checks the response ranges).
Status speciesModels(const char* call, const std::vector<CanopySpecies>& species, std::vector<SpeciesModel>* out) {
  for (size_t i = 0; i < species.size(); ++i) {
    if (!species[i].model)
      return Status::error(Result::InvalidArgument, std::string(call) + ": species #" + std::to_string(i) + " has no model");
    if (species[i].model->data.triangleCount() == 0)
      return Status::error(Result::InvalidModel, std::string(call) + ": species #" + std::to_string(i) + " has no triangles");
    out->push_back({&species[i].model->data, species[i].flexibility, species[i].responseSpeed});
  }
  return Status();
}

Status setCanopyInstances(CanopyContext* c, const std::vector<CanopyInstance>& instances) {
  return guardApi("setCanopyInstances", [&]() -> Status {
    if (!c) return Status::error("setCanopyInstances: null context");
    const InstanceInputs copies = instanceInputs(instances);
    CANOPY_TRY(setLayerInstances(c->layers, copies).context("setCanopyInstances"));
    // The default simulation plane stands at the vegetation's depth and its tile spans the view
    // there (eq. 4's domain units): taken again from the next frame for the copies' new bounds.
    if (!c->params.customPlane) c->planeChosen = false;
    // The per-vertex baseline's motion table holds one block per copy: sized again, graphs rebuilt.
    if (c->desc.allowPerVertex) CANOPY_TRY(resizePerVertexCopies(c->perVertex, uint32_t(copies.models.size())).context("setCanopyInstances"));
    // The per-vertex motion table and the impostor list may have been replaced: graphs rebuilt.
    if (c->desc.allowPerVertex || c->layers.impostors.enabled) c->generation++;
    return Status();
  });
}

Status setCanopySpecies(CanopyContext* c, const std::vector<CanopySpecies>& species, const std::vector<CanopyInstance>& instances) {
  return guardApi("setCanopySpecies", [&]() -> Status {
    if (!c) return Status::error("setCanopySpecies: null context");
    if (c->desc.allowPerVertex)
      return Status::error(Result::InvalidArgument, "setCanopySpecies: the per-vertex baseline (CanopyDesc.allowPerVertex) keeps "
                                                    "the first mesh's hierarchy; create a new context instead");
    std::vector<SpeciesModel> models;
    CANOPY_TRY(speciesModels("setCanopySpecies", species, &models));
    // The vegetation as it stands (size, guard band, formats, budget, settings in force) with the
    // new species and copies; the old one stays until the new one exists.
    LayeredVegetationDesc ld = c->layers.desc;
    ld.settings = c->layers.settings;
    ld.progress = {};
    ld.copies = instanceInputs(instances);
    if (ld.copies.models.empty()) return Status::error(Result::InvalidArgument, "setCanopySpecies: at least one instance is needed");
    LayeredVegetation next;
    CANOPY_TRY(createLayeredVegetation(*c->device, models, ld, &next).context("setCanopySpecies"));
    auto old = std::make_shared<LayeredVegetation>(std::move(c->layers));
    c->layers = std::move(next);
    deferRelease(*c->device, [old] { destroyLayeredVegetation(*old); });
    CANOPY_TRY(makeRigidFollow(*c).context("setCanopySpecies"));
    c->generation++;  // new layer images and mesh: graphs rebuilt
    c->previousAnimFrame = gpu::AnimFrame{};
    if (!c->params.customPlane) c->planeChosen = false;
    return Status();
  });
}

Status resizeCanopy(CanopyContext* c, uint32_t width, uint32_t height) {
  return guardApi("resizeCanopy", [&]() -> Status {
    if (!c) return Status::error("resizeCanopy: null context");
    CANOPY_TRY(checkRange("resizeCanopy width", width, 1, 16384));
    CANOPY_TRY(checkRange("resizeCanopy height", height, 1, 16384));
    if (width == c->desc.width && height == c->desc.height && c->sized) return Status();
    Device& d = *c->device;
    retireSizeDependentParts(*c);
    c->sized = false;  // no wait: the old objects go once the frames using them completed
    c->desc.width = width;
    c->desc.height = height;
    c->perVertex.desc.width = width;
    c->perVertex.desc.height = height;
    c->rigid.desc.width = width;
    c->rigid.desc.height = height;
    Status s = [&]() -> Status {
      CompositorDesc cd = c->compositorDesc;
      cd.width = width;
      cd.height = height;
      cd.guardX = guardPixels(c->desc.guardBand, width);
      cd.guardY = guardPixels(c->desc.guardBand, height);
      CANOPY_TRY(setLayerTargetSize(c->layers, compositorLayerWidth(cd), compositorLayerHeight(cd), cd.guardX, cd.guardY));
      CANOPY_TRY(createCompositor(d, cd, &c->compositor));
      // The warp grid's corners are in pixels: a new grid, and no previous displacement to take
      // motion vectors against (beginCanopyFrame sees the grid change).
      c->previousAnimFrame = gpu::AnimFrame{};
      CANOPY_TRY(createLayerDynamics(d, compositorLayerWidth(cd), compositorLayerHeight(cd), c->desc.minCellSize, c->desc.maxLayers,
                                     &c->dynamics));
      c->compositorDesc = cd;
      c->sized = true;
      return Status();
    }();
    c->generation++;
    return s.context("resizeCanopy to " + std::to_string(width) + "x" + std::to_string(height));
  });
}

}  // namespace canopy
