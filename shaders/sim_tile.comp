#version 460
#extension GL_GOOGLE_include_directive : require
#define SIM_COHERENT
#define SIM_NO_GROUP_SUM
// Tiling (paper 3.3, docs/design.md): T(x) = w(x) S(x) + (1 - w(x)) S(x + N/2 mod N) on each axis,
// w linear, 1 at the tile centre and 0 at its edges, so opposite edges of T join without a seam
// and later passes can sample it with fract(). The oscillator's V_s goes into `tiled` and the
// history ring slot; the wind V_wind, tiled the same way, after it (the field a host reads:
// docs/design.md "The wind a host reads"). The invocations over the (2n)^2 bend cells also step
// the pushers' bend field (docs/design.md "Pushers"), which is not tiled.
#include "sim_common.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

vec2 tileOf(uint base, uint i, uint j, uint i2, uint j2, float wx, float wy) {
  uint n = f.n;
  return wy * (wx * wave[base + j * n + i] + (1.0 - wx) * wave[base + j * n + i2]) +
         (1.0 - wy) * (wx * wave[base + j2 * n + i] + (1.0 - wx) * wave[base + j2 * n + i2]);
}

void main() {
  LOAD_FRAME();
  uint n = f.n, halfN = n / 2u;
  uint i = gl_GlobalInvocationID.x, j = gl_GlobalInvocationID.y;
  uint bn = SIM_BEND_SCALE * n;
  if (i >= bn || j >= bn) return;
  // The bend field (shared/sim.h bendSubstep): substeps of at most 1/120 s.
  uint b = j * bn + i;
  vec2 value = tiled[bendOffset(n) + b], rate = tiled[bendRateOffset(n) + b];
  vec3 target = vec3(0.0);
  vec2 p = bendCellCentre(n, i, j);
  vec2 reach = tiled[bendReachOffset(n) + b];
  bool touched = false;
  for (uint m = 0u; m < f.motorCount; ++m) {
    vec3 t = motorBendTarget(f.motors[m], p);
    target += t;
    if (t.z > 0.0) {  // the reach of the pushers touching it now (their trail keeps the last)
      reach = touched ? max(reach, vec2(f.motors[m].bend.z, f.motors[m].bend.w)) : vec2(f.motors[m].bend.z, f.motors[m].bend.w);
      touched = true;
    }
  }
  tiled[bendReachOffset(n) + b] = reach;
  uint steps = uint(clamp(ceil(f.dt * 120.0), 1.0, 1200.0));
  float h = f.dt / float(steps);
  for (uint s = 0u; s < steps; ++s) bendSubstep(value, rate, target, f.bendK, f.bendZeta, h);
  tiled[bendOffset(n) + b] = value;
  tiled[bendRateOffset(n) + b] = rate;
  if (i >= n || j >= n) return;
  uint i2 = (i + halfN) % n, j2 = (j + halfN) % n;
  float wx = tileWeight(i, n), wy = tileWeight(j, n);
  vec2 t = tileOf(0u, i, j, i2, j2, wx, wy);
  tiled[j * n + i] = t;
  tiled[tiledWindOffset(n) + j * n + i] = tileOf(waveWind(n, 0u), i, j, i2, j2, wx, wy);
  ring[f.ringSlot * n * n + j * n + i] = t;
  if (i == 0u && j == 0u) ringTimes[f.ringSlot] = f.time + f.dt;
}
