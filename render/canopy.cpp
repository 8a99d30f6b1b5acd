#include "render/canopy_context.h"
#include "render/host_images.h"

#include <canopy/canopy_graph.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <new>
#include <string>

#include "engine/memory.h"
#include "render/material_split.h"
#include "render/per_vertex.h"
#include "render/reprojection.h"

namespace canopy {

namespace {

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

// The plane's axes, checked together (its fields one by one: the schema).
Status validatePlane(const SimulationPlane& p) {
  CANOPY_TRY(checkParams(p, "CanopyParams.plane."));
  const glm::vec3 r = toGlm(p.right), u = toGlm(p.up);
  if (std::abs(glm::length(r) - 1.0f) > 1e-3f || std::abs(glm::length(u) - 1.0f) > 1e-3f || std::abs(glm::dot(r, u)) > 1e-3f)
    return Status::error("CanopyParams.plane: right and up must be orthogonal unit vectors");
  return Status();
}

// Every field against its schema line, then what is checked together and against the context's
// creation. Run when parameters are given (createCanopy, setCanopyParams), never per frame.
Status validateParams(const CanopyContext& c, const CanopyParams& p) {
  CANOPY_TRY(checkParams(p, "CanopyParams."));
  CANOPY_TRY(validateLayerSettings(p.layers));
  if (p.layers.layout.count() > c.desc.maxLayers)
    return Status::error("CanopyParams.layers.layout " + toString(p.layers.layout) + " has " +
                         std::to_string(p.layers.layout.count()) + " layers; CanopyDesc.maxLayers is " +
                         std::to_string(c.desc.maxLayers));
  if (p.dynamics.cellSize < c.desc.minCellSize)
    return Status::error("CanopyParams.dynamics.cellSize = " + std::to_string(p.dynamics.cellSize) +
                         " is below CanopyDesc.minCellSize = " + std::to_string(c.desc.minCellSize));
  if (p.customPlane) CANOPY_TRY(validatePlane(p.plane));
  if (p.animation == AnimationMode::PerVertex && !c.desc.allowPerVertex)
    return Status::error("CanopyParams.animation = PerVertex needs CanopyDesc.allowPerVertex at creation");
  return Status();
}

// The host's camera in Canopy's standard depth convention (0 = near): a reverse-Z projection is
// mirrored in depth, z_clip' = w_clip - z_clip (docs/design.md, "Embedding contract"), so the
// layers are rasterised and compared as always and only the composite's depth I/O converts.
LayerView standardView(const CanopyContext& c, const CanopyCamera& cam) {
  LayerView v = toLayerView(cam);
  if (c.desc.depthConvention == DepthConvention::Reverse) {
    glm::mat4 mirror(1.0f);
    mirror[2][2] = -1.0f;
    mirror[3][2] = 1.0f;
    v.proj = mirror * v.proj;
  }
  return v;
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

void destroyNow(CanopyContext* c) {
  if (c->device) {
    dropPreparedWork(*c->device, c->perVertexUploads);
    for (RecordGraph& g : c->recordGraphs) g.graph->release(*c->device);
    destroyCompositor(c->compositor);
    destroyShadowCaster(c->shadow);
    destroyPerVertex(c->perVertex);
    destroyLayerDynamics(c->dynamics);
    destroyLayeredVegetation(c->layers);
  }
  c->shared.reset();  // the simulation goes with the last context that follows it
  delete c;
}

// Canopy's passes in `g`, around the host's imported images (one declaration for recordCanopy, the
// render-graph path and canopyPassGroupUses).
Status declarePasses(CanopyContext& ctx, rg::RenderGraph& g, const CompositeTargets& targets) {
  CanopyContext* c = &ctx;
  // The per-vertex baseline replaces every pass of the 2D method (a mode change bumps the
  // generation, so graphs are rebuilt).
  if (c->params.animation == AnimationMode::PerVertex) return addPerVertexPasses(c->perVertex, c->layers, g, targets);
  SimulationResources sr;
  CANOPY_TRY(addSimulationPasses(c->shared->sim, g, &sr, &c->skipSimulationStep));
  LayerResources lr;
  CANOPY_TRY(addLayerPasses(c->layers, g, &lr));
  rg::ResourceId disp = rg::kInvalidResource, prev = rg::kInvalidResource;
  rg::ResourceId animFrame = rg::kInvalidResource;
  CANOPY_TRY(addDynamicsPasses(c->dynamics, g, sr.tiled, sr.ring, sr.ringTimes, &disp, &prev, &animFrame));
  return addCompositePasses(c->compositor, g, lr, disp, prev, targets, {animFrame, sr.tiled});
}

// How the passes use the host's images, from a graph declared with placeholder imports (never
// realized): the union of each image's uses and the layout the last one leaves.
Status derivePassGroupUses(CanopyContext& c) {
  rg::RenderGraph probe;
  ImageDesc d;
  d.width = c.desc.width;
  d.height = c.desc.height;
  const rg::State any = rg::stateOf(rg::Use::TransferSrc);
  CompositeTargets t;
  d.format = c.desc.colorFormat;
  t.color = probe.importImage("host: colour", d, {}, any);
  d.format = c.desc.depthFormat;
  t.depth = probe.importImage("host: depth", d, {}, any);
  if (c.desc.motionFormat != VK_FORMAT_UNDEFINED) {
    d.format = c.desc.motionFormat;
    t.motion = probe.importImage("host: motion", d, {}, any);
  }
  CANOPY_TRY(declarePasses(c, probe, t));
  CANOPY_TRY(probe.compile());
  c.groupUses.clear();
  const std::pair<CanopyTarget, rg::ResourceId> targets[] = {
      {CanopyTarget::Color, t.color}, {CanopyTarget::Depth, t.depth}, {CanopyTarget::Motion, t.motion}};
  for (const auto& [which, id] : targets) {
    if (id == rg::kInvalidResource) continue;
    CanopyTargetUse u;
    u.target = which;
    u.state = probe.combinedUse(id);
    u.writes = rg::isWriteAccess(u.state.access);
    c.groupUses.push_back(u);
  }
  return Status();
}

Status checkVersion(uint32_t header) {
  const uint32_t lib = libraryVersion();
  auto text = [](uint32_t v) {
    return std::to_string(v >> 22) + "." + std::to_string((v >> 12) & 0x3ff) + "." + std::to_string(v & 0xfff);
  };
  // docs/embedding.md "Versions": below 1.0 a minor version breaks the API (its structs' layout
  // too), so 0.x needs the same minor version; from 1.0 on the library may be newer.
  const uint32_t major = header >> 22, minor = (header >> 12) & 0x3ff, libMinor = (lib >> 12) & 0x3ff;
  const bool fits = major == (lib >> 22) && (major == 0 ? minor == libMinor : minor <= libMinor);
  if (!fits)
    return Status::error(Result::VersionMismatch,
                         "createCanopy: the host was compiled against Canopy " + text(header) + " but the library is " + text(lib) +
                             (major == 0 ? " (below 1.0 the major and minor versions must match)"
                                         : " (the major versions must match and the library's minor version be at least the header's)"));
  return Status();
}

}  // namespace

Status createCanopy(Device& d, const VegetationModel& model, const CanopyDesc& desc, CanopyContext** out) {
  return createCanopy(d, std::vector<SpeciesModel>{SpeciesModel{&model}}, desc, out);
}

// The copies as the layers take them (CanopyInstance's fields side by side).
static InstanceInputs instanceInputs(const std::vector<CanopyInstance>& instances) {
  InstanceInputs in;
  for (const CanopyInstance& i : instances) {
    in.models.push_back(toGlm(i.transform));
    in.tints.push_back(toGlm(i.tint));
    in.windPhases.push_back(i.windPhase);
    in.species.push_back(i.species);
  }
  return in;
}

Status createCanopy(Device& d, const std::vector<SpeciesModel>& species, const CanopyDesc& desc, CanopyContext** out) {
  if (!out) return Status::error("createCanopy: out is null");
  *out = nullptr;
  CANOPY_TRY(checkVersion(desc.headerVersion));
  if (!d.device || !d.vk.CreateBuffer) return Status::error("createCanopy: the device was not adopted");
  static_assert(CANOPY_MAX_LAYERS == kMaxLayers, "CANOPY_DESC's maxLayers range");
  // The description's fields (params are checked with the context's limits below), and the
  // impostors' only when they are built.
  CANOPY_TRY(checkParams(desc, "CanopyDesc."));
  if (desc.impostors.enable) CANOPY_TRY(checkParams(desc.impostors, "CanopyDesc.impostors."));
  if (desc.shareSimulationWith && desc.shareSimulationWith->device != &d)
    return Status::error("CanopyDesc.shareSimulationWith belongs to another Device");
  CANOPY_TRY(checkSpecies(species).context("createCanopy"));
  // Nothing to animate is a mistake in the input (a glTF whose scene reaches no triangle mesh),
  // not an empty frame to draw silently.
  auto nameOf = [&](size_t i) {
    const VegetationModel& m = *species[i].model;
    const std::string name = m.path.empty() ? std::string("the model") : "'" + m.path + "'";
    return species.size() > 1 ? "species #" + std::to_string(i) + " (" + name + ")" : name;
  };
  for (size_t i = 0; i < species.size(); ++i)
    if (species[i].model->triangleCount() == 0)
      return Status::error(Result::InvalidModel, "createCanopy: " + nameOf(i) +
                                                     " has no triangles (no TRIANGLES mesh primitive is reachable from its scene)");
  auto* c = new (std::nothrow) CanopyContext();
  if (!c) return Status::error(Result::OutOfHostMemory, "createCanopy: out of host memory");
  c->device = &d;
  const uint64_t liveAtStart = d.allocator->liveBytes;
  c->desc = desc;
  c->desc.shareSimulationWith = nullptr;  // kept through `shared`, never dereferenced later
  c->params = desc.params;
  c->params.dynamics.cellSize = std::max(c->params.dynamics.cellSize, desc.minCellSize);
  Status s = [&]() -> Status {
    CANOPY_TRY(validateParams(*c, c->params));
    const uint32_t guardX = guardPixels(desc.guardBand, desc.width), guardY = guardPixels(desc.guardBand, desc.height);
    CompositorDesc cd;
    cd.width = desc.width;
    cd.height = desc.height;
    cd.guardX = guardX;
    cd.guardY = guardY;
    cd.colorFormat = desc.colorFormat;
    cd.depthFormat = desc.depthFormat;
    cd.motionFormat = desc.motionFormat;
    cd.reverseZ = desc.depthConvention == DepthConvention::Reverse;
    cd.maxLayers = desc.maxLayers;
    cd.minCellSize = desc.minCellSize;
    CANOPY_TRY(createCompositor(d, cd, &c->compositor));
    LayeredVegetationDesc ld;
    ld.width = desc.width + 2 * guardX;
    ld.height = desc.height + 2 * guardY;
    ld.guardX = guardX;
    ld.guardY = guardY;
    ld.colorFormat = desc.layerFormat;
    ld.split = desc.split;
    ld.roots = desc.roots;
    ld.rootCacheDir = desc.rootCacheDir;
    ld.cacheMaxBytes = desc.cacheMaxBytes;
    ld.progress = desc.progress;
    ld.restUse = rg::Use::FragmentSampled;
    ld.settings = c->params.layers;
    ld.impostors = desc.impostors;
    ld.copies = instanceInputs(desc.instances);
    if (desc.allowPerVertex) {
      for (size_t i = 0; i < species.size(); ++i) {
        const VegetationModel& m = *species[i].model;
        CANOPY_TRY(validateBendHierarchy(m.bend, m.branches, m.positions.size(), nameOf(i)));
      }
      ld.keepBend = true;
    }
    // The split is cheap; knowing there is nothing to animate before leaf roots and the mesh
    // upload saves a big model's preparation. A species without foliage (a rock) is drawn with the
    // trunks; a vegetation without any is refused.
    uint64_t foliage = 0;
    std::string names;
    for (size_t s = 0; s < species.size(); ++s) {
      const VegetationModel& m = *species[s].model;
      MaterialSplit split;
      CANOPY_TRY(splitMaterials(m, desc.split, &split));
      foliage += split.foliageTriangles;
      for (size_t i = 0; i < m.materials.size(); ++i) {  // appends: GCC 12's -Wrestrict misfires on "#" + ...
        names += names.empty() ? "#" : ", #";
        names += std::to_string(i);
        names += " '";
        names += m.materials[i].name;
        names += "'";
      }
    }
    if (foliage == 0)
      return Status::error(Result::InvalidModel, (species.size() > 1 ? std::string("the species have") : nameOf(0) + " has") +
                                                     " no foliage: every material is rigid (" + names +
                                                     "); name the leaf materials in CanopyDesc.split.foliage");
    if (desc.shareSimulationWith) {
      c->shared = desc.shareSimulationWith->shared;
    } else {
      c->shared = std::make_shared<SharedSimulation>();
      CANOPY_TRY(createSimulation(d, desc.simulation, &c->shared->sim, &c->shared->firstClear));
    }
    CANOPY_TRY(createLayerDynamics(d, ld.width, ld.height, desc.minCellSize, desc.maxLayers, &c->dynamics));
    // The layers last: what the budget leaves after the compositor, simulation and dynamics decides
    // whether the mesh is resident or streamed (docs/design.md "Layers: mesh budget and staging ring").
    if (desc.deviceMemoryBudget) {
      const uint64_t used = d.allocator->liveBytes - liveAtStart;
      if (used >= desc.deviceMemoryBudget)
        return Status::error("CanopyDesc.deviceMemoryBudget " + std::to_string(desc.deviceMemoryBudget >> 20) +
                             " MiB: the compositor, simulation and dynamics alone take " + std::to_string(used >> 20) +
                             " MiB; raise it (or 0: no limit)");
      ld.deviceMemoryBudget = desc.deviceMemoryBudget - used;
    }
    ld.stagingRingBytes = desc.meshStagingRingBytes;
    // The layers' parts keep their own uploads (flushLayerWork); the baseline's go to the context's list.
    CANOPY_TRY(createLayeredVegetation(d, species, ld, &c->layers));
    CANOPY_TRY(validateParams(*c, c->params));  // against the instances too (the per-vertex baseline)
    if (desc.allowPerVertex)
      CANOPY_TRY(createPerVertex(d, c->layers, c->layers.mesh.branches, c->compositor.desc, &c->perVertex, &c->perVertexUploads));
    releaseLeafRootPositions(c->layers.mesh);  // uploaded (or not needed)
    // The pass group's uses are the 2D method's; the baseline's (colour blended, depth tested and
    // written, motion) are among them.
    const AnimationMode mode = c->params.animation;
    c->params.animation = AnimationMode::Layers2D;
    Status uses = derivePassGroupUses(*c);
    c->params.animation = mode;
    return uses;
  }();
  if (!s.ok()) {
    destroyNow(c);
    return s.context("createCanopy");
  }
  *out = c;
  return Status();
}

Status createCanopy(Device* device, const Model* model, const CanopyDesc& desc, CanopyContext** out) {
  return guardApi("createCanopy", [&]() -> Status {
    if (!device || !model) {
      if (out) *out = nullptr;
      return Status::error("createCanopy: device and model are required");
    }
    return createCanopy(*device, model->data, desc, out);
  });
}

// The species as the layers take them; a species without a model or triangles is refused by its
// index (checkSpecies checks the response ranges).
static Status speciesModels(const char* call, const std::vector<CanopySpecies>& species, std::vector<SpeciesModel>* out) {
  for (size_t i = 0; i < species.size(); ++i) {
    if (!species[i].model)
      return Status::error(Result::InvalidArgument, std::string(call) + ": species #" + std::to_string(i) + " has no model");
    if (species[i].model->data.triangleCount() == 0)
      return Status::error(Result::InvalidModel, std::string(call) + ": species #" + std::to_string(i) + " has no triangles");
    out->push_back({&species[i].model->data, species[i].flexibility, species[i].responseSpeed});
  }
  return Status();
}

Status createCanopy(Device* device, const std::vector<CanopySpecies>& species, const CanopyDesc& desc, CanopyContext** out) {
  return guardApi("createCanopy", [&]() -> Status {
    if (out) *out = nullptr;
    if (!device) return Status::error("createCanopy: device is required");
    std::vector<SpeciesModel> models;
    CANOPY_TRY(speciesModels("createCanopy", species, &models));
    return createCanopy(*device, models, desc, out);
  });
}

void destroyCanopy(CanopyContext* c) {
  if (!c) return;
  // Frames in flight may still read the context's objects: free them when those frames are done.
  // Queueing can only fail for host memory; the objects are then left alive (a leak) rather than
  // freed under frames that may still read them.
  try {
    deferRelease(*c->device, [c] { destroyNow(c); });
  } catch (...) {
  }
}

Status setCanopyParams(CanopyContext* c, const CanopyParams& p) {
  return guardApi("setCanopyParams", [&]() -> Status {
    if (!c) return Status::error("setCanopyParams: null context");
    CANOPY_TRY(validateParams(*c, p));
    if (!(p.layers == c->params.layers)) {
      bool recreated = false;
      CANOPY_TRY(setLayerSettings(c->layers, p.layers, &recreated));
      if (recreated) c->generation++;  // new layer images
    }
    if (p.animation != c->params.animation) {
      c->generation++;  // other passes: graphs are rebuilt
      if (p.animation == AnimationMode::Layers2D) {
        // Back to the layers: they are as old as the last 2D frame; re-slice at once, and no
        // motion vectors against a displacement from before the switch.
        requestReslice(c->layers.reslice, "animation mode", true);
        c->previousAnimFrame = gpu::AnimFrame{};
      } else {
        // To the baseline: its last frame's camera and time are from before the switch, so its
        // first frame carries no motion (as after a camera cut).
        c->perVertex.frames = 0;
      }
    }
    if (p.customPlane) {
      c->plane = p.plane;
      c->planeChosen = true;
    } else if (c->params.customPlane) {
      c->planeChosen = false;  // back to the default: taken from the next frame's camera
    }
    c->params = p;
    return Status();
  });
}

const CanopyParams& canopyParams(const CanopyContext* c) { return c->params; }

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
    if (width == c->desc.width && height == c->desc.height) return Status();
    Device& d = *c->device;
    const CompositorDesc before = c->compositor.desc;
    retireSizeDependentParts(*c);  // no wait: the old objects go once the frames using them completed
    c->desc.width = width;
    c->desc.height = height;
    c->perVertex.desc.width = width;
    c->perVertex.desc.height = height;
    Status s = [&]() -> Status {
      CompositorDesc cd = before;
      cd.width = width;
      cd.height = height;
      cd.guardX = guardPixels(c->desc.guardBand, width);
      cd.guardY = guardPixels(c->desc.guardBand, height);
      CANOPY_TRY(setLayerTargetSize(c->layers, compositorLayerWidth(cd), compositorLayerHeight(cd), cd.guardX, cd.guardY));
      CANOPY_TRY(createCompositor(d, cd, &c->compositor));
      // The warp grid's corners are in pixels: a new grid, and no previous displacement to take
      // motion vectors against (beginCanopyFrame sees the grid change).
      c->previousAnimFrame = gpu::AnimFrame{};
      return createLayerDynamics(d, compositorLayerWidth(cd), compositorLayerHeight(cd), c->desc.minCellSize, c->desc.maxLayers,
                                 &c->dynamics);
    }();
    c->generation++;
    return s.context("resizeCanopy to " + std::to_string(width) + "x" + std::to_string(height));
  });
}

