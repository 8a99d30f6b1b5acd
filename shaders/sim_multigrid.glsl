// Multigrid helpers of the MAC projection (docs/design.md "Conventions where the paper is silent",
// projection), shared by the workgroup-wide kernel (sim_fluid_project.comp) and the lane-blocked
// one for CPU devices (sim_fluid_project_lanes.comp): the same cell operations in the same order, so both match the CPU
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

#define MG(i) mg[i]
#define MGF(name) name
#include "sim_multigrid_cells.glsl"
#undef MG
#undef MGF

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
                 h * h * motorSourcesAt(vec2((float(i) + 0.5) * h, (float(j) + 0.5) * h));
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
