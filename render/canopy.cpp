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

void destroyNow(CanopyContext* c) {
  if (c->device) {
    dropPreparedWork(*c->device, c->perVertexUploads);
    for (RecordGraph& g : c->recordGraphs) g.graph->release(*c->device);
    destroyCompositor(c->compositor);
    destroyShadowCaster(c->shadow);
    destroyPerVertex(c->perVertex);
    destroyRigidFollow(c->rigid);
    destroyLayerDynamics(c->dynamics);
    destroyLayeredVegetation(c->layers);
  }
  c->shared.reset();  // the simulation goes with the last context that follows it
  delete c;
}

// Canopy's passes in `g`, around the host's imported images (one declaration for recordCanopy, the
// render-graph path and canopyPassGroupUses).
Status declarePasses(CanopyContext& ctx, rg::RenderGraph& g, const CompositeTargets& hostTargets) {
  CanopyContext* c = &ctx;
  CompositeTargets targets = hostTargets;
  targets.scissor = &c->host.scissor;  // this frame's viewport, read as each pass records
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
  // The rigid parts with the foliage they carry, into the host's targets before the composite
  // reads its depth (docs/design.md "Rigid parts in wind").
  if (rigidFollows(c->layers) && c->rigid.device)
    CANOPY_TRY(addRigidFollowPasses(c->rigid, c->layers, g, targets, {&lr, animFrame, disp, prev, &c->dynamics}));
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
    c->compositorDesc = cd;
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
    c->layers.mesh.woodApart = c->params.composite.debugView == CompositeDebugView::Layers;
    CANOPY_TRY(validateParams(*c, c->params));  // against the instances too (the per-vertex baseline)
    if (desc.allowPerVertex)
      CANOPY_TRY(createPerVertex(d, c->layers, c->layers.mesh.branches, c->compositor.desc, &c->perVertex, &c->perVertexUploads));
    CANOPY_TRY(makeRigidFollow(*c));
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
    // The rigid parts drawn every frame or into the background: another pass in the graphs.
    if (p.layers.rigidMotion != c->params.layers.rigidMotion) c->generation++;
    // The Layers debug view keeps the wood out of the layers (LayerMesh::woodApart): re-slice at once.
    const bool woodApart = p.composite.debugView == CompositeDebugView::Layers;
    if (woodApart != c->layers.mesh.woodApart) {
      c->layers.mesh.woodApart = woodApart;
      c->generation++;
      requestReslice(c->layers.reslice, "debug view", true);
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
  if (!c->sized)
    return Status::error(Result::InvalidArgument, "the last resizeCanopy failed: call resizeCanopy again (the same size is "
                                                  "enough) before recording a frame");
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
  // The viewport and a GL clip depth folded into the projection, the jitter kept apart.
  HostCamera hc;
  CANOPY_TRY(hostCamera(f.camera, c->desc.width, c->desc.height, &hc));
  Device& d = *c->device;
  // 0: the next frame (one context per host frame); otherwise the host's own counter.
  const uint64_t frameNumber = f.frameNumber ? f.frameNumber : (d.anyFrame ? d.frameNumber + 1 : 1);
  CANOPY_TRY(beginDeviceFrame(d, frameNumber));
  stepWorldWind(c->worldWind, c->params.wind, f.dt);
  c->host = hc;
  chooseSimulationPlane(*c, standardView(*c, hc.inViewport));  // before the step: the pushers are mapped through it
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
    CANOPY_TRY(preparePerVertex(c->perVertex, c->layers, stepParams, c->plane, hc.camera, hc.jitter, f.dt, f.cameraCut));
    c->layersRebuilt = false;
    c->frames++;
    return Status();
  }
  SharedSimulation& sh = *c->shared;
  Simulation& sim = sh.sim;
  const LayerView view = standardView(*c, hc.camera);  // unjittered: the re-slice policy's camera
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
  for (const LayerInfo& l : c->layers.visible.layers)
    fd.layers.push_back({l.slab.depth, l.slab.distance, l.rootLineY, l.height, l.plants, l.plantResponse, l.plantHeight, l.plantDepth, l.plantWoodOnly});
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
  CANOPY_TRY(prepareComposite(c->compositor, c->params.composite, a, drawsBackground(c->layers), c->layers.reslice.occupancyDirty,
                              motionValid, &footprint, c->layers.reslice.occupancyUniteNext));
  if (rigidFollows(c->layers) && c->rigid.device)
    CANOPY_TRY(prepareRigidFollow(c->rigid, c->layers, hc.camera, hc.jitter, c->params.composite.exposure, motionValid));
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
    // Sampled at the jittered position; the previous camera jittered alike, so the motion
    // vectors (current minus previous) carry no jitter.
    const LayerView jittered{view.view, hc.jitter * view.proj}, previousJittered{previous.view, hc.jitter * previous.proj};
    const gpu::CompositeView cv =
        compositeView(slice, jittered, previousJittered, depths, backgroundDepth, glm::dvec2(c->desc.width, c->desc.height),
                      glm::dvec2(c->layers.desc.width, c->layers.desc.height), search, c->params.composite.depthSearchSteps, backgroundSearch);
    setCompositeReprojection(c->compositor, &cv);
  } else {
    // The slice camera's own pixels, read at the jittered position: layer pixel = p + guard - jitter.
    c->compositor.push.originX -= hc.jitterPixels.x;
    c->compositor.push.originY -= hc.jitterPixels.y;
  }
  c->lastView = view;
  c->previousAnimFrame = a;
  c->layersRebuilt = rebuild;
  c->frames++;
  return Status();
}

Status addCanopyPasses(CanopyContext* c, rg::RenderGraph& g, const CompositeTargets& targets) {
  if (!c) return Status::error("addCanopyPasses: null context");
  if (!c->sized) return Status::error(Result::InvalidArgument, "addCanopyPasses: the last resizeCanopy failed: call it again first");
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
    if (!c->sized) return Status::error(Result::InvalidArgument, "recordCanopyShadow: the last resizeCanopy failed: call it again first");
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

}  // namespace canopy
