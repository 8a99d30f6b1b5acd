#pragma once
// CPU reference of every simulation pass, the same schemes as the GPU shaders (same sweep
// orders, same multigrid cycle), for tests and the benchmark only: it is a separate library
// (canopy_sim_reference) that the runtime never links. Stam's scheme can also run with his
// lexicographic Gauss-Seidel ordering (the games-paper solver, for the physics comparison).
#include <cstdint>
#include <vector>

#include "shaders/shared/sim.h"

namespace canopy::ref {

// Mirror of the GPU buffers (same layouts, shaders/shared/sim.h).
struct SimState {
  uint32_t n = 0, ringSize = 0;
  std::vector<float> velA, velB;  // velocityFloats(n) each
  std::vector<float> mg;          // mgFloats(n, levels)
  std::vector<float> wave;        // 6 n^2: V, V_prev, V_wind (vec2)
  std::vector<float> tiled;       // 2 n^2
  std::vector<float> ring;        // ringSize * 2 n^2
  std::vector<float> ringTimes;   // ringSize
};
SimState makeState(uint32_t n, uint32_t ringSize);

enum class GsOrder { RedBlack, Lexicographic };

// One whole step (fluid, wave, tile), as the GPU graph runs it.
void step(const gpu::SimFrame& f, SimState& s, GsOrder stamOrder = GsOrder::RedBlack);

// The parts, for tests.
void macFluidStep(const gpu::SimFrame& f, SimState& s);
// Projects the MAC field in `vel` in place (multigrid, f.mgCycles V-cycles, warm start from s.mg).
void macProject(const gpu::SimFrame& f, std::vector<float>& vel, std::vector<float>& mg);
void stamVelStep(const gpu::SimFrame& f, SimState& s, GsOrder order);
void waveStep(const gpu::SimFrame& f, SimState& s);
void tile(const gpu::SimFrame& f, SimState& s);

// Fraction of the energy of the lowest gradient mode (u = grad cos(pi x), walls) that one of Stam's
// projections with `iterations` Gauss-Seidel sweeps removes (the 9 % for 20 sweeps on 64^2).
double stamLowestModeRemoval(uint32_t n, uint32_t iterations, GsOrder order);

// Cell-centred velocity (n*n vec2, row-major from the bottom) of the current fluid field.
std::vector<float> cellVelocity(const gpu::SimFrame& f, const SimState& s);
// Largest |central-difference-free| discrete divergence of a MAC field: sum of face fluxes per cell.
double macMaxDivergence(uint32_t n, const std::vector<float>& vel);

}  // namespace canopy::ref