// docs/design.md "World wind": the wind's own plane, fixed in the world (no camera chooses it);
// PlaneSides: unless the host set one, the plane of the first view, one tile over the region
// visible at the vegetation's centre depth.
static void chooseSimulationPlane(CanopyContext& c, const LayerView& view) {
  if (c.params.windMode == WindMode::World) {
    c.plane = worldWindPlane(c.params.wind, c.worldWind.direction, c.layers.instances.boundsMin, c.layers.instances.boundsMax);
    return;
  }
  if (c.planeChosen) return;
  if (c.params.customPlane) {  // CanopyDesc.params' plane (setCanopyParams sets it as it is given)
    c.plane = c.params.plane;
    c.planeChosen = true;
    return;
  }
  const LayerInstances& lv = c.layers.instances;  // the world bounds of every copy
  const glm::vec3 centre = 0.5f * (lv.boundsMin + lv.boundsMax);
  const float depth = glm::dot(centre - viewPosition(view.view), viewForward(view.view));
  const float radius = 0.5f * glm::length(lv.boundsMax - lv.boundsMin);
  c.plane = simulationPlaneFromView(view, std::max(depth, std::max(radius, 1e-3f)));
  c.planeChosen = true;
}

Status beginCanopyFrame(CanopyContext* c, const CanopyFrame& f) {
  if (!c) return Status::error("beginCanopyFrame: null context");
  if (!std::isfinite(f.dt) || f.dt < 0.0f || f.dt > 10.0f)
    return Status::error("CanopyFrame.dt = " + std::to_string(f.dt) + " s is outside [0, 10]");
  // Everything downstream inverts these (eye position, slab planes, the simulation plane).
  for (const auto& [name, m] : {std::pair<const char*, const Float4x4*>{"view", &f.camera.view}, {"proj", &f.camera.proj}}) {
    const glm::mat4 g = toGlm(*m);
    for (int i = 0; i < 16; ++i)
      if (!std::isfinite(m->m[i])) return Status::error(std::string("CanopyFrame.camera.") + name + " has a non-finite element");
    const float det = glm::determinant(g);
    if (!std::isfinite(det) || std::abs(det) < 1e-30f)
      return Status::error(std::string("CanopyFrame.camera.") + name + " is singular (determinant " + std::to_string(det) + ")");
  }
  Device& d = *c->device;
  // 0: the next frame (one context per host frame); otherwise the host's own counter.
  const uint64_t frameNumber = f.frameNumber ? f.frameNumber : (d.anyFrame ? d.frameNumber + 1 : 1);
  CANOPY_TRY(beginDeviceFrame(d, frameNumber));
  stepWorldWind(c->worldWind, c->params.wind, f.dt);
  chooseSimulationPlane(*c, standardView(*c, f.camera));  // before the step: the pushers are mapped through it
  // The simulation's inflow: the world wind as it stands (World), or the host's sides (PlaneSides).
  CanopyParams stepParams = c->params;
  if (c->params.windMode == WindMode::World) {
    stepParams.simulation = worldWindSimulation(c->params.simulation, c->params.wind, c->plane, c->worldWind.speed);
    // The baseline's reference speed in m/s on this tile: it bends by m/s, whatever the tile.
    stepParams.perVertex.referenceSpeed = c->params.perVertex.worldReferenceSpeed * c->params.wind.unitsPerMetre / c->plane.tileSize;
  }
  if (c->params.animation == AnimationMode::PerVertex) {
    // The baseline: no simulation step, no re-slice, no dynamics or composite; the wind's
    // direction comes from the simulation plane, as the 2D method's.
    CANOPY_TRY(preparePerVertex(c->perVertex, c->layers, stepParams, c->plane, f.camera, f.dt, f.cameraCut));
    c->layersRebuilt = false;
    c->frames++;
    return Status();
  }
  SharedSimulation& sh = *c->shared;
  Simulation& sim = sh.sim;
  const LayerView view = standardView(*c, f.camera);
  // One step per host frame for a shared simulation, by the first context recorded in it.
  const bool stepHere = !sh.everStepped || sh.lastStepFrame != frameNumber;
  c->skipSimulationStep = !stepHere || f.dt == 0.0f;
  sim.paused = c->skipSimulationStep;
  if (stepHere) {
    sh.everStepped = true;
    sh.lastStepFrame = frameNumber;
    if (f.dt > 0.0f) {
      mapPushers(c->pushers, c->plane, view, &sim.pushers, &c->pusherCounts);
      CANOPY_TRY(prepareSimulationStep(sim, stepParams.simulation, f.dt));
      // The step's readback slot maps by this frame's plane (sampleCanopyWind).
      sim.windSlots[sim.windSlotNext].frame = frameNumber;
      sim.windSlots[sim.windSlotNext].plane = c->plane;
    }
  }
  if (f.cameraCut) requestReslice(c->layers.reslice, "camera cut", true);
  bool rebuild = false;
  CANOPY_TRY(updateLayerView(c->layers, view, &rebuild));
  // The dynamics run in the slice camera's pixels, where the layers and their warp grid are
  // (docs/design.md "Layers: reprojection"); the composite maps the current camera into them.
  const LayerView& slice = c->layers.visible.view;
  DynamicsFrameDesc fd;
  fd.view = slice;
  fd.plane = c->plane;
  for (const LayerInfo& l : c->layers.visible.layers) fd.layers.push_back({l.slab.depth, l.slab.distance, l.rootLineY, l.height, l.plants, l.plantResponse, l.plantHeight});
  fd.width = c->layers.desc.width;  // the layer images: the output and the guard band
  fd.height = c->layers.desc.height;
  fd.simSize = sim.n;
  fd.ringSize = sim.ringSize;
  fd.time = float(sim.time);
  fd.nominalDt = sim.nominalDt;
  fd.waveSpeed = c->params.simulation.wave.speed;
  // The simulation writes slot step % H: the exact delay can binary-search the ring (anim_displace.comp).
  // Before the first step every slot reads time 0, which is in order from any slot.
  fd.halfResolution = c->layers.visible.frame.halfResolution;
  fd.bend = sim.bendUsed;
  const BendPlane bp = bendPlaneOf(c->plane);
  c->pusherHeight = pusherHeight(c->pushers, c->pusherHeight);
  fd.bendOrigin = glm::vec4(bp.origin.x, c->pusherHeight, bp.origin.z, bp.tile);
  fd.bendX = glm::vec4(bp.x, 0.0f);
  fd.bendZ = glm::vec4(bp.z, 0.0f);
  fd.newestSlot = sim.stats.steps > 0 ? uint32_t((sim.stats.steps - 1) % sim.ringSize) : 0u;
  if (c->params.windMode == WindMode::World) {
    fd.heightSway = c->params.wind.sway;
    fd.unitsPerMetre = c->params.wind.unitsPerMetre;
  }
  CANOPY_TRY(makeAnimFrame(stepParams.dynamics, fd, &c->dynamics.current, &c->dynamics.plantRects));
  const gpu::AnimFrame& a = c->dynamics.current;
  const bool motionValid = c->frames > 0 && !f.cameraCut && a.gridX == c->previousAnimFrame.gridX && a.gridY == c->previousAnimFrame.gridY &&
                           a.layerCount == c->previousAnimFrame.layerCount;
  const VkRect2D footprint = layerFootprint(c->layers);
  CANOPY_TRY(prepareComposite(c->compositor, c->params.composite, a, c->layers.mesh.hasRigid, c->layers.reslice.occupancyDirty,
                              motionValid, &footprint, c->layers.reslice.occupancyUniteNext));
  const LayerView& previous = motionValid ? c->lastView : view;
  // The slice camera is the guard band's widening of the camera it was asked for: the same camera
  // as this frame's when that widening gives it bit for bit (layer pixel = pixel + guard).
  if (!sameCamera(slice, sliceCameraFor(c->layers, view)) || !sameCamera(previous, view)) {
    std::vector<float> depths;
    std::vector<LayerSearch> search;
    // A range of vertex depths widened by 2 % (impostor cards, rounding).
    auto widened = [](float lo, float hi) {
      const float pad = 0.02f * std::max(hi - lo, 0.0f) + 1e-4f * std::max(std::abs(hi), 1.0f);
      return LayerSearch{std::max(lo - pad, 1e-6f), hi + pad};
    };
    for (const LayerInfo& l : c->layers.visible.layers) {
      depths.push_back(l.slab.depth);
      // The leaf vertices' depths; a layer without leaves searches its slab.
      search.push_back(std::isfinite(l.drawnNear) ? widened(l.drawnNear, l.drawnFar) : widened(l.slab.zNear, l.slab.zFar));
    }
    const glm::vec2 rigid = c->layers.visible.rigidDepth;
    const LayerSearch backgroundSearch = std::isfinite(rigid.x) ? widened(rigid.x, rigid.y) : LayerSearch{};
    // The rigid background's plane: the vegetation's centre.
    const glm::vec3 centre = 0.5f * (c->layers.instances.boundsMin + c->layers.instances.boundsMax);
    const float backgroundDepth = glm::dot(centre - viewPosition(slice.view), viewForward(slice.view));
    const gpu::CompositeView cv =
        compositeView(slice, view, previous, depths, backgroundDepth, glm::dvec2(c->desc.width, c->desc.height),
                      glm::dvec2(c->layers.desc.width, c->layers.desc.height), search, c->params.composite.depthSearchSteps, backgroundSearch);
    setCompositeReprojection(c->compositor, &cv);
  }
  c->lastView = view;
  c->previousAnimFrame = a;
  c->layersRebuilt = rebuild;
  c->frames++;
  return Status();
}

