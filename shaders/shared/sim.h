// The 2D harmonic-motion simulation (paper 3.3, docs/design.md): the per-step parameter block, grid
// layouts, and the few functions the GPU passes and the CPU reference must compute identically.
//
// Units: the simulation domain is the unit square [0,1]^2 of the simulation plane, N x N cells of
// size h = 1/N (Stam's convention); velocities are in domain units per second, times in seconds.
// y grows upward (row 0 at the bottom).
#ifndef CANOPY_SIM_H
#define CANOPY_SIM_H
#include "shared/interop.h"

#define SIM_SCHEME_MAC_MULTIGRID 0u  // staggered grid, multigrid projection (default)
#define SIM_SCHEME_STAM 1u           // Stam's collocated games-paper solver, walls, red-black GS

#define SIM_BOUNDARY_TUNNEL 0u  // inflow on source sides, open outflow elsewhere (default)
#define SIM_BOUNDARY_WALLS 1u   // Stam's closed box

#define SIM_SIDE_LEFT 1u    // wind source on the left boundary, blowing toward +x
#define SIM_SIDE_RIGHT 2u   // on the right boundary, toward -x
#define SIM_SIDE_BOTTOM 4u  // on the bottom boundary, toward +y
#define SIM_SIDE_TOP 8u     // on the top boundary, toward -y

#define SIM_MAX_MOTORS 8u
// Invocations of the single-workgroup solver kernels: a specialization constant chosen per device
// class (compute/simulation.cpp, simulationGroupSize); this is the largest allowed and the default.
#define SIM_MAX_GROUP_SIZE 1024u
#define SIM_MG_PRE_SWEEPS 1u
#define SIM_MG_POST_SWEEPS 1u
#define SIM_MG_COARSE_SWEEPS 32u

CANOPY_NAMESPACE_BEGIN

// Everything a simulation step reads, uploaded once per step (vkCmdUpdateBuffer in the graph).
struct SimFrame {
  uint n;              // interior cells per side (power of two, 4..1024)
  uint scheme;         // SIM_SCHEME_*
  uint boundary;       // SIM_BOUNDARY_* (MAC scheme; Stam's scheme always has walls)
  uint windSides;      // SIM_SIDE_* mask of wind sources
  float dt;            // step length, s
  float time;          // simulation time at the start of the step, s
  float viscosity;     // kinematic viscosity, domain units^2/s
  uint diffuseSweeps;  // red-black sweeps of the implicit diffusion (0 = no viscosity)
  uint iterations;     // Stam scheme: Gauss-Seidel sweeps per linear solve
  uint mgCycles;       // MAC scheme: multigrid V-cycles per projection
  uint mgLevels;       // number of multigrid levels (finest N, coarsest >= 2 cells a side)
  uint mgSerialSize;   // levels at most this many cells a side run in one invocation, without barriers
  uint motorCount;     // active entries of motors[]
  float strength;      // inflow speed scale, domain units/s
  float frequency;     // temporal modulation frequency, Hz
  float baseline;      // a in strength * (a + b sin(2 pi f t))
  float modulation;    // b
  float gust;          // relative gust amplitude, 0..1
  float gustScale;     // gust wavelength along a boundary, domain units
  float gustSpeed;     // gust travel speed along the boundary, domain units/s
  uint seed;           // gust noise seed
  float waveK;         // oscillator stiffness k, 1/s^2 (omega = sqrt(k))
  float waveC;         // wave propagation speed c, domain units/s
  float waveZeta;      // damping zeta, 1/s
  float waveGain;      // g: the oscillator is driven toward g * V_wind
  uint waveSubsteps;   // Verlet substeps this step (stability: omega dt < 2, wave CFL)
  float waveDt;        // dt / waveSubsteps, s
  uint ringSlot;       // history ring slot the tile pass writes
  uint ringSize;       // H
  uint groupSize;      // invocations of the single-workgroup kernels (their specialization constant)
  uint pad1;
  uint pad2;
  vec4 motors[8];      // xy: position (domain units), z: radius (domain units), w: outward speed at the rim (domain units/s)
};
CANOPY_SIZE_CHECK(SimFrame, 256)

struct SimPush {
  uint phase;  // pass-specific selector (e.g. which velocity buffer a projection works on)
  uint pad0;
  uint pad1;
  uint pad2;
};
CANOPY_SIZE_CHECK(SimPush, 16)

