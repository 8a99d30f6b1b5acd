#pragma once
// The context behind <canopy/canopy.h> (CanopyContext), shared by the façade (render/canopy.cpp)
// and the cache of graphs it compiles for the host's images (render/record_graphs.cpp). Each part's
// state is the part's own (LayeredVegetation, LayerDynamics, Compositor, PerVertexAnimation); the
// façade reaches them through their functions.
#include <memory>
#include <vector>

#include <canopy/canopy_graph.h>

#include "render/canopy.h"
#include "render/host_camera.h"
#include "render/per_vertex.h"
#include "render/pushers.h"
#include "render/rigid_follow.h"
#include "render/shadow.h"
#include "render/world_wind.h"

namespace canopy {

// One simulation, possibly followed by several contexts (CanopyDesc.shareSimulationWith): it is
// stepped once per host frame number by whichever context records first, and freed with the
// last context that follows it.
struct SharedSimulation {
  Simulation sim;
  PreparedList firstClear;  // its first clear, recorded by whichever context records first
  uint64_t lastStepFrame = 0;
  bool everStepped = false;
  ~SharedSimulation() {
    if (sim.device) dropPreparedWork(*sim.device, firstClear);
    destroySimulation(sim);
  }
};

struct RecordGraph {
  std::shared_ptr<rg::RenderGraph> graph;  // compiled and realized
  CanopyFrameInputs inputs;                // the host images and states it was built for
  uint64_t generation = 0;                 // CanopyContext::generation at build
  uint64_t lastUse = 0;
};
constexpr size_t kMaxRecordGraphs = 4;

struct CanopyContext {
  Device* device = nullptr;
  CanopyDesc desc;
  CanopyParams params;
  LayeredVegetation layers;
  std::shared_ptr<SharedSimulation> shared;
  bool skipSimulationStep = false;  // this frame's step is recorded by another context, or dt is 0 (see SharedSimulation)
  LayerDynamics dynamics;
  Compositor compositor;
  CompositorDesc compositorDesc;  // what the compositor was created from (resizeCanopy starts from it)
  // False from a resizeCanopy that failed until one succeeds: the size-dependent parts are missing,
  // frames are refused, and the same size again recreates them.
  bool sized = true;
  PerVertexAnimation perVertex;  // CanopyDesc.allowPerVertex only
  RigidFollow rigid;  // the rigid parts drawn every frame (render/rigid_follow.h): a resident mesh with rigid parts
  bool planeChosen = false;  // `plane` holds the host's or the first view's (chooseSimulationPlane)
  SimulationPlane plane;
  WorldWindState worldWind;  // CanopyParams.wind as it stands while a change eases in
  uint64_t generation = 0;
  uint64_t frames = 0;
  bool layersRebuilt = false;
  gpu::AnimFrame previousAnimFrame{};  // the previous frame's dynamics constants (motion-vector validity)
  LayerView lastView;     // the previous frame's camera (motion vectors: the camera's motion)
  HostCamera host;        // this frame's camera as the host gave it: the viewport's scissor, the jitter
  // recordCanopy(): one compiled graph per set of host images it has seen recently (a host that
  // renders into its swapchain images cycles through 2-4 of them), least recently used first out.
  std::vector<RecordGraph> recordGraphs;
  uint64_t recordGraphUses = 0;
  uint64_t recordGraphBuilds = 0;
  PreparedList perVertexUploads;  // the per-vertex baseline's uploads not yet recorded (host devices: the first frame records them)
  std::vector<CanopyTargetUse> groupUses;  // <canopy/canopy_graph.h>: how the passes use the host's images
  ShadowCaster shadow;  // recordCanopyShadow (render/shadow.h): created at its first call
  std::vector<CanopyPusher> pushers;  // setCanopyPushers: mapped onto the plane at every step
  PusherCounts pusherCounts;          // the last step's mapping
  float pusherHeight = 0.0f;          // the layers' bend lookup height (pusherHeight)
};

// recordCanopy()'s graph for these images (same images, views, states and declarations, built for
// the context's current resources), or null.
RecordGraph* findRecordGraph(CanopyContext& context, const CanopyFrameInputs& inputs);
// Compiles and realizes a graph of Canopy's passes around the host's images (`inputs` passed
// checkFrameInputs) and keeps it, dropping graphs of replaced resources and the least recently
// used beyond kMaxRecordGraphs; dropped graphs are released once no frame in flight uses them.
Status buildRecordGraph(CanopyContext& context, const CanopyFrameInputs& inputs, RecordGraph** out);
// Releases `graphs` once no frame in flight records from them.
void retireRecordGraphs(CanopyContext& context, std::vector<RecordGraph> graphs);

// Shared by createCanopy (render/canopy.cpp) and the calls after it (render/canopy_scene.cpp).
// Creates the rigid parts' draw for the mesh in force (its textures' specialization), retiring
// one made for another mesh once no frame in flight uses it; none without resident rigid parts.
Status makeRigidFollow(CanopyContext& c);
uint32_t guardPixels(float fraction, uint32_t size);
Status checkRange(const char* name, uint32_t v, uint32_t lo, uint32_t hi);
void retireSizeDependentParts(CanopyContext& c);
InstanceInputs instanceInputs(const std::vector<CanopyInstance>& instances);
Status speciesModels(const char* call, const std::vector<CanopySpecies>& species, std::vector<SpeciesModel>* out);

}  // namespace canopy