Status addCanopyPasses(CanopyContext* c, rg::RenderGraph& g, const CompositeTargets& targets) {
  if (!c) return Status::error("addCanopyPasses: null context");
  if (!c->perVertexUploads.empty() || !c->shared->firstClear.empty() || layerWorkPending(c->layers))
    return Status::error("addCanopyPasses: this context has uploads waiting for recordCanopy (a device that defers "
                         "uploads is embedded through recordCanopy only)");
  return declarePasses(*c, g, targets);
}

Status requestCanopyRebuild(CanopyContext* c, bool immediate) {
  return guardApi("requestCanopyRebuild", [&]() -> Status {
    if (!c) return Status::error("requestCanopyRebuild: null context");
    requestReslice(c->layers.reslice, immediate ? "requested at once" : "requested", immediate);
    return Status();
  });
}

uint64_t canopyResourceGeneration(const CanopyContext* c) { return c ? c->generation : 0; }

Status recordCanopy(CanopyContext* c, VkCommandBuffer cmd, const CanopyFrameInputs& in) {
  return guardApi("recordCanopy", [&]() -> Status {
    if (!c) return Status::error("recordCanopy: null context");
    if (!cmd) return Status::error("recordCanopy: null command buffer");
    // The graph compiled for these images; images not seen before are checked before anything is
    // recorded or stepped (beginCanopyFrame changes no graph).
    RecordGraph* graph = findRecordGraph(*c, in);
    if (!graph) CANOPY_TRY(checkFrameInputs(c->desc, in));
    CANOPY_TRY(beginCanopyFrame(c, in.frame));
    // Uploads and clears prepared since the last frame, before anything reads them.
    CANOPY_TRY(flushPreparedWork(*c->device, c->shared->firstClear, cmd));
    CANOPY_TRY(flushLayerWork(c->layers, cmd));
    CANOPY_TRY(flushPreparedWork(*c->device, c->perVertexUploads, cmd));
    if (!graph) CANOPY_TRY(buildRecordGraph(*c, in, &graph));
    graph->lastUse = ++c->recordGraphUses;
    return graph->graph->record(cmd);
  });
}

