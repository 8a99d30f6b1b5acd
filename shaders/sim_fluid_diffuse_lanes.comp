#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
// Sources + implicit diffusion of the MAC field, lane-blocked for CPU devices: the same sweeps as
// sim_fluid_diffuse.comp (one Jacobi sweep from B into A, then f.diffuseSweeps red-black
// Gauss-Seidel sweeps on A, same per-face arithmetic) with both fields in registers — one subgroup
// of W = SIM_GROUP lanes, lane L holding the columns k W + L of every row, the layout and the
// reason of sim_fluid_project_lanes.comp (docs/performance.md, "Simulation step").
#include "sim_common.glsl"
layout(local_size_x_id = 0) in;  // SIM_GROUP == the subgroup size (compute/simulation.cpp checks)

// Floats per lane: u faces of columns 0..n-1 (n rows) and v faces (n + 1 rows), each for A and B,
// plus column n of u (compute/simulation.cpp, the lane kernels' sizes).
layout(constant_id = 1) const uint SIM_LANE_FLOATS = 1u;
float reg[SIM_LANE_FLOATS];

float a;
uint segs, uA, uB, vA, vB, uEdge;  // register offsets: u of A and B (segs x n), v of A and B (segs x (n+1)), u column n
uint lane() { return gl_SubgroupInvocationID; }

// Neighbours of the vector (segment k, row j) of a field of `rows` rows at register offset `base`:
// along x by shuffles (lane W-1 of the last segment gets `edge`), along y within the segment.
struct Stencil { float c, left, right, down, up; };
Stencil stencilAt(uint base, uint rows, uint k, uint j, float edge) {
  uint r = base + k * rows + j, L = lane(), W = SIM_GROUP;
  Stencil s;
  s.c = reg[r];
  float prevSeg = reg[k > 0u ? r - rows : r];
  float next = reg[k + 1u < segs ? r + rows : r];  // indices clamped: never outside the array
  float nextSeg = k + 1u < segs ? next : edge;
  s.left = subgroupShuffle(L == W - 1u ? prevSeg : s.c, (L + W - 1u) & (W - 1u));
  s.right = subgroupShuffle(L == 0u ? nextSeg : s.c, (L + 1u) & (W - 1u));
  s.down = reg[j > 0u ? r - 1u : r];
  s.up = reg[j + 1u < rows ? r + 1u : r];
  return s;
}

// updateU / updateV of sim_fluid_diffuse.comp for one vector, reading the field at `src`.
float updateU(uint src, uint k, uint j) {
  uint n = f.n;
  Stencil s = stencilAt(src, n, k, j, reg[uEdge + j]);
  float sum = s.left + s.right, cnt = 2.0;
  if (j > 0u) { sum += s.down; cnt += 1.0; }
  if (j + 1u < n) { sum += s.up; cnt += 1.0; }
  return (reg[uB + k * n + j] + a * sum) / (1.0 + a * cnt);
}
float updateV(uint src, uint k, uint j) {
  uint n = f.n, x = k * SIM_GROUP + lane();
  Stencil s = stencilAt(src, n + 1u, k, j, 0.0);
  float sum = s.down + s.up, cnt = 2.0;
  if (x > 0u) { sum += s.left; cnt += 1.0; }
  if (x + 1u < n) { sum += s.right; cnt += 1.0; }
  return (reg[vB + k * (n + 1u) + j] + a * sum) / (1.0 + a * cnt);
}

void main() {
  LOAD_FRAME();
  uint n = f.n, B = velocityFloats(n), L = lane(), W = SIM_GROUP;
  a = f.dt * f.viscosity * float(n) * float(n);
  segs = n / W;
  uA = 0u;
  uB = segs * n;
  vA = 2u * segs * n;
  vB = vA + segs * (n + 1u);
  uEdge = vB + segs * (n + 1u);
  wallWindForce(B);
  SYNC();
  macBoundary(B);
  SYNC();
  for (uint k = 0u; k < segs; ++k) {
    uint x = k * W + L;
    for (uint j = 0u; j < n; ++j) reg[uB + k * n + j] = vel[B + macU(n, x, j)];
    for (uint j = 0u; j <= n; ++j) reg[vB + k * (n + 1u) + j] = vel[B + macV(n, x, j)];
  }
  for (uint j = 0u; j < n; ++j) reg[uEdge + j] = vel[B + macU(n, n, j)];
  // Jacobi sweep B -> A on interior faces; boundary faces (u columns 0 and n, v rows 0 and n) copied.
  for (uint k = 0u; k < segs; ++k) {
    uint x = k * W + L;
    for (uint j = 0u; j < n; ++j) {
      float u = updateU(uB, k, j);
      reg[uA + k * n + j] = x == 0u ? reg[uB + k * n + j] : u;
    }
    for (uint j = 0u; j <= n; ++j) {
      float v = j == 0u || j == n ? reg[vB + k * (n + 1u) + j] : updateV(vB, k, j);
      reg[vA + k * (n + 1u) + j] = v;
    }
  }
  // Red-black sweeps on A: a face of colour c has (i + j + c) even (the order of the other kernel
  // within a colour does not matter: faces of one colour do not neighbour each other).
  for (uint sweep = 0u; sweep < f.diffuseSweeps; ++sweep)
    for (uint color = 0u; color < 2u; ++color)
      for (uint k = 0u; k < segs; ++k) {
        uint x = k * W + L;
        bool mine = ((x + color) & 1u) == 0u;
        for (uint j = 0u; j < n; ++j) {
          uint r = uA + k * n + j;
          float u = updateU(uA, k, j);
          if (x > 0u && mine == ((j & 1u) == 0u)) reg[r] = u;
        }
        for (uint j = 1u; j < n; ++j) {
          uint r = vA + k * (n + 1u) + j;
          float v = updateV(vA, k, j);
          if (mine == ((j & 1u) == 0u)) reg[r] = v;
        }
      }
  for (uint k = 0u; k < segs; ++k) {
    uint x = k * W + L;
    for (uint j = 0u; j < n; ++j) vel[macU(n, x, j)] = reg[uA + k * n + j];
    for (uint j = 0u; j <= n; ++j) vel[macV(n, x, j)] = reg[vA + k * (n + 1u) + j];
  }
  if (L == 0u)
    for (uint j = 0u; j < n; ++j) vel[macU(n, n, j)] = reg[uEdge + j];
}
