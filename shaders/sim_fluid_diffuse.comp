#version 460
#extension GL_GOOGLE_include_directive : require
// MAC scheme, first part of Stam's velocity step: add sources (inflow boundaries) to B, then the
// implicit diffusion (I - dt nu lap) A = B: one Jacobi sweep from B (doubles as the copy into A),
// then f.diffuseSweeps red-black Gauss-Seidel sweeps. Free-slip across tangential boundaries
// (missing neighbours drop out). One workgroup.
#include "sim_common.glsl"
layout(local_size_x_id = 0) in;  // SIM_GROUP

float a;

void updateU(uint src, uint i, uint j) {
  uint n = f.n;
  float sum = vel[src + macU(n, i - 1u, j)] + vel[src + macU(n, i + 1u, j)], cnt = 2.0;
  if (j > 0u) { sum += vel[src + macU(n, i, j - 1u)]; cnt += 1.0; }
  if (j + 1u < n) { sum += vel[src + macU(n, i, j + 1u)]; cnt += 1.0; }
  vel[macU(n, i, j)] = (vel[velocityFloats(n) + macU(n, i, j)] + a * sum) / (1.0 + a * cnt);
}
void updateV(uint src, uint i, uint j) {
  uint n = f.n;
  float sum = vel[src + macV(n, i, j - 1u)] + vel[src + macV(n, i, j + 1u)], cnt = 2.0;
  if (i > 0u) { sum += vel[src + macV(n, i - 1u, j)]; cnt += 1.0; }
  if (i + 1u < n) { sum += vel[src + macV(n, i + 1u, j)]; cnt += 1.0; }
  vel[macV(n, i, j)] = (vel[velocityFloats(n) + macV(n, i, j)] + a * sum) / (1.0 + a * cnt);
}

void main() {
  LOAD_FRAME();
  uint n = f.n, hn = n >> 1u;
  uint B = velocityFloats(n);
  a = f.dt * f.viscosity * float(n) * float(n);
  // Sources: inflow boundaries (tunnel) or wind forces (walls); motors are mass sources in the projection.
  wallWindForce(B);
  SYNC();
  macBoundary(B);
  SYNC();
  // Jacobi sweep B -> A on interior faces; boundary faces copied.
  FOR_EACH(k, macFloats(n)) {
    bool isU = k < (n + 1u) * n;
    uint q = isU ? k : k - (n + 1u) * n;
    if (isU) {
      uint i = q % (n + 1u), j = q / (n + 1u);
      if (i == 0u || i == n) vel[k] = vel[B + k];
      else updateU(B, i, j);
    } else {
      uint i = q % n, j = q / n;
      if (j == 0u || j == n) vel[k] = vel[B + k];
      else updateV(B, i, j);
    }
  }
  SYNC();
  for (uint sweep = 0u; sweep < f.diffuseSweeps; ++sweep) {
    for (uint color = 0u; color < 2u; ++color) {
      // u faces of this colour: rows j in [0, n), i from i0 in {1, 2} by 2 up to n - 1;
      // v faces: rows j in [1, n), i from (color + j) & 1 by 2 (n/2 a row).
      FOR_EACH(k, n * hn + (n - 1u) * hn) {
        if (k < n * hn) {
          uint j = k / hn;
          uint i = 2u - ((color + j) & 1u) + 2u * (k % hn);
          if (i < n) updateU(0u, i, j);
        } else {
          uint q = k - n * hn;
          uint j = 1u + q / hn;
          updateV(0u, ((color + j) & 1u) + 2u * (q % hn), j);
        }
      }
      SYNC();
    }
  }
}