Status recordCanopyShadow(CanopyContext* c, VkCommandBuffer cmd, const CanopyShadowInputs& in, bool* updated) {
  return guardApi("recordCanopyShadow", [&]() -> Status {
    if (updated) *updated = false;
    if (!c) return Status::error("recordCanopyShadow: null context");
    if (!cmd) return Status::error("recordCanopyShadow: null command buffer");
    CANOPY_TRY(checkShadowInputs(in));
    if (c->frames == 0)
      return Status::error(Result::InvalidArgument, "recordCanopyShadow: record a frame first (recordCanopy): the shadow follows "
                                                    "that frame's layers and wind");
    ShadowSources src;
    src.layers = &c->layers;
    src.dynamics = &c->dynamics;
    src.displaced = c->params.animation == AnimationMode::Layers2D;
    src.generation = c->generation;
    return recordShadow(c->shadow, src, cmd, in, updated);
  });
}

namespace {
// The load frame's own targets (recordCanopyLoad): the host's formats and size, contents never read
// by anyone; freed once the frames after it are done.
struct LoadTargets {
  Image color, depth, motion;
  VkImageView depthOnly = VK_NULL_HANDLE;
};
void destroyLoadTargets(Device& d, LoadTargets& t) {
  if (t.depthOnly) d.vk.DestroyImageView(d.device, t.depthOnly, d.allocationCallbacks);
  destroyImage(d, t.color);
  destroyImage(d, t.depth);
  destroyImage(d, t.motion);
  t = LoadTargets{};
}
Status createLoadTargets(Device& d, const CanopyDesc& desc, LoadTargets* t) {
  ImageDesc i;
  i.width = desc.width;
  i.height = desc.height;
  i.format = desc.colorFormat;
  i.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  CANOPY_TRY(createImage(d, i, &t->color, "load frame: colour"));
  i.format = desc.depthFormat;
  i.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
  CANOPY_TRY(createImage(d, i, &t->depth, "load frame: depth"));
  VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vi.image = t->depth.image;
  vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
  vi.format = desc.depthFormat;
  vi.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
  CANOPY_VK(d.vk.CreateImageView(d.device, &vi, d.allocationCallbacks, &t->depthOnly));
  if (desc.motionFormat != VK_FORMAT_UNDEFINED) {
    i.format = desc.motionFormat;
    i.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
    CANOPY_TRY(createImage(d, i, &t->motion, "load frame: motion"));
  }
  return Status();
}
}  // namespace

