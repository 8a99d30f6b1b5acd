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

// Motors of a step: the host's SimulationParams.motors (at most 8) then the pushers the context
// maps onto the plane (at most 32; docs/design.md "Pushers").
#define SIM_MAX_MOTORS 40u
// The pushers' bend field (docs/design.md "Pushers"): BEND_SCALE times n cells a side on the
// world's horizontal plane, BEND_SCALE tiles a side around the simulation tile's centre, not tiled.
#define SIM_BEND_SCALE 2u
// Invocations of the single-workgroup solver kernels: a specialization constant chosen per device
// class (compute/simulation.cpp, simulationGroupSize); this is the largest allowed and the default.
#define SIM_MAX_GROUP_SIZE 1024u
#define SIM_MG_PRE_SWEEPS 1u
#define SIM_MG_POST_SWEEPS 1u
#define SIM_MG_COARSE_SWEEPS 32u

CANOPY_NAMESPACE_BEGIN

// One motor of the fluid (a point or a segment: a sphere or a capsule seen on the plane), in domain
// units. A host's SimulationParams.motors entry is a point with no velocity and no bend.
struct SimMotor {
  vec4 segment;  // xy: one end, zw: the other (equal for a point), domain units
  vec4 flow;     // x: radius R (domain units), y: outward speed at the rim (domain units/s),
                 // zw: the body's velocity on the plane times its air coupling (domain units/s)
  vec4 bend;     // x: the bend field's peak target (domain units/s); y: the radius on the ground (tile units);
                 // z: the highest world y it reaches (its top + its radius); w: its radius, world units
  vec4 ground;   // the segment's ends on the bend field's plane: xy one end, zw the other (tile units)
};
CANOPY_SIZE_CHECK(SimMotor, 64)

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
  float bendK;         // the bend field's spring stiffness, 1/s^2 (SimulationParams.push)
  float bendZeta;      // its damping, 1/s
  SimMotor motors[SIM_MAX_MOTORS];  // [0, motorCount): the host's motors, then the pushers
};
CANOPY_SIZE_CHECK(SimFrame, 128 + 64 * SIM_MAX_MOTORS)

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
// The point of motor m's segment nearest to p (a point motor: its position).
CANOPY_INLINE vec2 motorNearest(SimMotor m, vec2 p) {
  vec2 a = vec2(m.segment.x, m.segment.y), b = vec2(m.segment.z, m.segment.w);
  vec2 ab = b - a;
  float len2 = dot(ab, ab);
  float t = len2 > 0.0f ? clamp(dot(p - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
  return a + t * ab;
}
// Mass-source rate (1/s) of a motor at domain position p. An incompressible flow removes any radial
// push (it is a pure gradient), so a motor — a character or an explosion displacing air — is a
// source the projection keeps: div u = q. Two terms, d = p - the nearest point of the motor,
// r = |d|, R its radius:
//  - the outward push s (flow.y): q = 6 s (1 - r/R) / R inside R, so the flux out of a point motor is
//    2 pi R s and the outward speed at the rim is s (negative s: a sink);
//  - the moving body (flow.zw = v): the air it displaces, q = -v . grad chi with chi = (1 - r^2/R^2)^2
//    the body's smooth footprint: q = 4 (1 - r^2/R^2) (v . d) / R^2, a source ahead of it and a sink
//    behind (net zero), so air is pushed aside in front and drawn in behind.
// The source at p is the sum over SimFrame.motors[0 .. motorCount), in that order (the CPU
// reference's motorSources, the shaders' motorSourcesAt). The term takes one motor, not the frame:
// GLSL passes a struct by value, and lavapipe copied the whole frame — its motors[] indexed by the
// loop — on every call (~0.14 ms per projection at N = 64, docs/performance.md).
CANOPY_INLINE float motorSource(SimMotor m, vec2 p) {
  vec2 d = p - motorNearest(m, p);
  float r2 = dot(d, d);
  float R = m.flow.x;
  if (r2 >= R * R) return 0.0f;
  float r = sqrt(r2);
  float q = 6.0f * m.flow.y * (1.0f - r / R) / R;
  return q + 4.0f * (1.0f - r2 / (R * R)) * (m.flow.z * d.x + m.flow.w * d.y) / (R * R);
}
// The bend field's target at its position g (tile units on the ground plane) from motor m, in xy,
// and in z 1 where the motor touches g (its ground segment within its radius R), else 0. Away from
// the segment, |target| = peak * k rho (1 - rho^2)^2 with rho = r/R, k = 5^(5/2)/16 so the largest
// is `peak` (at rho = 1/sqrt 5): zero on the axis (no direction there) and at the rim. The target
// is a horizontal vector (the field's two axes).
CANOPY_INLINE vec3 motorBendTarget(SimMotor m, vec2 g) {
  vec2 a = vec2(m.ground.x, m.ground.y), b = vec2(m.ground.z, m.ground.w);
  vec2 ab = b - a;
  float len2 = dot(ab, ab);
  float t = len2 > 0.0f ? clamp(dot(g - a, ab) / len2, 0.0f, 1.0f) : 0.0f;
  vec2 d = g - (a + t * ab);
  float r2 = dot(d, d);
  float R = m.bend.y;
  if (m.bend.x == 0.0f || r2 >= R * R) return vec3(0.0f, 0.0f, 0.0f);
  float w = 1.0f - r2 / (R * R);
  vec2 target = (m.bend.x * 3.4938562f * w * w / R) * d;  // rho * d/r = d / R
  return vec3(target.x, target.y, 1.0f);
}
// One substep of h seconds of a bend cell (value, rate) toward `target` (motorBendTarget summed;
// z > 0: touched). Where a pusher touches it the grass goes where it is pushed at the contact rate
// (bendContact, 1/s: a foot does not wait for a spring); elsewhere it springs back, the damped
// spring B'' = -k (B - 0) - zeta B' of SimulationParams.push (semi-implicit Euler).
#define SIM_BEND_CONTACT_RATE 30.0f
CANOPY_INLINE void bendSubstep(CANOPY_INOUT(vec2) value, CANOPY_INOUT(vec2) rate, vec3 target, float k, float zeta, float h) {
  if (target.z > 0.0f) {
    vec2 next = value + (vec2(target.x, target.y) - value) * (1.0f - exp(-h * SIM_BEND_CONTACT_RATE));
    rate = (next - value) / h;
    value = next;
  } else {
    rate += h * (-k * value - zeta * rate);
    value += h * rate;
  }
}
// The bend field's cell (i, j) centre (tile units from the field's corner).
CANOPY_INLINE vec2 bendCellCentre(uint n, uint i, uint j) {
  return vec2((float(i) + 0.5f) / float(n), (float(j) + 0.5f) / float(n));
}
// The tiled buffer: tiled V_s (n*n vec2, what the plants read), the tiled V_wind (n*n vec2, what a
// host reads: the wind image and sampleCanopyWind), then the bend field's value, its rate and its
// reach (the world height the last pusher touching the cell reached, and the fade above it, world
// units) ((SIM_BEND_SCALE n)^2 vec2 each).
CANOPY_INLINE uint tiledWindOffset(uint n) { return n * n; }
CANOPY_INLINE uint bendCells(uint n) { return SIM_BEND_SCALE * SIM_BEND_SCALE * n * n; }
CANOPY_INLINE uint bendOffset(uint n) { return 2u * n * n; }
CANOPY_INLINE uint bendRateOffset(uint n) { return 2u * n * n + bendCells(n); }
CANOPY_INLINE uint bendReachOffset(uint n) { return 2u * n * n + 2u * bendCells(n); }
CANOPY_INLINE uint tiledVec2s(uint n) { return 2u * n * n + 3u * bendCells(n); }
// Linear seam-blend weight of the tiling (docs/design.md): 1 at the tile centre, 0 at its edges.
CANOPY_INLINE float tileWeight(uint i, uint n) {
  return 1.0f - abs((float(i) + 0.5f) / float(n) - 0.5f) * 2.0f;
}

CANOPY_NAMESPACE_END
#endif
