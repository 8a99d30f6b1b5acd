#version 460
#extension GL_GOOGLE_include_directive : require
#define SIM_COHERENT
#define SIM_NO_GROUP_SUM
// MAC self-advection, semi-Lagrangian with bilinear sampling (Stam): every interior face of B is
// traced back through A. Boundary faces are left to the projection that follows (it sets them).
#include "sim_common.glsl"
layout(local_size_x = 8, local_size_y = 8) in;

float sampleU(float x, float y) {
  uint n = f.n;
  float fx = clamp(x, 0.0, float(n)), fy = clamp(y - 0.5, 0.0, float(n - 1u));
  uint i0 = uint(fx), j0 = uint(fy);
  uint i1 = min(i0 + 1u, n), j1 = min(j0 + 1u, n - 1u);
  float s = fx - float(i0), t = fy - float(j0);
  return (1.0 - t) * ((1.0 - s) * vel[macU(n, i0, j0)] + s * vel[macU(n, i1, j0)]) +
         t * ((1.0 - s) * vel[macU(n, i0, j1)] + s * vel[macU(n, i1, j1)]);
}
float sampleV(float x, float y) {
  uint n = f.n;
  float fx = clamp(x - 0.5, 0.0, float(n - 1u)), fy = clamp(y, 0.0, float(n));
  uint i0 = uint(fx), j0 = uint(fy);
  uint i1 = min(i0 + 1u, n - 1u), j1 = min(j0 + 1u, n);
  float s = fx - float(i0), t = fy - float(j0);
  return (1.0 - t) * ((1.0 - s) * vel[macV(n, i0, j0)] + s * vel[macV(n, i1, j0)]) +
         t * ((1.0 - s) * vel[macV(n, i0, j1)] + s * vel[macV(n, i1, j1)]);
}

void main() {
  LOAD_FRAME();
  uint n = f.n;
  uint i = gl_GlobalInvocationID.x, j = gl_GlobalInvocationID.y;
  uint B = velocityFloats(n);
  float dt0 = f.dt * float(n);
  if (i >= 1u && i < n && j < n) {
    float u = vel[macU(n, i, j)];
    float v = 0.25 * (vel[macV(n, i - 1u, j)] + vel[macV(n, i, j)] + vel[macV(n, i - 1u, j + 1u)] + vel[macV(n, i, j + 1u)]);
    vel[B + macU(n, i, j)] = sampleU(float(i) - dt0 * u, float(j) + 0.5 - dt0 * v);
  }
  if (i < n && j >= 1u && j < n) {
    float u = 0.25 * (vel[macU(n, i, j - 1u)] + vel[macU(n, i + 1u, j - 1u)] + vel[macU(n, i, j)] + vel[macU(n, i + 1u, j)]);
    float v = vel[macV(n, i, j)];
    vel[B + macV(n, i, j)] = sampleV(float(i) + 0.5 - dt0 * u, float(j) - dt0 * v);
  }
}