Status recordCanopyLoad(CanopyContext* c, VkCommandBuffer cmd, const CanopyCamera& camera) {
  return guardApi("recordCanopyLoad", [&]() -> Status {
    if (!c) return Status::error("recordCanopyLoad: null context");
    if (!cmd) return Status::error("recordCanopyLoad: null command buffer");
    Device& d = *c->device;
    // A whole frame at `camera` with the simulation held (dt 0), into targets of its own: the
    // uploads, the first re-slice, the composite's occupancy and every pass's first use happen
    // here, and the first frame of play at that camera finds the layers current.
    auto targets = std::make_shared<LoadTargets>();
    Status s = createLoadTargets(d, c->desc, targets.get());
    if (s.ok()) {
      const ResourceState none{};
      CanopyFrameInputs in;
      in.frame.camera = camera;
      in.frame.dt = 1.0f / 30.0f;
      in.frame.frameNumber = d.anyFrame ? d.frameNumber : 0;
      in.color = canopyImage(targets->color.image, targets->color.view, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, c->desc.colorFormat, none,
                             {VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                              VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL});
      in.depth = canopyImage(targets->depth.image, targets->depthOnly,
                             VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, c->desc.depthFormat, none,
                             {VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                              VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL});
      if (targets->motion.image)
        in.motion = canopyImage(targets->motion.image, targets->motion.view, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, c->desc.motionFormat,
                                none, {VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                                       VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL});
      // The load is no host frame: the first frame of play steps the simulation whatever its number.
      SharedSimulation& sh = *c->shared;
      const bool everStepped = sh.everStepped;
      const uint64_t lastStep = sh.lastStepFrame;
      s = recordCanopy(c, cmd, in);
      sh.everStepped = everStepped;
      sh.lastStepFrame = lastStep;
      // Its graph names these targets only: retired with them, never found for a host's images.
      std::vector<RecordGraph> keep, drop;
      for (RecordGraph& g : c->recordGraphs) (g.inputs.color.image == targets->color.image ? drop : keep).push_back(std::move(g));
      c->recordGraphs = std::move(keep);
      retireRecordGraphs(*c, std::move(drop));
    }
    Device* dev = &d;
    deferRelease(d, [dev, targets] { destroyLoadTargets(*dev, *targets); });
    return s;
  });
}

