// Multigrid helpers of the MAC projection (docs/design.md, "Stable fluids"), shared by the
// workgroup-wide kernel (sim_fluid_project.comp) and the lane-blocked one for CPU devices
// (sim_fluid_project_lanes.comp): the same cell operations in the same order, so both match the CPU
// reference (compute/sim_reference.cpp) to float rounding.
#include "sim_common.glsl"

bool dl, dr, db, dtop;  // Dirichlet sides (outflow)

// Subtracts the mean of mg[off .. off+count) (pure-Neumann compatibility / null space).
void subtractMean(uint off, uint count) {
  float s = 0.0;
  FOR_EACH(k, count) s += mg[off + k];
  float mean = groupSum(s) / float(count);
  FOR_EACH(k, count) mg[off + k] -= mean;
  SYNC();
}

void relaxCell(uint po, uint bo, uint m, uint i, uint j) {
  float sum = 0.0, diag = 0.0;
  if (i > 0u) { sum += mg[po + j * m + i - 1u]; diag += 1.0; } else if (dl) diag += 2.0;
  if (i + 1u < m) { sum += mg[po + j * m + i + 1u]; diag += 1.0; } else if (dr) diag += 2.0;
  if (j > 0u) { sum += mg[po + (j - 1u) * m + i]; diag += 1.0; } else if (db) diag += 2.0;
  if (j + 1u < m) { sum += mg[po + (j + 1u) * m + i]; diag += 1.0; } else if (dtop) diag += 2.0;
  mg[po + j * m + i] = (sum + mg[bo + j * m + i]) / diag;
}

float residualAt(uint po, uint bo, uint m, uint i, uint j) {
  float c = mg[po + j * m + i], ap = 0.0;
  if (i > 0u) ap += c - mg[po + j * m + i - 1u]; else if (dl) ap += 2.0 * c;
  if (i + 1u < m) ap += c - mg[po + j * m + i + 1u]; else if (dr) ap += 2.0 * c;
  if (j > 0u) ap += c - mg[po + (j - 1u) * m + i]; else if (db) ap += 2.0 * c;
  if (j + 1u < m) ap += c - mg[po + (j + 1u) * m + i]; else if (dtop) ap += 2.0 * c;
  return mg[bo + j * m + i] - ap;
}

void restrictCell(uint po, uint bo, uint m, uint pco, uint bco, uint k) {
  uint mc = m >> 1u, I = k & (mc - 1u), J = k >> findMSB(mc);
  // The sum of the four children: the coarse operator is 4x the fine one.
  mg[bco + k] = residualAt(po, bo, m, 2u * I, 2u * J) + residualAt(po, bo, m, 2u * I + 1u, 2u * J) +
                residualAt(po, bo, m, 2u * I, 2u * J + 1u) + residualAt(po, bo, m, 2u * I + 1u, 2u * J + 1u);
  mg[pco + k] = 0.0;
}

float ghosted(uint eo, uint m, int I, int J) {
  float s = 1.0;
  if (I < 0) { I = 0; if (dl) s = -s; }
  if (I >= int(m)) { I = int(m) - 1; if (dr) s = -s; }
  if (J < 0) { J = 0; if (db) s = -s; }
  if (J >= int(m)) { J = int(m) - 1; if (dtop) s = -s; }
  return s * mg[eo + uint(J) * m + uint(I)];
}

// Bilinear (cell-centred) prolongation of the coarse correction at eo to fine cell (i, j): 9/16 own
// coarse cell, 3/16 the two nearest, 1/16 the diagonal.
float prolongValue(uint eo, uint m, uint i, uint j) {
  uint mc = m >> 1u;
  int I = int(i >> 1u), J = int(j >> 1u);
  int di = (i & 1u) != 0u ? 1 : -1, dj = (j & 1u) != 0u ? 1 : -1;
  return 0.5625 * ghosted(eo, mc, I, J) + 0.1875 * ghosted(eo, mc, I + di, J) +
         0.1875 * ghosted(eo, mc, I, J + dj) + 0.0625 * ghosted(eo, mc, I + di, J + dj);
}

void prolongCell(uint po, uint eo, uint m, uint k) {
  mg[po + k] += prolongValue(eo, m, k & (m - 1u), k >> findMSB(m));
}

// Levels are powers of two: shifts and masks instead of integer division (which CPU drivers run
// one lane at a time).
// Red-black sweep of one colour by the whole workgroup. Levels are powers of two >= 2 a side,
// so each row holds m/2 cells of each colour.
void relax(uint po, uint bo, uint m, uint color) {
  uint hm = m >> 1u;
  FOR_EACH(k, m * hm) {
    uint j = k >> findMSB(hm);
    relaxCell(po, bo, m, 2u * (k & (hm - 1u)) + ((j + color) & 1u), j);
  }
  SYNC();
}