// ---- layouts ----------------------------------------------------------------------------
// MAC velocity buffer: u on vertical faces ((n+1) x n), then v on horizontal faces (n x (n+1)).
CANOPY_INLINE uint macU(uint n, uint i, uint j) { return j * (n + 1u) + i; }
CANOPY_INLINE uint macV(uint n, uint i, uint j) { return (n + 1u) * n + j * n + i; }
CANOPY_INLINE uint macFloats(uint n) { return 2u * n * (n + 1u); }
// Stam's collocated arrays: (n+2)^2 with a boundary ring; array k (0: u, 1: v) of a buffer.
CANOPY_INLINE uint stamIX(uint n, uint k, uint i, uint j) { return k * (n + 2u) * (n + 2u) + j * (n + 2u) + i; }
CANOPY_INLINE uint stamFloats(uint n) { return 2u * (n + 2u) * (n + 2u); }
CANOPY_INLINE uint velocityFloats(uint n) { return max(macFloats(n), stamFloats(n)); }
// Multigrid pyramid: per level, the unknown p (m*m) then the right-hand side b (m*m), m = n >> level.
CANOPY_INLINE uint mgOffset(uint n, uint level) {
  uint off = 0u;
  for (uint l = 0u; l < level; ++l) off += 2u * (n >> l) * (n >> l);
  return off;
}
CANOPY_INLINE uint mgFloats(uint n, uint levels) { return mgOffset(n, levels); }
// Levels from n down to the first size <= 4 (at least 2 cells a side so every cell has a neighbour).
CANOPY_INLINE uint mgLevelCount(uint n) {
  uint levels = 1u;
  while ((n >> (levels - 1u)) > 4u) ++levels;
  return levels;
}
// Wave buffer (vec2 elements): V (n*n), V_previous (n*n), V_wind at cell centres (n*n).
CANOPY_INLINE uint waveWind(uint n, uint c) { return 2u * n * n + c; }

// ---- inflow ----------------------------------------------------------------------------------
CANOPY_INLINE float hashToSigned(uint x) {
  x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
  return float(x & 0xffffu) * (2.0f / 65535.0f) - 1.0f;
}
// Smooth 1D value noise in [-1, 1].
CANOPY_INLINE float valueNoise(float x, uint seed) {
  float fl = floor(x);
  int i = int(fl);
  float t = x - fl;
  t = t * t * (3.0f - 2.0f * t);
  return mix(hashToSigned(uint(i) * 0x9e3779b9u ^ seed), hashToSigned(uint(i + 1) * 0x9e3779b9u ^ seed), t);
}
// Inflow speed through a source side at position s in [0,1] along it: strength * (a + b sin(2 pi f t))
// times (1 + gust * noise) where the noise travels along the side, so neighbours do not move in lockstep.
CANOPY_INLINE float inflowSpeed(SimFrame f, uint side, float s) {
  float temporal = f.baseline + f.modulation * sin(6.28318530718f * f.frequency * f.time);
  float x = (s - f.gustSpeed * f.time) / max(f.gustScale, 1e-4f);
  uint seed = f.seed * 4u + side;
  float noise = 0.65f * valueNoise(x, seed) + 0.35f * valueNoise(2.3f * x + 0.37f * f.time, seed ^ 0x5bd1e995u);
  return f.strength * temporal * (1.0f + f.gust * noise);
}
// Mass-source rate (1/s) of the point motors at domain position p. An incompressible flow removes
// any radial push (it is a pure gradient), so a motor — a character or an explosion displacing
// air — is a source the projection keeps: div u = q. q = 6 s (1 - r/R) / R inside radius R, so the
// total flux is 2 pi R s and the outward speed at the rim is s (negative s: a sink). The source
// at p is the sum of motorSource over SimFrame.motors[0 .. motorCount), in that order (the CPU
// reference's motorSources, the shaders' motorSourcesAt). The term takes one motor, not the frame:
// GLSL passes a struct by value, and lavapipe copied the whole frame — its motors[] indexed by the
// loop — on every call (~0.14 ms per projection at N = 64, docs/performance.md).
CANOPY_INLINE float motorSource(vec4 motor, vec2 p) {
  float dx = p.x - motor.x, dy = p.y - motor.y;
  float r = sqrt(dx * dx + dy * dy);
  float R = motor.z;
  return r < R ? 6.0f * motor.w * (1.0f - r / R) / R : 0.0f;
}
// Linear seam-blend weight of the tiling (docs/design.md): 1 at the tile centre, 0 at its edges.
CANOPY_INLINE float tileWeight(uint i, uint n) {
  return 1.0f - abs((float(i) + 0.5f) / float(n) - 0.5f) * 2.0f;
}

CANOPY_NAMESPACE_END
#endif