Status canopyPassGroupUses(const CanopyContext* c, std::vector<CanopyTargetUse>* uses) {
  return guardApi("canopyPassGroupUses", [&]() -> Status {
    if (!c || !uses) return Status::error("canopyPassGroupUses: null context or output");
    *uses = c->groupUses;
    return Status();
  });
}

Status recordCanopyPassGroup(CanopyContext* c, VkCommandBuffer cmd, const CanopyFrameInputs& inputs) {
  if (!c) return Status::error("recordCanopyPassGroup: null context");
  // The host's graph has put each image in its declared use: Canopy's first barrier on it chains
  // from those stages (a layout change inside the group), and no closing barrier is recorded.
  CanopyFrameInputs in = inputs;
  for (const CanopyTargetUse& u : c->groupUses) {
    CanopyImage& img = u.target == CanopyTarget::Color ? in.color : u.target == CanopyTarget::Depth ? in.depth : in.motion;
    img.current = {u.state.stage, VK_ACCESS_2_NONE, u.state.layout};
    img.final = {VK_PIPELINE_STAGE_2_NONE, VK_ACCESS_2_NONE, u.state.layout};
  }
  return recordCanopy(c, cmd, in).context("recordCanopyPassGroup");
}

CanopyStats canopyStats(const CanopyContext* c) {
  CanopyStats s;
  if (!c) return s;
  s.frames = c->frames;
  s.layersRebuilt = c->layersRebuilt;
  s.resourceGeneration = c->generation;
  s.shadowUpdates = c->shadow.updates;
  s.shadowSkips = c->shadow.skips;
  s.pushersMapped = c->pusherCounts.mapped;
  s.pushersOutside = c->pusherCounts.outside;
  s.pushersBehind = c->pusherCounts.behind;
  s.internalGraphBuilds = c->recordGraphBuilds;
  s.pendingReleases = c->device->pendingReleases.size();
  s.deviceBytes = c->device->allocator->liveBytes;
  s.peakDeviceBytes = c->device->allocator->peakLiveBytes;
  s.deviceBlockBytes = c->device->allocator->blockBytes;
  s.layers = c->layers.stats;
  s.layers.layerWidth = c->layers.desc.width;
  s.layers.layerHeight = c->layers.desc.height;
  s.layers.guardX = c->layers.desc.guardX;
  s.layers.guardY = c->layers.desc.guardY;
  s.layers.instances = uint32_t(c->layers.instances.models.size());
  s.simulation = c->shared->sim.stats;
  return s;
}

