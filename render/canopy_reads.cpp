// What a host reads from a context and the pushers it sets (<canopy/canopy.h>: canopyStats,
// setCanopyPushers, canopyWind, sampleCanopyWind), and the parts' accessors for tests and tools.
#include "render/canopy_context.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "engine/memory.h"

namespace canopy {

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
  s.compositeCompute = c->params.animation == AnimationMode::Layers2D && c->compositor.computeThisFrame;
  s.compositeComputeAvailable = c->compositor.computeAvailable;
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
