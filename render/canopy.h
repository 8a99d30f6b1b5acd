#pragma once
// The internal side of the public API (<canopy/canopy.h>): what the demo, tools, tests and the
// benchmark use beyond it, from the source tree (never installed). Hosts include only
// <canopy/canopy.h> (and <canopy/canopy_graph.h> for Canopy's render graph path).
#include <canopy/canopy.h>

#include "compute/dynamics.h"
#include "compute/simulation.h"
#include "engine/camera.h"
#include "engine/device.h"
#include "engine/render_graph.h"
#include "engine/status.h"
#include "render/composite.h"
#include "render/model.h"
#include "render/layers.h"

namespace canopy {

// The opaque public Model: a VegetationModel in host memory.
struct Model {
  VegetationModel data;
};

// createCanopy from a VegetationModel held by the caller (no copy into a Model).
Status createCanopy(Device& device, const VegetationModel& model, const CanopyDesc& desc, CanopyContext** out);
// canopySceneInstances from the species' bounds (the demo and tools hold VegetationModels).
Status sceneCopies(const CanopyScene& scene, const std::vector<Float3>& boundsMin, const std::vector<Float3>& boundsMax,
                   std::vector<CanopyInstance>* out);
// The same for several species held by the caller (render/species.h).
Status createCanopy(Device& device, const std::vector<SpeciesModel>& species, const CanopyDesc& desc, CanopyContext** out);

// Canopy's own render-graph path (the demo, the benchmark; a host's graph uses
// <canopy/canopy_graph.h>): prepares the next recorded frame (CPU work only), then adds Canopy's
// passes to a graph holding the host's imported images.
Status beginCanopyFrame(CanopyContext* context, const CanopyFrame& frame);
Status addCanopyPasses(CanopyContext* context, rg::RenderGraph& graph, const CompositeTargets& targets);
uint64_t canopyResourceGeneration(const CanopyContext* context);

// The parts (tools, tests, the benchmark).
LayeredVegetation& canopyLayers(CanopyContext* context);
LayerDynamics& canopyDynamics(CanopyContext* context);
Simulation& canopySimulation(CanopyContext* context);
Compositor& canopyCompositor(CanopyContext* context);

// A CanopyFrame from a layer view (tools and tests work in glm).
inline CanopyFrame makeCanopyFrame(const LayerView& view, float dt, uint64_t frameNumber = 0) {
  CanopyFrame f;
  f.camera = toCamera(view);
  f.dt = dt;
  f.frameNumber = frameNumber;
  return f;
}

}  // namespace canopy
