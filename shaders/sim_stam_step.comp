#version 460
#extension GL_GOOGLE_include_directive : require
// Stam's "Real-Time Fluid Dynamics for Games" velocity step on his collocated (N+2)^2 grid with
// his set_bnd walls: add_source, diffuse, project, advect, project. Gauss-Seidel is red-black
// here (lexicographic order is inherently serial); f.iterations sweeps per linear solve.
// Field A (offset 0) holds u, v; field B holds u0, v0. One workgroup.
#include "sim_common.glsl"
layout(local_size_x_id = 0) in;  // SIM_GROUP

uint IX(uint arr, uint i, uint j) {  // arr: 0 u, 1 v, 2 u0, 3 v0
  uint n = f.n, sz = (n + 2u) * (n + 2u);
  return (arr >> 1u) * velocityFloats(n) + (arr & 1u) * sz + j * (n + 2u) + i;
}

void setBnd(int b, uint x) {
  uint n = f.n;
  FOR_EACH(k, n) {
    uint i = k + 1u;
    vel[IX(x, 0u, i)] = b == 1 ? -vel[IX(x, 1u, i)] : vel[IX(x, 1u, i)];
    vel[IX(x, n + 1u, i)] = b == 1 ? -vel[IX(x, n, i)] : vel[IX(x, n, i)];
    vel[IX(x, i, 0u)] = b == 2 ? -vel[IX(x, i, 1u)] : vel[IX(x, i, 1u)];
    vel[IX(x, i, n + 1u)] = b == 2 ? -vel[IX(x, i, n)] : vel[IX(x, i, n)];
  }
  SYNC();
  if (gl_LocalInvocationIndex == 0u) {
    vel[IX(x, 0u, 0u)] = 0.5 * (vel[IX(x, 1u, 0u)] + vel[IX(x, 0u, 1u)]);
    vel[IX(x, 0u, n + 1u)] = 0.5 * (vel[IX(x, 1u, n + 1u)] + vel[IX(x, 0u, n)]);
    vel[IX(x, n + 1u, 0u)] = 0.5 * (vel[IX(x, n, 0u)] + vel[IX(x, n + 1u, 1u)]);
    vel[IX(x, n + 1u, n + 1u)] = 0.5 * (vel[IX(x, n, n + 1u)] + vel[IX(x, n + 1u, n)]);
  }
  SYNC();
}

void linSolve(int b, uint x, uint x0, float a, float c) {
  uint n = f.n, hn = n >> 1u;  // n is even: each row holds n/2 cells of each colour
  for (uint it = 0u; it < f.iterations; ++it) {
    for (uint color = 0u; color < 2u; ++color) {
      FOR_EACH(k, n * hn) {
        uint j = 1u + k / hn;
        uint i = 1u + 2u * (k % hn) + ((j + 1u + color) & 1u);
        vel[IX(x, i, j)] = (vel[IX(x0, i, j)] + a * (vel[IX(x, i - 1u, j)] + vel[IX(x, i + 1u, j)] +
                                                     vel[IX(x, i, j - 1u)] + vel[IX(x, i, j + 1u)])) / c;
      }
      SYNC();
    }
    setBnd(b, x);
  }
}

void advect(int b, uint d, uint d0, uint uu, uint vv) {
  uint n = f.n;
  float dt0 = f.dt * float(n);
  FOR_EACH(k, n * n) {
    uint i = 1u + k % n, j = 1u + k / n;
    float x = clamp(float(i) - dt0 * vel[IX(uu, i, j)], 0.5, float(n) + 0.5);
    float y = clamp(float(j) - dt0 * vel[IX(vv, i, j)], 0.5, float(n) + 0.5);
    uint i0 = uint(x), j0 = uint(y), i1 = i0 + 1u, j1 = j0 + 1u;
    float s1 = x - float(i0), s0 = 1.0 - s1, t1 = y - float(j0), t0 = 1.0 - t1;
    vel[IX(d, i, j)] = s0 * (t0 * vel[IX(d0, i0, j0)] + t1 * vel[IX(d0, i0, j1)]) +
                       s1 * (t0 * vel[IX(d0, i1, j0)] + t1 * vel[IX(d0, i1, j1)]);
  }
  SYNC();
  setBnd(b, d);
}