Status setCanopyPushers(CanopyContext* c, const std::vector<CanopyPusher>& pushers) {
  return guardApi("setCanopyPushers", [&]() -> Status {
    if (!c) return Status::error(Result::InvalidArgument, "setCanopyPushers: null context");
    CANOPY_TRY(checkPushers(pushers));
    c->pushers = pushers;
    return Status();
  });
}

// The mapping the wind is read through: the context's plane (canopy_wind.glsl's CanopyWindInfo).
static CanopyWindInfo windInfo(const SimulationPlane& p, uint32_t n) {
  const glm::vec3 normal = glm::cross(toGlm(p.right), toGlm(p.up));
  return CanopyWindInfo{{p.origin.x, p.origin.y, p.origin.z, p.tileSize},
                        {p.right.x, p.right.y, p.right.z, float(n)},
                        {p.up.x, p.up.y, p.up.z, 0.0f},
                        {normal.x, normal.y, normal.z, 0.0f}};
}

Status canopyWind(const CanopyContext* c, CanopyWind* out) {
  return guardApi("canopyWind", [&]() -> Status {
    if (!c || !out) return Status::error(Result::InvalidArgument, "canopyWind: context and out are required");
    const Simulation& sim = c->shared->sim;
    *out = CanopyWind{};
    out->image = sim.windImage.image;
    out->view = sim.windImage.view;
    out->format = kWindImageFormat;
    out->size = sim.n;
    const rg::State rest = windImageRest();
    out->state = ResourceState{rest.stage, rest.access, rest.layout};
    // Before the first frame chose it, the plane the host gave or a placeholder (the field is zero).
    out->info = windInfo(c->plane, sim.n);
    return Status();
  });
}

