#include "render/canopy.h"

#include <cmath>
#include <string>

#include "engine/memory.h"

namespace canopy {

struct CanopyContext {
  Device* device = nullptr;
  CanopyDesc desc;
  CanopyParams params;
  LayeredVegetation layers;
  Simulation simulation;
  LayerDynamics dynamics;
  Compositor compositor;
  bool planeFixed = false;
  SimulationPlane plane;
  uint64_t generation = 0;
  uint64_t frames = 0;
  bool layersRebuilt = false;
  gpu::AnimFrame last{};  // the previous frame's dynamics constants (motion-vector validity)
  // recordCanopy(): the graph holding the host's images, and what it was built for.
  rg::RenderGraph graph;
  bool graphReady = false;
  CanopyFrameInputs graphInputs;
  uint64_t graphGeneration = 0;
  uint64_t graphBuilds = 0;
};

namespace {

Status checkRange(const char* name, uint32_t v, uint32_t lo, uint32_t hi) {
  if (v < lo || v > hi)
    return Status::error(std::string(name) + " = " + std::to_string(v) + " is outside [" + std::to_string(lo) + ", " +
                         std::to_string(hi) + "]");
  return Status();
}

Status validatePlane(const SimulationPlane& p) {
  const bool finite = std::isfinite(p.tileSize) && std::isfinite(glm::dot(p.origin, p.origin)) &&
                      std::isfinite(glm::dot(p.right, p.right)) && std::isfinite(glm::dot(p.up, p.up));
  if (!finite || !(p.tileSize > 0.0f)) return Status::error("CanopyParams.plane: tileSize must be > 0 and every field finite");
  if (std::abs(glm::length(p.right) - 1.0f) > 1e-3f || std::abs(glm::length(p.up) - 1.0f) > 1e-3f ||
      std::abs(glm::dot(p.right, p.up)) > 1e-3f)
    return Status::error("CanopyParams.plane: right and up must be orthogonal unit vectors");
  return Status();
}

Status validateParams(const CanopyContext& c, const CanopyParams& p) {
  CANOPY_TRY(validateLayerSettings(p.layers));
  if (p.layers.layout.count() > c.desc.maxLayers)
    return Status::error("CanopyParams.layers.layout " + toString(p.layers.layout) + " has " +
                         std::to_string(p.layers.layout.count()) + " layers; CanopyDesc.maxLayers is " +
                         std::to_string(c.desc.maxLayers));
  CANOPY_TRY(validateSimulationParams(p.simulation, c.desc.simulation.nominalDt));
  CANOPY_TRY(validateDynamicsParams(p.dynamics));
  if (p.dynamics.cellSize < c.desc.minCellSize)
    return Status::error("CanopyParams.dynamics.cellSize = " + std::to_string(p.dynamics.cellSize) +
                         " is below CanopyDesc.minCellSize = " + std::to_string(c.desc.minCellSize));
  CANOPY_TRY(validateCompositeParams(p.composite));
  if (p.customPlane) CANOPY_TRY(validatePlane(p.plane));
  return Status();
}

bool sameState(const rg::State& a, const rg::State& b) {
  return a.stage == b.stage && a.access == b.access && a.layout == b.layout;
}
bool sameImage(const CanopyImage& a, const CanopyImage& b) {
  return a.image == b.image && a.view == b.view && sameState(a.current, b.current) && sameState(a.final, b.final);
}

Image hostImage(const CanopyImage& h, VkFormat format, uint32_t width, uint32_t height) {
  Image img;
  img.image = h.image;
  img.view = h.view;
  img.format = format;
  img.extent = {width, height, 1};
  img.aspect = aspectOf(format);
  return img;
}

Status buildRecordGraph(CanopyContext& c, const CanopyFrameInputs& in) {
  const bool motion = c.desc.motionFormat != VK_FORMAT_UNDEFINED;
  if (!in.color.image || !in.color.view || !in.depth.image || !in.depth.view)
    return Status::error("recordCanopy: the colour and depth images and views are required");
  if (motion != (in.motion.image != VK_NULL_HANDLE) || (motion && !in.motion.view))
    return Status::error(motion ? "recordCanopy: CanopyDesc.motionFormat is set but no motion image (and view) was given"
                                : "recordCanopy: a motion image was given but CanopyDesc.motionFormat is UNDEFINED");
  if (c.graphReady) c.graph.release(*c.device);
  c.graph = rg::RenderGraph();
  c.graphReady = false;
  const uint32_t w = c.desc.width, h = c.desc.height;
  auto import = [&](const char* name, const CanopyImage& img, VkFormat format, rg::ResourceId* id) -> Status {
    ImageDesc d;
    d.format = format;
    d.width = w;
    d.height = h;
    *id = c.graph.importImage(name, d, img.current, img.final);
    return c.graph.bindImage(*id, hostImage(img, format, w, h));
  };
  CompositeTargets t;
  CANOPY_TRY(import("host: colour", in.color, c.desc.colorFormat, &t.color));
  CANOPY_TRY(import("host: depth", in.depth, c.desc.depthFormat, &t.depth));
  if (motion) CANOPY_TRY(import("host: motion", in.motion, c.desc.motionFormat, &t.motion));
  CANOPY_TRY(addCanopyPasses(&c, c.graph, t));
  CANOPY_TRY(c.graph.compile());
  CANOPY_TRY(c.graph.realize(*c.device));
  c.graphReady = true;
  c.graphInputs = in;
  c.graphGeneration = c.generation;
  c.graphBuilds++;
  return Status();
}

}  // namespace

Status createCanopy(Device& d, const VegetationModel& model, const CanopyDesc& desc, CanopyContext** out) {
  if (!out) return Status::error("createCanopy: out is null");
  *out = nullptr;
  CANOPY_TRY(checkRange("CanopyDesc.width", desc.width, 1, 16384));
  CANOPY_TRY(checkRange("CanopyDesc.height", desc.height, 1, 16384));
  CANOPY_TRY(checkRange("CanopyDesc.maxLayers", desc.maxLayers, 1, CANOPY_MAX_LAYERS));
  CANOPY_TRY(checkRange("CanopyDesc.minCellSize", desc.minCellSize, 2, 256));
  // Nothing to animate is a mistake in the input (a glTF whose scene reaches no triangle mesh),
  // not an empty frame to draw silently.
  const std::string what = model.path.empty() ? std::string("the model") : "'" + model.path + "'";
  if (model.triangleCount() == 0)
    return Status::error("createCanopy: " + what + " has no triangles (no TRIANGLES mesh primitive is reachable from its scene)");
  auto* c = new CanopyContext();
  c->device = &d;
  c->desc = desc;
  c->params.dynamics.cellSize = std::max(c->params.dynamics.cellSize, desc.minCellSize);
  Status s = [&]() -> Status {
    CANOPY_TRY(validateParams(*c, c->params));
    CompositorDesc cd;
    cd.width = desc.width;
    cd.height = desc.height;
    cd.colorFormat = desc.colorFormat;
    cd.depthFormat = desc.depthFormat;
    cd.motionFormat = desc.motionFormat;
    cd.maxLayers = desc.maxLayers;
    CANOPY_TRY(createCompositor(d, cd, &c->compositor));
    LayeredVegetationDesc ld;
    ld.width = desc.width;
    ld.height = desc.height;
    ld.colorFormat = desc.layerFormat;
    ld.split = desc.split;
    ld.roots = desc.roots;
    ld.useRootCache = desc.useRootCache;
    ld.rootCacheDir = desc.rootCacheDir;
    ld.progress = desc.progress;
    ld.restUse = rg::Use::FragmentSampled;
    ld.settings = c->params.layers;
    // The split is cheap; knowing there is nothing to animate before leaf roots and the mesh
    // upload saves a big model's preparation.
    MaterialSplit split;
    CANOPY_TRY(splitMaterials(model, desc.split, &split));
    if (split.foliageTriangles == 0) {
      std::string names;
      for (size_t i = 0; i < model.materials.size(); ++i) {  // appends: GCC 12's -Wrestrict misfires on "#" + ...
        names += i ? ", #" : "#";
        names += std::to_string(i);
        names += " '";
        names += model.materials[i].name;
        names += "'";
      }
      return Status::error(what + " has no foliage: every material is rigid (" + names +
                           "); name the leaf materials in CanopyDesc.split.foliage");
    }
    CANOPY_TRY(createLayeredVegetation(d, model, ld, &c->layers));
    CANOPY_TRY(createSimulation(d, desc.simulation, &c->simulation));
    CANOPY_TRY(createLayerDynamics(d, desc.width, desc.height, desc.minCellSize, desc.maxLayers, &c->dynamics));
    return Status();
  }();
  if (!s.ok()) {
    destroyCanopy(c);
    return s.context("createCanopy");
  }
  *out = c;
  return Status();
}

void destroyCanopy(CanopyContext* c) {
  if (!c) return;
  if (c->device) {
    if (c->graphReady) c->graph.release(*c->device);
    destroyCompositor(c->compositor);
    destroyLayerDynamics(c->dynamics);
    destroySimulation(c->simulation);
    destroyLayeredVegetation(c->layers);
  }
  delete c;
}

Status setCanopyParams(CanopyContext* c, const CanopyParams& p) {
  if (!c) return Status::error("setCanopyParams: null context");
  CANOPY_TRY(validateParams(*c, p));
  if (!(p.layers == c->params.layers)) {
    const uint32_t before = c->layers.settings.layout.count();
    CANOPY_TRY(setLayerSettings(c->layers, p.layers));
    if (p.layers.layout.count() != before) c->generation++;  // new layer images
  }
  if (p.customPlane) {
    c->plane = p.plane;
    c->planeFixed = true;
  } else if (c->params.customPlane) {
    c->planeFixed = false;  // back to the default: taken from the next frame's camera
  }
  c->params = p;
  return Status();
}

const CanopyParams& canopyParams(const CanopyContext* c) { return c->params; }

Status resizeCanopy(CanopyContext* c, uint32_t width, uint32_t height) {
  if (!c) return Status::error("resizeCanopy: null context");
  CANOPY_TRY(checkRange("resizeCanopy width", width, 1, 16384));
  CANOPY_TRY(checkRange("resizeCanopy height", height, 1, 16384));
  if (width == c->desc.width && height == c->desc.height) return Status();
  Device& d = *c->device;
  vkDeviceWaitIdle(d.device);
  if (c->graphReady) c->graph.release(d);
  c->graphReady = false;
  c->desc.width = width;
  c->desc.height = height;
  Status s = [&]() -> Status {
    CANOPY_TRY(setLayerTargetSize(c->layers, width, height));
    CompositorDesc cd = c->compositor.desc;
    cd.width = width;
    cd.height = height;
    destroyCompositor(c->compositor);
    CANOPY_TRY(createCompositor(d, cd, &c->compositor));
    // The warp grid's corners are in pixels: a new grid, and no previous displacement to take
    // motion vectors against (beginCanopyFrame sees the grid change).
    c->last = gpu::AnimFrame{};
    destroyLayerDynamics(c->dynamics);
    return createLayerDynamics(d, width, height, c->desc.minCellSize, c->desc.maxLayers, &c->dynamics);
  }();
  c->generation++;
  return s.context("resizeCanopy to " + std::to_string(width) + "x" + std::to_string(height));
}

Status beginCanopyFrame(CanopyContext* c, const CanopyFrame& f) {
  if (!c) return Status::error("beginCanopyFrame: null context");
  if (!std::isfinite(f.dt) || f.dt < 0.0f || f.dt > 10.0f)
    return Status::error("CanopyFrame.dt = " + std::to_string(f.dt) + " s is outside [0, 10]");
  Simulation& sim = c->simulation;
  sim.paused = f.dt == 0.0f;
  if (!sim.paused) CANOPY_TRY(prepareSimulationStep(sim, c->params.simulation, f.dt));
  bool rebuild = false;
  CANOPY_TRY(updateLayerView(c->layers, f.camera, &rebuild));
  if (!c->planeFixed) {
    // design.md: the plane of the first view, one tile over the region visible at the
    // vegetation's centre depth.
    const LayeredVegetation& lv = c->layers;
    const glm::vec3 centre = 0.5f * (lv.boundsMin + lv.boundsMax);
    const float depth = glm::dot(centre - viewPosition(f.camera.view), viewForward(f.camera.view));
    const float radius = 0.5f * glm::length(lv.boundsMax - lv.boundsMin);
    c->plane = simulationPlaneFromView(f.camera, std::max(depth, std::max(radius, 1e-3f)));
    c->planeFixed = true;
  }
  DynamicsFrameDesc fd;
  fd.view = f.camera;
  fd.plane = c->plane;
  for (const LayerInfo& l : c->layers.layers) fd.layers.push_back({l.slab.depth, l.slab.distance, l.rootLineY, l.height});
  fd.width = c->desc.width;
  fd.height = c->desc.height;
  fd.simSize = sim.n;
  fd.ringSize = sim.ringSize;
  fd.time = float(sim.time);
  CANOPY_TRY(makeAnimFrame(c->params.dynamics, fd, &c->dynamics.current));
  const gpu::AnimFrame& a = c->dynamics.current;
  const bool motionValid = c->frames > 0 && a.gridX == c->last.gridX && a.gridY == c->last.gridY &&
                           a.layerCount == c->last.layerCount;
  CANOPY_TRY(prepareComposite(c->compositor, c->params.composite, a, !c->layers.rigidDraws.empty(), rebuild,
                              motionValid));
  c->last = a;
  c->layersRebuilt = rebuild;
  c->frames++;
  return Status();
}

Status addCanopyPasses(CanopyContext* c, rg::RenderGraph& g, const CompositeTargets& targets) {
  if (!c) return Status::error("addCanopyPasses: null context");
  SimulationResources sr;
  CANOPY_TRY(addSimulationPasses(c->simulation, g, &sr));
  LayerResources lr;
  CANOPY_TRY(addLayerPasses(c->layers, g, &lr));
  rg::ResourceId disp = rg::kInvalidResource, prev = rg::kInvalidResource;
  rg::ResourceId animFrame = rg::kInvalidResource;
  CANOPY_TRY(addDynamicsPasses(c->dynamics, g, sr.tiled, sr.ring, sr.ringTimes, &disp, &prev, &animFrame));
  return addCompositePasses(c->compositor, g, lr, disp, prev, targets, {animFrame, sr.tiled});
}

uint64_t canopyResourceGeneration(const CanopyContext* c) { return c ? c->generation : 0; }

Status recordCanopy(CanopyContext* c, VkCommandBuffer cmd, const CanopyFrameInputs& in) {
  if (!c) return Status::error("recordCanopy: null context");
  if (!cmd) return Status::error("recordCanopy: null command buffer");
  CANOPY_TRY(beginCanopyFrame(c, in.frame));
  const bool same = c->graphReady && c->graphGeneration == c->generation && sameImage(c->graphInputs.color, in.color) &&
                    sameImage(c->graphInputs.depth, in.depth) && sameImage(c->graphInputs.motion, in.motion);
  if (!same) CANOPY_TRY(buildRecordGraph(*c, in));
  return c->graph.record(cmd);
}

CanopyStats canopyStats(const CanopyContext* c) {
  CanopyStats s;
  if (!c) return s;
  s.frames = c->frames;
  s.layersRebuilt = c->layersRebuilt;
  s.resourceGeneration = c->generation;
  s.internalGraphBuilds = c->graphBuilds;
  s.layers = c->layers.stats;
  s.simulation = c->simulation.stats;
  return s;
}

LayeredVegetation& canopyLayers(CanopyContext* c) { return c->layers; }
LayerDynamics& canopyDynamics(CanopyContext* c) { return c->dynamics; }
Simulation& canopySimulation(CanopyContext* c) { return c->simulation; }
Compositor& canopyCompositor(CanopyContext* c) { return c->compositor; }

}  // namespace canopy
