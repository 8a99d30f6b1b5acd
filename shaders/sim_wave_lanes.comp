#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
// The wave oscillator, lane-blocked for CPU devices: the same substeps as sim_wave.comp (same
// per-cell arithmetic) with V, V- and V_wind in registers for all f.waveSubsteps substeps — one
// subgroup of W = SIM_GROUP lanes, lane L holding the columns k W + L of every row (layout and
// reason: sim_fluid_project_lanes.comp, docs/performance.md "Simulation step").
#include "sim_common.glsl"
layout(local_size_x_id = 0) in;  // SIM_GROUP == the subgroup size (compute/simulation.cpp checks)

// vec2 per lane: three fields of (n / W) x n (compute/simulation.cpp, the lane kernels' sizes).
layout(constant_id = 1) const uint SIM_LANE_FLOATS = 1u;
vec2 reg[SIM_LANE_FLOATS];

void main() {
  LOAD_FRAME();
  uint n = f.n, nn = n * n, L = gl_SubgroupInvocationID, W = SIM_GROUP, segs = n / W, field = segs * n;
  uint windOff = 2u * field;
  for (uint k = 0u; k < segs; ++k) {
    uint i = k * W + L;
    for (uint j = 0u; j < n; ++j) {
      uint c = j * n + i;
      vec2 w;
      if (f.scheme == SIM_SCHEME_STAM) {
        w = vec2(vel[stamIX(n, 0u, i + 1u, j + 1u)], vel[stamIX(n, 1u, i + 1u, j + 1u)]);
      } else {
        uint B = velocityFloats(n);
        w = vec2(0.5 * (vel[B + macU(n, i, j)] + vel[B + macU(n, i + 1u, j)]),
                 0.5 * (vel[B + macV(n, i, j)] + vel[B + macV(n, i, j + 1u)]));
      }
      wave[waveWind(n, c)] = w;
      uint r = k * n + j;
      reg[windOff + r] = w;
      reg[r] = wave[c];
      reg[field + r] = wave[nn + c];
    }
  }
  float dt = f.waveDt, damp = 1.0 - f.waveZeta * dt, c2 = f.waveC * f.waveC * float(n) * float(n);
  // The newest state at register offset cur, the previous one at prev; each substep overwrites the
  // previous one in place (it is read only at the same cell), then the two swap.
  uint cur = 0u, prev = field;
  for (uint sub = 0u; sub < f.waveSubsteps; ++sub) {
    for (uint k = 0u; k < segs; ++k) {
      uint i = k * W + L;
      for (uint j = 0u; j < n; ++j) {
        uint r = cur + k * n + j;
        vec2 x = reg[r];
        vec2 prevSeg = reg[k > 0u ? r - n : r], nextSeg = reg[k + 1u < segs ? r + n : r];
        vec2 left = subgroupShuffle(L == W - 1u ? prevSeg : x, (L + W - 1u) & (W - 1u));
        vec2 right = subgroupShuffle(L == 0u ? nextSeg : x, (L + 1u) & (W - 1u));
        vec2 l = i > 0u ? left : x;
        vec2 rr = i + 1u < n ? right : x;
        vec2 below = reg[j > 0u ? r - 1u : r], above = reg[j + 1u < n ? r + 1u : r];  // clamped indices
        vec2 d = j > 0u ? below : x;
        vec2 u = j + 1u < n ? above : x;
        vec2 lap = (l + rr + d + u - 4.0 * x) * c2;
        uint p = prev + k * n + j;
        reg[p] = x + damp * (x - reg[p]) + dt * dt * (lap - f.waveK * (x - f.waveGain * reg[windOff + k * n + j]));
      }
    }
    uint t = cur;
    cur = prev;
    prev = t;
  }
  // The newest state to slot 0, the previous to slot 1 (as the other kernel's final swap leaves them).
  for (uint k = 0u; k < segs; ++k) {
    uint i = k * W + L;
    for (uint j = 0u; j < n; ++j) {
      wave[j * n + i] = reg[cur + k * n + j];
      wave[nn + j * n + i] = reg[prev + k * n + j];
    }
  }
}
