#pragma once
// The 2D harmonic-motion simulation of paper section 3.3 on the GPU (design.md): wind by stable
// fluids, the wave oscillator driven by it, tiling with seam blending, and a history ring of the
// tiled field for the exact layer delay. Every step is a handful of compute passes recorded
// through the render graph (addSimulationPasses), or run standalone (runSimulationSteps).
//
// Units: the simulation domain is the unit square of the simulation plane (N x N cells, h = 1/N);
// lengths in domain units, velocities in domain units per second, times in seconds.
#include <cstdint>
#include <string>
#include <vector>

#include "engine/memory.h"
#include "engine/pipeline.h"
#include "engine/render_graph.h"
#include "engine/status.h"
#include "shaders/shared/sim.h"

namespace canopy {
struct Device;

enum class FluidScheme : uint32_t {
  MacMultigrid = SIM_SCHEME_MAC_MULTIGRID,  // staggered grid + multigrid projection (default)
  Stam = SIM_SCHEME_STAM,                   // Stam's collocated games-paper solver, closed walls
};
enum class FluidBoundary : uint32_t {
  WindTunnel = SIM_BOUNDARY_TUNNEL,  // inflow on source sides, open outflow elsewhere (default)
  Walls = SIM_BOUNDARY_WALLS,        // closed box (no net wind can cross it)
};
// Wind source sides (combinable): a source on the left blows toward +x, on the top toward -y.
enum WindSide : uint32_t {
  kWindFromLeft = SIM_SIDE_LEFT,
  kWindFromRight = SIM_SIDE_RIGHT,
  kWindFromBottom = SIM_SIDE_BOTTOM,
  kWindFromTop = SIM_SIDE_TOP,
};

// Injected wind: speed through a source side = strength * (baseline + modulation sin(2 pi f t))
// * (1 + gust * noise), the noise travelling along the side. Changeable every step.
struct WindParams {
  uint32_t sides = kWindFromLeft;  // WindSide mask, 0..15 (0: no boundary wind)
  float strength = 0.5f;           // domain units/s, [0, 1000]
  float frequency = 0.25f;         // Hz, [0, 1000]
  float baseline = 1.0f;           // a, [-10, 10]
  float modulation = 0.3f;         // b, [-10, 10]
  float gust = 0.3f;               // relative gust amplitude, [0, 1]
  float gustScale = 0.25f;         // gust wavelength along a side, domain units, (0, 100]
  float gustSpeed = 0.3f;          // gust travel speed along a side, domain units/s, [-1000, 1000]
  uint32_t seed = 1;               // gust noise seed
};

// A point "motor" (a character, an explosion): a mass source in the fluid, so air flows outward
// around it (negative strength: inward). The source density falls linearly to zero at the radius.
struct Motor {
  float x = 0.5f, y = 0.5f;  // centre, domain units (may lie outside [0,1])
  float radius = 0.1f;       // domain units, (0, 100]
  float strength = 1.0f;     // outward flow speed at the radius, domain units/s, [-1000, 1000]
};

struct FluidParams {
  FluidScheme scheme = FluidScheme::MacMultigrid;
  FluidBoundary boundary = FluidBoundary::WindTunnel;  // MAC scheme only; Stam's has walls
  float viscosity = 1e-4f;       // domain units^2/s, [0, 10]
  uint32_t iterations = 20;      // relaxation sweeps: Stam's linear solves; cap of the diffusion sweeps, [1, 10000]
  uint32_t multigridCycles = 2;  // V-cycles per MAC projection, [1, 64]
};

// The oscillator V'' = c^2 lap V - k (V - g V_wind) - zeta V' (design.md).
struct WaveParams {
  float stiffness = 40.0f;    // k, 1/s^2, [0, 1e6]: undamped angular frequency sqrt(k)
  float speed = 0.05f;        // c, domain units/s, [0, 100]
  float damping = 2.0f;       // zeta, 1/s, [0, 1000]
  float gain = 1.0f;          // g, [-100, 100]
  uint32_t maxSubsteps = 64;  // [1, 4096]: a longer step is clamped (stats.clampedSeconds)
};

struct SimulationParams {
  WindParams wind;
  FluidParams fluid;
  WaveParams wave;
  std::vector<Motor> motors;  // at most SIM_MAX_MOTORS (8)
};

struct SimulationDesc {
  uint32_t gridSize = 64;        // N: a power of two in [4, 1024]
  uint32_t historySize = 0;      // H tiled fields kept; 0: enough for historySeconds at nominalDt
  float historySeconds = 1.0f;   // (0, 3600]
  float nominalDt = 1.0f / 30.0f;
};

// Resources of one simulation as seen by a render graph (addSimulationPasses).
struct SimulationResources {
  rg::ResourceId frame, velocity, multigrid, wave, tiled, ring, ringTimes;
};

struct SimulationStats {
  uint64_t steps = 0;
  uint32_t lastWaveSubsteps = 0;
  uint32_t lastDiffuseSweeps = 0;
  uint32_t dispatchesPerStep = 0;
  double clampedSeconds = 0.0;  // oscillator time dropped by the maxSubsteps clamp (frame hitches)
};

// GPU state of a simulation. Memory: velocity 2 * 2(N+2)^2 floats, multigrid ~(8/3) N^2 floats,
// wave 6 N^2 floats, tiled 2 N^2 floats and the history ring H * N^2 * 8 bytes (H * 32 KiB at N = 64).
struct Simulation {
  Device* device = nullptr;
  uint32_t n = 0, ringSize = 0;
  uint32_t mgSerialSize = 8;  // see createSimulation
  Buffer frame, velocity, multigrid, wave, tiled, ring, ringTimes;
  ComputePipeline diffuse, project, advect, stam, oscillator, tile;
  gpu::SimFrame next{};  // the block the next recorded step uploads (prepareSimulationStep)
  double time = 0.0;     // simulation clock, s
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
Status makeSimFrame(const SimulationParams& params, uint32_t n, float time, float dt, uint32_t ringSlot,
                    uint32_t ringSize, gpu::SimFrame* out);
// Loop iterations one shader invocation of the busiest simulation kernel runs for this step, and
// the check against kMaxLoopTrips (lavapipe silently stops loops past 65535 iterations).
inline constexpr double kMaxLoopTrips = 60000;
double estimateLoopTrips(const gpu::SimFrame& frame);
Status checkLoopBudget(const gpu::SimFrame& frame);
// Stable wave substep length for the given parameters and grid (s).
float maxStableWaveDt(const WaveParams& wave, uint32_t n);

Status createSimulation(Device& device, const SimulationDesc& desc, Simulation* out);
void destroySimulation(Simulation& sim);

// Adds one step's passes to `graph` (the host's, or Canopy's own), importing the simulation's
// buffers. Each record() of that graph runs the step prepared last by prepareSimulationStep.
Status addSimulationPasses(Simulation& sim, rg::RenderGraph& graph, SimulationResources* out);
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
// Overwrites device state from host data (tests: initial conditions). Empty vectors are skipped.
Status writeSimulationState(Simulation& sim, const std::vector<float>& velocity, const std::vector<float>& wave);

}  // namespace canopy
