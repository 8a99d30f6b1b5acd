#include "compute/sim_reference.h"

#include <algorithm>
#include <cmath>

namespace canopy::ref {
using namespace canopy::gpu;

SimState makeState(uint32_t n, uint32_t ringSize) {
  SimState s;
  s.n = n;
  s.ringSize = ringSize;
  s.velA.assign(velocityFloats(n), 0.0f);
  s.velB.assign(velocityFloats(n), 0.0f);
  s.mg.assign(mgFloats(n, mgLevelCount(n)), 0.0f);
  s.wave.assign(6 * size_t(n) * n, 0.0f);
  s.tiled.assign(2 * size_t(tiledVec2s(n)), 0.0f);
  s.ring.assign(size_t(ringSize) * 2 * n * n, 0.0f);
  s.ringTimes.assign(ringSize, 0.0f);
  return s;
}

namespace {

bool isSource(const SimFrame& f, uint side) { return (f.windSides & side) != 0; }
// The motors' mass source at p (shared/sim.h, motorSource), summed in the shaders' order.
float motorSources(const SimFrame& f, vec2 p) {
  float q = 0.0f;
  for (uint m = 0; m < f.motorCount; ++m) q += motorSource(f.motors[m], p);
  return q;
}
// Inflow is prescribed only in the tunnel; a closed box gets the wind as a body force instead.
bool isInflow(const SimFrame& f, uint side) { return f.boundary == SIM_BOUNDARY_TUNNEL && isSource(f, side); }
// Whether a side is open outflow (pressure 0) in the MAC scheme.
bool isOutflow(const SimFrame& f, uint side) { return f.boundary == SIM_BOUNDARY_TUNNEL && !isSource(f, side); }

// Boundary faces of a MAC field: inflow prescribed on source sides, 0 on walls, zero-gradient
// copy of the neighbouring interior face on outflow sides.
void macBoundary(const SimFrame& f, std::vector<float>& w) {
  const uint n = f.n;
  for (uint j = 0; j < n; ++j) {
    const float s = (float(j) + 0.5f) / float(n);
    w[macU(n, 0, j)] = isInflow(f, SIM_SIDE_LEFT) ? inflowSpeed(f, SIM_SIDE_LEFT, s)
                       : isOutflow(f, SIM_SIDE_LEFT) ? w[macU(n, 1, j)] : 0.0f;
    w[macU(n, n, j)] = isInflow(f, SIM_SIDE_RIGHT) ? -inflowSpeed(f, SIM_SIDE_RIGHT, s)
                       : isOutflow(f, SIM_SIDE_RIGHT) ? w[macU(n, n - 1, j)] : 0.0f;
  }
  for (uint i = 0; i < n; ++i) {
    const float s = (float(i) + 0.5f) / float(n);
    w[macV(n, i, 0)] = isInflow(f, SIM_SIDE_BOTTOM) ? inflowSpeed(f, SIM_SIDE_BOTTOM, s)
                       : isOutflow(f, SIM_SIDE_BOTTOM) ? w[macV(n, i, 1)] : 0.0f;
    w[macV(n, i, n)] = isInflow(f, SIM_SIDE_TOP) ? -inflowSpeed(f, SIM_SIDE_TOP, s)
                       : isOutflow(f, SIM_SIDE_TOP) ? w[macV(n, i, n - 1)] : 0.0f;
  }
}

// ---- multigrid (cell-centred, 5-point, Neumann on inflow/wall sides, Dirichlet 0 on outflow) ----
struct Sides {
  bool dl, dr, db, dt;  // Dirichlet on left/right/bottom/top
  bool anyDirichlet() const { return dl || dr || db || dt; }
};
Sides sidesOf(const SimFrame& f) {
  return {isOutflow(f, SIM_SIDE_LEFT), isOutflow(f, SIM_SIDE_RIGHT), isOutflow(f, SIM_SIDE_BOTTOM),
          isOutflow(f, SIM_SIDE_TOP)};
}

// (A p)_c = sum over faces of coef * (p_c - p_nb): interior faces coef 1, Dirichlet faces 2 against 0.
void relax(float* p, const float* b, uint m, const Sides& sd, uint color) {
  for (uint j = 0; j < m; ++j)
    for (uint i = 0; i < m; ++i) {
      if (((i + j) & 1u) != color) continue;
      float sum = 0.0f, diag = 0.0f;
      if (i > 0) { sum += p[j * m + i - 1]; diag += 1.0f; } else if (sd.dl) diag += 2.0f;
      if (i + 1 < m) { sum += p[j * m + i + 1]; diag += 1.0f; } else if (sd.dr) diag += 2.0f;
      if (j > 0) { sum += p[(j - 1) * m + i]; diag += 1.0f; } else if (sd.db) diag += 2.0f;
      if (j + 1 < m) { sum += p[(j + 1) * m + i]; diag += 1.0f; } else if (sd.dt) diag += 2.0f;
      p[j * m + i] = (sum + b[j * m + i]) / diag;
    }
}
float residualAt(const float* p, const float* b, uint m, const Sides& sd, uint i, uint j) {
  float c = p[j * m + i], ap = 0.0f;
  if (i > 0) ap += c - p[j * m + i - 1]; else if (sd.dl) ap += 2.0f * c;
  if (i + 1 < m) ap += c - p[j * m + i + 1]; else if (sd.dr) ap += 2.0f * c;
  if (j > 0) ap += c - p[(j - 1) * m + i]; else if (sd.db) ap += 2.0f * c;
  if (j + 1 < m) ap += c - p[(j + 1) * m + i]; else if (sd.dt) ap += 2.0f * c;
  return b[j * m + i] - ap;
}
void subtractMean(float* x, uint count) {
  double sum = 0.0;
  for (uint k = 0; k < count; ++k) sum += x[k];
  const float mean = float(sum / double(count));
  for (uint k = 0; k < count; ++k) x[k] -= mean;
}
// Value of the coarse correction at (I, J), reflecting out-of-range indices by the side's rule.
float ghosted(const float* e, uint m, const Sides& sd, int I, int J) {
  float s = 1.0f;
  if (I < 0) { I = 0; if (sd.dl) s = -s; }
  if (I >= int(m)) { I = int(m) - 1; if (sd.dr) s = -s; }
  if (J < 0) { J = 0; if (sd.db) s = -s; }
  if (J >= int(m)) { J = int(m) - 1; if (sd.dt) s = -s; }
  return s * e[J * int(m) + I];
}

void vCycle(const SimFrame& f, std::vector<float>& mg, const Sides& sd) {
  const uint n = f.n, L = f.mgLevels;
  const bool neumann = !sd.anyDirichlet();
  for (uint l = 0; l + 1 < L; ++l) {
    const uint m = n >> l, mc = m >> 1;
    float* p = &mg[mgOffset(n, l)];
    float* b = p + m * m;
    for (uint s = 0; s < SIM_MG_PRE_SWEEPS; ++s) { relax(p, b, m, sd, 0); relax(p, b, m, sd, 1); }
    float* pc = &mg[mgOffset(n, l + 1)];
    float* bc = pc + mc * mc;
    for (uint J = 0; J < mc; ++J)
      for (uint I = 0; I < mc; ++I) {
        // Restriction is the sum of the four children: the coarse operator is 4x the fine one.
        float r = residualAt(p, b, m, sd, 2 * I, 2 * J) + residualAt(p, b, m, sd, 2 * I + 1, 2 * J) +
                  residualAt(p, b, m, sd, 2 * I, 2 * J + 1) + residualAt(p, b, m, sd, 2 * I + 1, 2 * J + 1);
        bc[J * mc + I] = r;
        pc[J * mc + I] = 0.0f;
      }
    if (neumann) subtractMean(bc, mc * mc);
  }
  {
    const uint m = n >> (L - 1);
    float* p = &mg[mgOffset(n, L - 1)];
    float* b = p + m * m;
    for (uint s = 0; s < SIM_MG_COARSE_SWEEPS; ++s) { relax(p, b, m, sd, 0); relax(p, b, m, sd, 1); }
  }
  for (uint l = L - 1; l-- > 0;) {
    const uint m = n >> l, mc = m >> 1;
    float* p = &mg[mgOffset(n, l)];
    float* b = p + m * m;
    const float* e = &mg[mgOffset(n, l + 1)];
    for (uint j = 0; j < m; ++j)
      for (uint i = 0; i < m; ++i) {
        // Bilinear (cell-centred) prolongation: 9/16 own coarse cell, 3/16 the two nearest, 1/16 the diagonal.
        const int I = int(i >> 1), J = int(j >> 1), di = (i & 1u) ? 1 : -1, dj = (j & 1u) ? 1 : -1;
        p[j * m + i] += 0.5625f * ghosted(e, mc, sd, I, J) + 0.1875f * ghosted(e, mc, sd, I + di, J) +
                        0.1875f * ghosted(e, mc, sd, I, J + dj) + 0.0625f * ghosted(e, mc, sd, I + di, J + dj);
      }
    for (uint s = 0; s < SIM_MG_POST_SWEEPS; ++s) { relax(p, b, m, sd, 0); relax(p, b, m, sd, 1); }
  }
}

}  // namespace

void macProject(const SimFrame& f, std::vector<float>& w, std::vector<float>& mg) {
  const uint n = f.n;
  const float h = 1.0f / float(n);
  const Sides sd = sidesOf(f);
  macBoundary(f, w);
  float* p = &mg[0];
  float* b = p + n * n;
  // A p = -h^2 (div u - q): then div(u - grad p) = q in the MAC (compact) sense, q the motors' sources.
  for (uint j = 0; j < n; ++j)
    for (uint i = 0; i < n; ++i)
      b[j * n + i] = -h * (w[macU(n, i + 1, j)] - w[macU(n, i, j)] + w[macV(n, i, j + 1)] - w[macV(n, i, j)]) +
                     h * h * motorSources(f, vec2((float(i) + 0.5f) * h, (float(j) + 0.5f) * h));
  if (!sd.anyDirichlet()) subtractMean(b, n * n);
  for (uint c = 0; c < f.mgCycles; ++c) vCycle(f, mg, sd);
  if (!sd.anyDirichlet()) subtractMean(p, n * n);
  const float invh = float(n);
  for (uint j = 0; j < n; ++j)
    for (uint i = 1; i < n; ++i) w[macU(n, i, j)] -= (p[j * n + i] - p[j * n + i - 1]) * invh;
  for (uint j = 1; j < n; ++j)
    for (uint i = 0; i < n; ++i) w[macV(n, i, j)] -= (p[j * n + i] - p[(j - 1) * n + i]) * invh;
  // Outflow faces: the pressure outside is 0 (ghost = -p), so the face gradient is 2p/h.
  for (uint j = 0; j < n; ++j) {
    if (sd.dl) w[macU(n, 0, j)] -= 2.0f * p[j * n] * invh;
    if (sd.dr) w[macU(n, n, j)] += 2.0f * p[j * n + n - 1] * invh;
  }
  for (uint i = 0; i < n; ++i) {
    if (sd.db) w[macV(n, i, 0)] -= 2.0f * p[i] * invh;
    if (sd.dt) w[macV(n, i, n)] += 2.0f * p[(n - 1) * n + i] * invh;
  }
}

namespace {

float sampleU(const std::vector<float>& w, uint n, float x, float y) {
  // u lives at (i, j + 0.5) in cell units.
  float fx = std::clamp(x, 0.0f, float(n)), fy = std::clamp(y - 0.5f, 0.0f, float(n - 1));
  uint i0 = uint(fx), j0 = uint(fy);
  uint i1 = std::min(i0 + 1, n), j1 = std::min(j0 + 1, n - 1);
  float s = fx - float(i0), t = fy - float(j0);
  return (1 - t) * ((1 - s) * w[macU(n, i0, j0)] + s * w[macU(n, i1, j0)]) +
         t * ((1 - s) * w[macU(n, i0, j1)] + s * w[macU(n, i1, j1)]);
}
float sampleV(const std::vector<float>& w, uint n, float x, float y) {
  // v lives at (i + 0.5, j).
  float fx = std::clamp(x - 0.5f, 0.0f, float(n - 1)), fy = std::clamp(y, 0.0f, float(n));
  uint i0 = uint(fx), j0 = uint(fy);
  uint i1 = std::min(i0 + 1, n - 1), j1 = std::min(j0 + 1, n);
  float s = fx - float(i0), t = fy - float(j0);
  return (1 - t) * ((1 - s) * w[macV(n, i0, j0)] + s * w[macV(n, i1, j0)]) +
         t * ((1 - s) * w[macV(n, i0, j1)] + s * w[macV(n, i1, j1)]);
}

}  // namespace

void macFluidStep(const SimFrame& f, SimState& s) {
  const uint n = f.n;
  std::vector<float>& A = s.velA;
  std::vector<float>& B = s.velB;
  // 1. Sources: inflow boundaries (tunnel) or the wind as a force on the first interior faces
  //    (walls); the motors are mass sources, added in the projection.
  if (f.boundary == SIM_BOUNDARY_WALLS)
    for (uint t = 0; t < n; ++t) {
      const float s = (float(t) + 0.5f) / float(n);
      if (isSource(f, SIM_SIDE_LEFT)) B[macU(n, 1, t)] += f.dt * inflowSpeed(f, SIM_SIDE_LEFT, s);
      if (isSource(f, SIM_SIDE_RIGHT)) B[macU(n, n - 1, t)] -= f.dt * inflowSpeed(f, SIM_SIDE_RIGHT, s);
      if (isSource(f, SIM_SIDE_BOTTOM)) B[macV(n, t, 1)] += f.dt * inflowSpeed(f, SIM_SIDE_BOTTOM, s);
      if (isSource(f, SIM_SIDE_TOP)) B[macV(n, t, n - 1)] -= f.dt * inflowSpeed(f, SIM_SIDE_TOP, s);
    }
  macBoundary(f, B);
  // 2. Implicit diffusion (I - dt nu lap) A = B: one Jacobi sweep from B, then red-black
  //    Gauss-Seidel; free-slip across the tangential boundaries (missing neighbours drop out).
  const float a = f.dt * f.viscosity * float(n) * float(n);
  auto updU = [&](const std::vector<float>& src, uint i, uint j) {
    float sum = src[macU(n, i - 1, j)] + src[macU(n, i + 1, j)], cnt = 2.0f;
    if (j > 0) { sum += src[macU(n, i, j - 1)]; cnt += 1.0f; }
    if (j + 1 < n) { sum += src[macU(n, i, j + 1)]; cnt += 1.0f; }
    A[macU(n, i, j)] = (B[macU(n, i, j)] + a * sum) / (1.0f + a * cnt);
  };
  auto updV = [&](const std::vector<float>& src, uint i, uint j) {
    float sum = src[macV(n, i, j - 1)] + src[macV(n, i, j + 1)], cnt = 2.0f;
    if (i > 0) { sum += src[macV(n, i - 1, j)]; cnt += 1.0f; }
    if (i + 1 < n) { sum += src[macV(n, i + 1, j)]; cnt += 1.0f; }
    A[macV(n, i, j)] = (B[macV(n, i, j)] + a * sum) / (1.0f + a * cnt);
  };
  A = B;
  for (uint j = 0; j < n; ++j)
    for (uint i = 1; i < n; ++i) updU(B, i, j);
  for (uint j = 1; j < n; ++j)
    for (uint i = 0; i < n; ++i) updV(B, i, j);
  for (uint sweep = 0; sweep < f.diffuseSweeps; ++sweep)
    for (uint color = 0; color < 2; ++color) {
      for (uint j = 0; j < n; ++j)
        for (uint i = 1; i < n; ++i)
          if (((i + j) & 1u) == color) updU(A, i, j);
      for (uint j = 1; j < n; ++j)
        for (uint i = 0; i < n; ++i)
          if (((i + j) & 1u) == color) updV(A, i, j);
    }
  // 3. Project.
  macProject(f, A, s.mg);
  // 4. Self-advection (semi-Lagrangian, bilinear) A -> B.
  const float dt0 = f.dt * float(n);
  for (uint j = 0; j < n; ++j)
    for (uint i = 1; i < n; ++i) {
      float u = A[macU(n, i, j)];
      float v = 0.25f * (A[macV(n, i - 1, j)] + A[macV(n, i, j)] + A[macV(n, i - 1, j + 1)] + A[macV(n, i, j + 1)]);
      B[macU(n, i, j)] = sampleU(A, n, float(i) - dt0 * u, float(j) + 0.5f - dt0 * v);
    }
  for (uint j = 1; j < n; ++j)
    for (uint i = 0; i < n; ++i) {
      float u = 0.25f * (A[macU(n, i, j - 1)] + A[macU(n, i + 1, j - 1)] + A[macU(n, i, j)] + A[macU(n, i + 1, j)]);
      float v = A[macV(n, i, j)];
      B[macV(n, i, j)] = sampleV(A, n, float(i) + 0.5f - dt0 * u, float(j) - dt0 * v);
    }
  // 5. Project again.
  macProject(f, B, s.mg);
}

// ---- Stam's games-paper solver ------------------------------------------------------------------
namespace {

void setBnd(uint n, int b, float* x) {
  auto IX = [n](uint i, uint j) { return j * (n + 2) + i; };
  for (uint i = 1; i <= n; ++i) {
    x[IX(0, i)] = b == 1 ? -x[IX(1, i)] : x[IX(1, i)];
    x[IX(n + 1, i)] = b == 1 ? -x[IX(n, i)] : x[IX(n, i)];
    x[IX(i, 0)] = b == 2 ? -x[IX(i, 1)] : x[IX(i, 1)];
    x[IX(i, n + 1)] = b == 2 ? -x[IX(i, n)] : x[IX(i, n)];
  }
  x[IX(0, 0)] = 0.5f * (x[IX(1, 0)] + x[IX(0, 1)]);
  x[IX(0, n + 1)] = 0.5f * (x[IX(1, n + 1)] + x[IX(0, n)]);
  x[IX(n + 1, 0)] = 0.5f * (x[IX(n, 0)] + x[IX(n + 1, 1)]);
  x[IX(n + 1, n + 1)] = 0.5f * (x[IX(n, n + 1)] + x[IX(n + 1, n)]);
}

void linSolve(uint n, int b, float* x, const float* x0, float a, float c, uint iters, GsOrder order) {
  auto IX = [n](uint i, uint j) { return j * (n + 2) + i; };
  for (uint k = 0; k < iters; ++k) {
    if (order == GsOrder::Lexicographic) {
      for (uint j = 1; j <= n; ++j)
        for (uint i = 1; i <= n; ++i)
          x[IX(i, j)] = (x0[IX(i, j)] + a * (x[IX(i - 1, j)] + x[IX(i + 1, j)] + x[IX(i, j - 1)] + x[IX(i, j + 1)])) / c;
    } else {
      for (uint color = 0; color < 2; ++color)
        for (uint j = 1; j <= n; ++j)
          for (uint i = 1; i <= n; ++i)
            if (((i + j) & 1u) == color)
              x[IX(i, j)] =
                  (x0[IX(i, j)] + a * (x[IX(i - 1, j)] + x[IX(i + 1, j)] + x[IX(i, j - 1)] + x[IX(i, j + 1)])) / c;
    }
    setBnd(n, b, x);
  }
}

void stamAdvect(uint n, int b, float* d, const float* d0, const float* u, const float* v, float dt) {
  auto IX = [n](uint i, uint j) { return j * (n + 2) + i; };
  const float dt0 = dt * float(n);
  for (uint j = 1; j <= n; ++j)
    for (uint i = 1; i <= n; ++i) {
      float x = float(i) - dt0 * u[IX(i, j)], y = float(j) - dt0 * v[IX(i, j)];
      x = std::clamp(x, 0.5f, float(n) + 0.5f);
      y = std::clamp(y, 0.5f, float(n) + 0.5f);
      uint i0 = uint(x), j0 = uint(y), i1 = i0 + 1, j1 = j0 + 1;
      float s1 = x - float(i0), s0 = 1 - s1, t1 = y - float(j0), t0 = 1 - t1;
      d[IX(i, j)] = s0 * (t0 * d0[IX(i0, j0)] + t1 * d0[IX(i0, j1)]) + s1 * (t0 * d0[IX(i1, j0)] + t1 * d0[IX(i1, j1)]);
    }
  setBnd(n, b, d);
}

void stamProject(const SimFrame& f, float* u, float* v, float* p, float* div, GsOrder order) {
  const uint n = f.n, iters = f.iterations;
  const float h = 1.0f / float(n);
  auto IX = [n](uint i, uint j) { return j * (n + 2) + i; };
  // Motor sources enter as in the MAC scheme (div u = q); Stam's box has walls, so their net is
  // balanced by a uniform sink to keep the Neumann problem solvable.
  double qsum = 0.0;
  for (uint j = 1; j <= n; ++j)
    for (uint i = 1; i <= n; ++i) qsum += motorSources(f, vec2((float(i) - 0.5f) * h, (float(j) - 0.5f) * h));
  const float qmean = float(qsum / double(n * n));
  for (uint j = 1; j <= n; ++j)
    for (uint i = 1; i <= n; ++i) {
      div[IX(i, j)] = -0.5f * (u[IX(i + 1, j)] - u[IX(i - 1, j)] + v[IX(i, j + 1)] - v[IX(i, j - 1)]) / float(n) +
                      h * h * (motorSources(f, vec2((float(i) - 0.5f) * h, (float(j) - 0.5f) * h)) - qmean);
      p[IX(i, j)] = 0.0f;
    }
  setBnd(n, 0, div);
  setBnd(n, 0, p);
  linSolve(n, 0, p, div, 1.0f, 4.0f, iters, order);
  for (uint j = 1; j <= n; ++j)
    for (uint i = 1; i <= n; ++i) {
      u[IX(i, j)] -= 0.5f * float(n) * (p[IX(i + 1, j)] - p[IX(i - 1, j)]);
      v[IX(i, j)] -= 0.5f * float(n) * (p[IX(i, j + 1)] - p[IX(i, j - 1)]);
    }
  setBnd(n, 1, u);
  setBnd(n, 2, v);
}

}  // namespace

// Stam-mode sources: the boundary wind as a body force on the first interior row/column of each
// source side (a closed box cannot carry a through-flow); motors enter the projection.
void stamSources(const SimFrame& f, float* u0, float* v0) {
  const uint n = f.n;
  const float h = 1.0f / float(n);
  auto IX = [n](uint i, uint j) { return j * (n + 2) + i; };
  for (uint j = 0; j < n + 2; ++j)
    for (uint i = 0; i < n + 2; ++i) {
      vec2 a = vec2(0.0f, 0.0f);
      if (i >= 1 && i <= n && j >= 1 && j <= n) {
        const float sy = (float(j) - 0.5f) * h, sx = (float(i) - 0.5f) * h;
        if (i == 1 && (f.windSides & SIM_SIDE_LEFT)) a.x += inflowSpeed(f, SIM_SIDE_LEFT, sy);
        if (i == n && (f.windSides & SIM_SIDE_RIGHT)) a.x -= inflowSpeed(f, SIM_SIDE_RIGHT, sy);
        if (j == 1 && (f.windSides & SIM_SIDE_BOTTOM)) a.y += inflowSpeed(f, SIM_SIDE_BOTTOM, sx);
        if (j == n && (f.windSides & SIM_SIDE_TOP)) a.y -= inflowSpeed(f, SIM_SIDE_TOP, sx);
      }
      u0[IX(i, j)] = a.x;
      v0[IX(i, j)] = a.y;
    }
}

void stamVelStep(const SimFrame& f, SimState& s, GsOrder order) {
  const uint n = f.n, sz = (n + 2) * (n + 2);
  float* U = &s.velA[0];
  float* V = U + sz;
  float* U0 = &s.velB[0];
  float* V0 = U0 + sz;
  stamSources(f, U0, V0);
  for (uint k = 0; k < sz; ++k) { U[k] += f.dt * U0[k]; V[k] += f.dt * V0[k]; }
  const float a = f.dt * f.viscosity * float(n) * float(n);
  // SWAP(u0,u); diffuse(u, u0): the diffused field goes to U0, V0, whose old contents (the
  // sources) are Gauss-Seidel's starting guess, exactly as in Stam's code.
  linSolve(n, 1, U0, U, a, 1 + 4 * a, f.iterations, order);
  linSolve(n, 2, V0, V, a, 1 + 4 * a, f.iterations, order);
  stamProject(f, U0, V0, U, V, order);
  // SWAP back; advect(u, u0 by (u0, v0)).
  stamAdvect(n, 1, U, U0, U0, V0, f.dt);
  stamAdvect(n, 2, V, V0, U0, V0, f.dt);
  stamProject(f, U, V, U0, V0, order);
}

double stamLowestModeRemoval(uint32_t n, uint32_t iterations, GsOrder order) {
  SimFrame f{};
  f.n = n;
  f.iterations = iterations;
  const uint32_t sz = (n + 2) * (n + 2);
  std::vector<float> u(sz, 0.0f), v(sz, 0.0f), p(sz), div(sz);
  const double pi = 3.14159265358979323846;
  for (uint32_t j = 1; j <= n; ++j)
    for (uint32_t i = 1; i <= n; ++i) u[j * (n + 2) + i] = float(-pi * std::sin(pi * (i - 0.5) / n));
  setBnd(n, 1, u.data());
  auto energy = [&] {
    double e = 0;
    for (uint32_t j = 1; j <= n; ++j)
      for (uint32_t i = 1; i <= n; ++i) e += double(u[j * (n + 2) + i]) * u[j * (n + 2) + i] + double(v[j * (n + 2) + i]) * v[j * (n + 2) + i];
    return e;
  };
  const double before = energy();
  stamProject(f, u.data(), v.data(), p.data(), div.data(), order);
  return 1.0 - energy() / before;
}

// ---- wave oscillator and tiling ---------------------------------------------------------------
std::vector<float> cellVelocity(const SimFrame& f, const SimState& s) {
  const uint n = f.n;
  std::vector<float> out(2 * size_t(n) * n);
  const std::vector<float>& w = f.scheme == SIM_SCHEME_STAM ? s.velA : s.velB;
  for (uint j = 0; j < n; ++j)
    for (uint i = 0; i < n; ++i) {
      const uint c = j * n + i;
      if (f.scheme == SIM_SCHEME_STAM) {
        out[2 * c] = w[stamIX(n, 0, i + 1, j + 1)];
        out[2 * c + 1] = w[stamIX(n, 1, i + 1, j + 1)];
      } else {
        out[2 * c] = 0.5f * (w[macU(n, i, j)] + w[macU(n, i + 1, j)]);
        out[2 * c + 1] = 0.5f * (w[macV(n, i, j)] + w[macV(n, i, j + 1)]);
      }
    }
  return out;
}

void waveStep(const SimFrame& f, SimState& s) {
  const uint n = f.n, nn = n * n;
  std::vector<float> wind = cellVelocity(f, s);
  float* V = &s.wave[0];
  float* P = &s.wave[2 * nn];
  float* W = &s.wave[4 * nn];
  std::copy(wind.begin(), wind.end(), W);
  const float dt = f.waveDt, damp = 1.0f - f.waveZeta * dt, c2 = f.waveC * f.waveC * float(n) * float(n);
  std::vector<float> next(2 * nn);
  for (uint sub = 0; sub < f.waveSubsteps; ++sub) {
    for (uint j = 0; j < n; ++j)
      for (uint i = 0; i < n; ++i)
        for (uint k = 0; k < 2; ++k) {
          const uint c = j * n + i;
          const float x = V[2 * c + k];
          // Neumann (mirror) edges: a missing neighbour equals the cell itself.
          const float l = i > 0 ? V[2 * (c - 1) + k] : x, r = i + 1 < n ? V[2 * (c + 1) + k] : x;
          const float d = j > 0 ? V[2 * (c - n) + k] : x, u = j + 1 < n ? V[2 * (c + n) + k] : x;
          const float lap = (l + r + d + u - 4.0f * x) * c2;
          next[2 * c + k] = x + damp * (x - P[2 * c + k]) + dt * dt * (lap - f.waveK * (x - f.waveGain * W[2 * c + k]));
        }
    std::copy(V, V + 2 * nn, P);
    std::copy(next.begin(), next.end(), V);
  }
}

void tile(const SimFrame& f, SimState& s) {
  const uint n = f.n, half = n / 2;
  float* ring = &s.ring[size_t(f.ringSlot) * 2 * n * n];
  // V_s into the plants' field and the ring; V_wind (after V_s and V_prev in the wave buffer) into
  // the host's (shaders/sim_tile.comp).
  for (uint field = 0; field < 2; ++field) {
    const float* S = &s.wave[field == 0 ? 0 : 2 * size_t(waveWind(n, 0))];
    float* out = &s.tiled[field == 0 ? 0 : 2 * size_t(tiledWindOffset(n))];
    for (uint j = 0; j < n; ++j)
      for (uint i = 0; i < n; ++i) {
        const uint i2 = (i + half) % n, j2 = (j + half) % n;
        const float wx = tileWeight(i, n), wy = tileWeight(j, n);
        for (uint k = 0; k < 2; ++k) {
          float t = wy * (wx * S[2 * (j * n + i) + k] + (1 - wx) * S[2 * (j * n + i2) + k]) +
                    (1 - wy) * (wx * S[2 * (j2 * n + i) + k] + (1 - wx) * S[2 * (j2 * n + i2) + k]);
          out[2 * (j * n + i) + k] = t;
          if (field == 0) ring[2 * (j * n + i) + k] = t;
        }
      }
  }
  // The pushers' bend field, each cell a damped spring toward the motors' target (the shader's
  // substeps and order).
  const uint bn = SIM_BEND_SCALE * n;
  for (uint j = 0; j < bn; ++j)
    for (uint i = 0; i < bn; ++i) {
      const uint b = j * bn + i;
      float* value = &s.tiled[2 * size_t(bendOffset(n) + b)];
      float* rate = &s.tiled[2 * size_t(bendRateOffset(n) + b)];
      vec2 v(value[0], value[1]), r(rate[0], rate[1]);
      vec3 target(0.0f);
      const vec2 p = bendCellCentre(n, i, j);
      float* reach = &s.tiled[2 * size_t(bendReachOffset(n) + b)];
      bool touched = false;
      for (uint m = 0; m < f.motorCount; ++m) {
        const vec3 t = motorBendTarget(f.motors[m], p);
        target += t;
        if (t.z > 0.0f) {
          const vec2 mine(f.motors[m].bend.z, f.motors[m].bend.w);
          const vec2 kept = touched ? glm::max(vec2(reach[0], reach[1]), mine) : mine;
          reach[0] = kept.x, reach[1] = kept.y;
          touched = true;
        }
      }
      const uint steps = uint(std::clamp(std::ceil(f.dt * 120.0f), 1.0f, 1200.0f));
      const float h = f.dt / float(steps);
      for (uint k = 0; k < steps; ++k) bendSubstep(v, r, target, f.bendK, f.bendZeta, h);
      value[0] = v.x, value[1] = v.y, rate[0] = r.x, rate[1] = r.y;
    }
  s.ringTimes[f.ringSlot] = f.time + f.dt;
}

void step(const SimFrame& f, SimState& s, GsOrder stamOrder) {
  if (f.scheme == SIM_SCHEME_STAM) stamVelStep(f, s, stamOrder);
  else macFluidStep(f, s);
  waveStep(f, s);
  tile(f, s);
}

double macMaxDivergence(uint32_t n, const std::vector<float>& w) {
  double worst = 0.0;
  for (uint j = 0; j < n; ++j)
    for (uint i = 0; i < n; ++i)
      worst = std::max(worst, std::fabs(double(w[macU(n, i + 1, j)]) - w[macU(n, i, j)] + w[macV(n, i, j + 1)] -
                                        w[macV(n, i, j)]) * n);
  return worst;
}

}  // namespace canopy::ref