// Serial tail: levels from `first` down to the coarsest and back, by one invocation. Small levels
// are mostly barrier cost when spread over the workgroup (docs/design.md: lavapipe runs a workgroup on
// one core), so below f.mgSerialSize they run here without any barrier. Same operations, same order
// within each colour, so the result is identical.
void serialTail(uint first, bool neumann) {
  uint n = f.n, L = f.mgLevels;
  for (uint l = first; l + 1u < L; ++l) {
    uint m = n >> l, mc = m >> 1u;
    uint po = mgOffset(n, l), bo = po + m * m, pco = mgOffset(n, l + 1u), bco = pco + mc * mc;
    for (uint s = 0u; s < SIM_MG_PRE_SWEEPS; ++s)
      for (uint c = 0u; c < 2u; ++c)
        for (uint k = 0u; k < m * m; ++k)
          if ((((k % m) + (k / m)) & 1u) == c) relaxCell(po, bo, m, k % m, k / m);
    for (uint k = 0u; k < mc * mc; ++k) restrictCell(po, bo, m, pco, bco, k);
    if (neumann) {
      float s = 0.0;
      for (uint k = 0u; k < mc * mc; ++k) s += mg[bco + k];
      s /= float(mc * mc);
      for (uint k = 0u; k < mc * mc; ++k) mg[bco + k] -= s;
    }
  }
  {
    uint m = n >> (L - 1u);
    uint po = mgOffset(n, L - 1u), bo = po + m * m;
    for (uint s = 0u; s < SIM_MG_COARSE_SWEEPS; ++s)
      for (uint c = 0u; c < 2u; ++c)
        for (uint k = 0u; k < m * m; ++k)
          if ((((k % m) + (k / m)) & 1u) == c) relaxCell(po, bo, m, k % m, k / m);
  }
  for (uint l = L - 1u; l-- > first;) {
    uint m = n >> l;
    uint po = mgOffset(n, l), bo = po + m * m, eo = mgOffset(n, l + 1u);
    for (uint k = 0u; k < m * m; ++k) prolongCell(po, eo, m, k);
    for (uint s = 0u; s < SIM_MG_POST_SWEEPS; ++s)
      for (uint c = 0u; c < 2u; ++c)
        for (uint k = 0u; k < m * m; ++k)
          if ((((k % m) + (k / m)) & 1u) == c) relaxCell(po, bo, m, k % m, k / m);
  }
}


// The right-hand side of level 0, -h^2 (div u - q), into mg[n*n ..), from the field at o (its
// boundary faces set first), made compatible (zero mean) in the pure-Neumann case.
void projectionRhs(uint o, bool neumann) {
  uint n = f.n;
  float h = 1.0 / float(n);
  macBoundary(o);
  SYNC();
  uint bo = n * n;
  FOR_EACH(c, n * n) {
    uint i = c & (n - 1u), j = c >> findMSB(n);
    mg[bo + c] = -h * (vel[o + macU(n, i + 1u, j)] - vel[o + macU(n, i, j)] + vel[o + macV(n, i, j + 1u)] - vel[o + macV(n, i, j)]) +
                 h * h * motorSource(f, vec2((float(i) + 0.5) * h, (float(j) + 0.5) * h));
  }
  SYNC();
  if (neumann) subtractMean(bo, n * n);
}

// u -= grad p with the solved pressure at mg[0 .. n*n) (its mean removed in the pure-Neumann case).
void subtractPressureGradient(uint o, bool neumann) {
  uint n = f.n;
  if (neumann) subtractMean(0u, n * n);
  float invh = float(n);
  FOR_EACH(k, (n - 1u) * n) {
    uint i = 1u + k % (n - 1u), j = k / (n - 1u);
    vel[o + macU(n, i, j)] -= (mg[j * n + i] - mg[j * n + i - 1u]) * invh;
  }
  FOR_EACH(k, n * (n - 1u)) {
    uint i = k & (n - 1u), j = 1u + (k >> findMSB(n));
    vel[o + macV(n, i, j)] -= (mg[j * n + i] - mg[(j - 1u) * n + i]) * invh;
  }
  FOR_EACH(t, n) {
    if (dl) vel[o + macU(n, 0u, t)] -= 2.0 * mg[t * n] * invh;
    if (dr) vel[o + macU(n, n, t)] += 2.0 * mg[t * n + n - 1u] * invh;
    if (db) vel[o + macV(n, t, 0u)] -= 2.0 * mg[t] * invh;
    if (dtop) vel[o + macV(n, t, n)] += 2.0 * mg[(n - 1u) * n + t] * invh;
  }
}

// Reads the frame and the field's outflow sides; returns whether the problem is pure Neumann.
bool beginProjection() {
  LOAD_FRAME();
  dl = isOutflow(SIM_SIDE_LEFT);
  dr = isOutflow(SIM_SIDE_RIGHT);
  db = isOutflow(SIM_SIDE_BOTTOM);
  dtop = isOutflow(SIM_SIDE_TOP);
  return !(dl || dr || db || dtop);
}