void project(uint u, uint v, uint p, uint div) {
  uint n = f.n;
  float h = 1.0 / float(n);
  // Motor sources (our extension: Stam's box has walls, so their net is balanced by a uniform sink
  // to keep the Neumann problem solvable).
  float qsum = 0.0;
  if (f.motorCount > 0u) {
    FOR_EACH(k, n * n) qsum += motorSourcesAt(vec2((float(k % n) + 0.5) * h, (float(k / n) + 0.5) * h));
    qsum = groupSum(qsum);
  }
  float qmean = qsum / float(n * n);
  FOR_EACH(k, n * n) {
    uint i = 1u + k % n, j = 1u + k / n;
    vel[IX(div, i, j)] = -0.5 * (vel[IX(u, i + 1u, j)] - vel[IX(u, i - 1u, j)] + vel[IX(v, i, j + 1u)] - vel[IX(v, i, j - 1u)]) / float(n) +
                         h * h * (motorSourcesAt(vec2((float(i) - 0.5) * h, (float(j) - 0.5) * h)) - qmean);
    vel[IX(p, i, j)] = 0.0;
  }
  SYNC();
  setBnd(0, div);
  setBnd(0, p);
  linSolve(0, p, div, 1.0, 4.0);
  FOR_EACH(k, n * n) {
    uint i = 1u + k % n, j = 1u + k / n;
    vel[IX(u, i, j)] -= 0.5 * float(n) * (vel[IX(p, i + 1u, j)] - vel[IX(p, i - 1u, j)]);
    vel[IX(v, i, j)] -= 0.5 * float(n) * (vel[IX(p, i, j + 1u)] - vel[IX(p, i, j - 1u)]);
  }
  SYNC();
  setBnd(1, u);
  setBnd(2, v);
}

void main() {
  LOAD_FRAME();
  uint n = f.n;
  float h = 1.0 / float(n);
  // Sources: boundary wind as a body force on the first interior row/column (motors: in project()).
  FOR_EACH(k, (n + 2u) * (n + 2u)) {
    uint i = k % (n + 2u), j = k / (n + 2u);
    vec2 a = vec2(0.0);
    if (i >= 1u && i <= n && j >= 1u && j <= n) {
      float sy = (float(j) - 0.5) * h, sx = (float(i) - 0.5) * h;
      if (i == 1u && isSource(SIM_SIDE_LEFT)) a.x += inflowSpeed(f, SIM_SIDE_LEFT, sy);
      if (i == n && isSource(SIM_SIDE_RIGHT)) a.x -= inflowSpeed(f, SIM_SIDE_RIGHT, sy);
      if (j == 1u && isSource(SIM_SIDE_BOTTOM)) a.y += inflowSpeed(f, SIM_SIDE_BOTTOM, sx);
      if (j == n && isSource(SIM_SIDE_TOP)) a.y -= inflowSpeed(f, SIM_SIDE_TOP, sx);
    }
    vel[IX(2u, i, j)] = a.x;
    vel[IX(3u, i, j)] = a.y;
    vel[IX(0u, i, j)] += f.dt * a.x;  // add_source
    vel[IX(1u, i, j)] += f.dt * a.y;
  }
  SYNC();
  float a = f.dt * f.viscosity * float(n) * float(n);
  linSolve(1, 2u, 0u, a, 1.0 + 4.0 * a);  // SWAP(u0, u); diffuse: u0 <- diffuse(u)
  linSolve(2, 3u, 1u, a, 1.0 + 4.0 * a);
  project(2u, 3u, 0u, 1u);
  advect(1, 0u, 2u, 2u, 3u);  // SWAP back; advect u from u0 by (u0, v0)
  advect(2, 1u, 3u, 2u, 3u);
  project(0u, 1u, 2u, 3u);
}
