#pragma once
// The 2D harmonic-motion simulation of paper section 3.3 on the GPU (docs/design.md): wind by stable
// fluids, the wave oscillator driven by it, tiling with seam blending, and a history ring of the
// tiled field for the exact layer delay. Every step is a handful of compute passes recorded
// through the render graph (addSimulationPasses), or run standalone (runSimulationSteps).
//
// Units: the simulation domain is the unit square of the simulation plane (N x N cells, h = 1/N);
// lengths in domain units, velocities in domain units per second, times in seconds.
#include <cstdint>
#include <string>
#include <vector>

#include <canopy/canopy_params.h>

#include "engine/memory.h"
#include "engine/pipeline.h"
#include "engine/render_graph.h"
#include "engine/status.h"
#include "engine/transfer.h"
#include "shaders/shared/sim.h"

namespace canopy {
struct Device;

// WindParams, Motor, FluidParams, WaveParams, SimulationParams, SimulationDesc and SimulationStats
// are the public API's (<canopy/canopy_params.h>); their enum values are the shader's constants.
static_assert(uint32_t(FluidScheme::MacMultigrid) == SIM_SCHEME_MAC_MULTIGRID && uint32_t(FluidScheme::Stam) == SIM_SCHEME_STAM);
static_assert(uint32_t(FluidBoundary::WindTunnel) == SIM_BOUNDARY_TUNNEL && uint32_t(FluidBoundary::Walls) == SIM_BOUNDARY_WALLS);
static_assert(kWindFromLeft == SIM_SIDE_LEFT && kWindFromRight == SIM_SIDE_RIGHT && kWindFromBottom == SIM_SIDE_BOTTOM &&
              kWindFromTop == SIM_SIDE_TOP && kMaxMotors + kMaxPushers == SIM_MAX_MOTORS);

// Resources of one simulation as seen by a render graph (addSimulationPasses).
struct SimulationResources {
  rg::ResourceId frame, velocity, multigrid, wave, tiled, ring, ringTimes, windImage, windReadback;
};

// The wind a host reads (docs/design.md "The wind a host reads"): the tiled V_wind copied each
// step into an n x n R32G32_SFLOAT image (domain units/s, row 0 at the bottom), left in
// kWindImageRest for any shader stage, and into a host-visible ring of windSlotCount copies.
inline constexpr VkFormat kWindImageFormat = VK_FORMAT_R32G32_SFLOAT;
rg::State windImageRest();
// One readback slot: the step it holds, the host frame that recorded it and the plane it maps by.
struct WindSlot {
  bool valid = false;
  uint64_t frame = 0;   // the host frame number whose recording copied it
  double time = 0.0;    // simulation time at the end of that step, s
  SimulationPlane plane;
};

// GPU state of a simulation. Memory: velocity 2 * 2(N+2)^2 floats, multigrid ~(8/3) N^2 floats,
// wave 6 N^2 floats, tiled 2 tiledVec2s(N) = 28 N^2 floats (V_s, V_wind, the bend field) and the history ring H * N^2 * 8 bytes (H * 32 KiB at N = 64).
struct Simulation {
  Device* device = nullptr;
  uint32_t n = 0, ringSize = 0;
  uint32_t mgSerialSize = 8;  // see createSimulation
  uint32_t groupSize = SIM_MAX_GROUP_SIZE;  // single-workgroup kernels' width (createSimulation)
  Buffer frame, velocity, multigrid, wave, tiled, ring, ringTimes;
  ComputePipeline diffuse, project, advect, stam, oscillator, tile;
  // The single-workgroup kernels again at the widest width, when groupSize is narrower: lavapipe
  // stops a shader's loops after 65535 iterations in all per invocation, so a step whose loops
  // would not fit at groupSize (many V-cycles or sweeps) runs these instead (prepareSimulationStep).
  ComputePipeline wideDiffuse, wideProject, wideStam, wideOscillator;
  uint32_t wideGroupSize = 0;  // 0: no wide variant (groupSize is already the widest)
  // The lane-blocked diffusion, projection and oscillator (shaders/sim_*_lanes.comp) for CPU devices:
  // one subgroup of laneWidth lanes holding the fields in registers. laneWidth 0: not created (a GPU,
  // no compute shuffles, a subgroup other than 8 or 16 wide, a grid outside [laneWidth, 128] or a
  // groupSize the host chose).
  ComputePipeline laneProject, laneDiffuse, laneOscillator;
  uint32_t laneWidth = 0;
  bool laneProjectNext = false, laneDiffuseNext = false, laneOscillatorNext = false;  // the next recorded step uses them (prepareSimulationStep)
  gpu::SimFrame next{};  // the block the next recorded step uploads (prepareSimulationStep)
  std::vector<gpu::SimMotor> pushers;  // the next step's pushers (after the params' motors; the context sets them)
  bool bendUsed = false;  // a step had a pusher with a bend: the field may be non-zero (DynamicsFrameDesc.bend)
  Image windImage;        // kWindImageFormat, n x n
  Buffer windReadback;    // windSlots.size() copies of n*n vec2, host-visible
  std::vector<WindSlot> windSlots;  // framesInFlight + 1
  uint32_t windSlotNext = 0;        // the slot the next recorded step copies into
  double time = 0.0;     // simulation clock, s
  float nominalDt = 1.0f / 30.0f;  // SimulationDesc.nominalDt: eq. 6's Delta t (DynamicsParams.dt 0)
  SimulationStats stats;
  bool paused = false;   // the graph's step passes record nothing (a host frame with dt = 0)
  rg::RenderGraph graph;  // standalone graph (runSimulationSteps)
  SimulationResources graphIds{};
  bool graphReady = false;
};

// Checks a description / parameters; the error names the parameter and its allowed range.
Status validateSimulationDesc(const SimulationDesc& desc);
Status validateSimulationParams(const SimulationParams& params, float dt);
// The GPU parameter block for one step (substep counts, sweep counts); pure CPU, also used by the
// CPU reference so both run exactly the same step.
// `pushers` (at most kMaxPushers) follow params.motors in SimFrame.motors (the context maps its
// CanopyPushers to them: render/pushers.h).
Status makeSimFrame(const SimulationParams& params, uint32_t n, float time, float dt, uint32_t ringSlot,
                    uint32_t ringSize, gpu::SimFrame* out, const std::vector<gpu::SimMotor>& pushers = {});
// Loop iterations one shader invocation of the busiest simulation kernel runs for this step, and
// the check against kMaxLoopTrips (lavapipe silently stops loops past 65535 iterations).
inline constexpr double kMaxLoopTrips = 60000;
double estimateLoopTrips(const gpu::SimFrame& frame);
// The same for the lane-blocked projection, diffusion and oscillator kernels with `lanes` lanes.
double estimateLaneProjectTrips(const gpu::SimFrame& frame, uint32_t lanes);
double estimateLaneDiffuseTrips(const gpu::SimFrame& frame, uint32_t lanes);
double estimateLaneOscillatorTrips(const gpu::SimFrame& frame, uint32_t lanes);
Status checkLoopBudget(const gpu::SimFrame& frame);
// Stable wave substep length for the given parameters and grid (s).
float maxStableWaveDt(const WaveParams& wave, uint32_t n);

// The state's first clear goes to `deferred` on a device that defers its work (engine/transfer.h,
// submitOrDefer); null: submitted at once.
Status createSimulation(Device& device, const SimulationDesc& desc, Simulation* out, PreparedList* deferred = nullptr);
void destroySimulation(Simulation& sim);

// Adds one step's passes to `graph` (the host's, or Canopy's own), importing the simulation's
// buffers. Each record() of that graph runs the step prepared last by prepareSimulationStep.
// `hold` (default: &sim.paused) is read when the graph is recorded: true records no step (a paused
// host frame, or a context that shares a simulation another context stepped this frame).
Status addSimulationPasses(Simulation& sim, rg::RenderGraph& graph, SimulationResources* out, const bool* hold = nullptr);
// The single-workgroup width for the step `frame` describes: the simulation's own groupSize when
// its loops fit lavapipe's budget there, else the wide variant's; refuses when neither fits.
Status chooseGroupSize(const Simulation& sim, gpu::SimFrame* frame);
// Validates `params` and fixes the next recorded step (advances the clock by dt and the ring slot).
Status prepareSimulationStep(Simulation& sim, const SimulationParams& params, float dt);
// Standalone: records `count` steps (one command buffer per 256 steps), submits and waits.
Status runSimulationSteps(Simulation& sim, const SimulationParams& params, float dt, uint32_t count);

// Diagnostics: projects velocity field A in place with the MAC multigrid projection as configured
// by `params` (boundary, cycles), starting from a zero pressure. Used to measure projection quality.
Status runProjectionOnly(Simulation& sim, const SimulationParams& params);

// Host copies of the fields (tools, tests, benchmark).
struct SimulationFields {
  uint32_t n = 0;
  std::vector<float> velocity;  // both fields, velocityFloats(n) each (MAC faces or Stam arrays)
  std::vector<float> wind;      // V_wind at cell centres, n*n vec2, row 0 at the bottom
  std::vector<float> vs;        // V_s (oscillator), n*n vec2
  std::vector<float> vsPrev;    // V_s one substep earlier
  std::vector<float> tiled;     // tiled V_s, n*n vec2
  std::vector<float> ring;      // H * n*n vec2
  std::vector<float> ringTimes; // H
  std::vector<float> multigrid;
};
Status readSimulationFields(Simulation& sim, SimulationFields* out);
// The readback slot to sample on the CPU: the newest whose frame is at most `completedFrame` (null: none).
const WindSlot* completedWindSlot(const Simulation& sim, uint64_t completedFrame, uint32_t* index);
// Overwrites device state from host data (tests: initial conditions), submitted at once. Empty
// vectors are skipped.
Status writeSimulationState(Simulation& sim, const std::vector<float>& velocity, const std::vector<float>& wave);

}  // namespace canopy
