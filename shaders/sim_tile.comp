#version 460
#extension GL_GOOGLE_include_directive : require
#define SIM_COHERENT
#define SIM_NO_GROUP_SUM
// Tiling (paper 3.3, docs/design.md): T(x) = w(x) S(x) + (1 - w(x)) S(x + N/2 mod N) on each axis,
// w linear, 1 at the tile centre and 0 at its edges, so opposite edges of T join without a seam
// and later passes can sample it with fract(). The result also goes into the history ring slot.
#include "sim_common.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

void main() {
  LOAD_FRAME();
  uint n = f.n, halfN = n / 2u;
  uint i = gl_GlobalInvocationID.x, j = gl_GlobalInvocationID.y;
  if (i >= n || j >= n) return;
  uint i2 = (i + halfN) % n, j2 = (j + halfN) % n;
  float wx = tileWeight(i, n), wy = tileWeight(j, n);
  vec2 t = wy * (wx * wave[j * n + i] + (1.0 - wx) * wave[j * n + i2]) +
           (1.0 - wy) * (wx * wave[j2 * n + i] + (1.0 - wx) * wave[j2 * n + i2]);
  tiled[j * n + i] = t;
  ring[f.ringSlot * n * n + j * n + i] = t;
  if (i == 0u && j == 0u) ringTimes[f.ringSlot] = f.time + f.dt;
}