Status sampleCanopyWind(const CanopyContext* c, const Float3* points, size_t count, Float3* out, uint64_t* fieldFrame) {
  return guardApi("sampleCanopyWind", [&]() -> Status {
    if (fieldFrame) *fieldFrame = 0;
    if (!c) return Status::error(Result::InvalidArgument, "sampleCanopyWind: null context");
    if (count > 0 && (!points || !out)) return Status::error(Result::InvalidArgument, "sampleCanopyWind: points and out are required");
    const Simulation& sim = c->shared->sim;
    const Device& d = *c->device;
    // Frames at most frameNumber - framesInFlight have completed (CanopyFrame.frameNumber).
    const uint64_t completed = d.frameNumber >= d.framesInFlight ? d.frameNumber - d.framesInFlight : 0;
    uint32_t slot = 0;
    const WindSlot* w = d.anyFrame ? completedWindSlot(sim, completed, &slot) : nullptr;
    const float* field = w ? static_cast<const float*>(sim.windReadback.allocation.mapped) : nullptr;
    for (size_t i = 0; i < count; ++i) {
      if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y) || !std::isfinite(points[i].z))
        return Status::error(Result::InvalidArgument, "sampleCanopyWind: points[" + std::to_string(i) + "] is not finite");
      out[i] = field ? toFloat3(windAtWorld(field + size_t(slot) * 2 * sim.n * sim.n, sim.n, w->plane, toGlm(points[i]))) : Float3{};
    }
    if (fieldFrame && field) *fieldFrame = w->frame;
    return Status();
  });
}

LayeredVegetation& canopyLayers(CanopyContext* c) { return c->layers; }
LayerDynamics& canopyDynamics(CanopyContext* c) { return c->dynamics; }
Simulation& canopySimulation(CanopyContext* c) { return c->shared->sim; }
Compositor& canopyCompositor(CanopyContext* c) { return c->compositor; }

}  // namespace canopy
