#version 460
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_shuffle : require
#extension GL_KHR_shader_subgroup_arithmetic : require
// MAC projection, lane-blocked for CPU devices (docs/performance.md, "Simulation step"): the same
// solve as sim_fluid_project.comp — same right-hand side, V-cycles, smoother, transfers and
// gradient — but the multigrid levels at least W wide live in registers instead of the multigrid
// buffer. The workgroup is one subgroup of W = SIM_GROUP lanes (the device's subgroup
// size); lane L holds the columns x = k W + L of every row, so a row segment of W cells is one SIMD
// vector: row neighbours are the same private-array element of the next/previous row (a plain vector
// load) and column neighbours come from subgroupShuffle. Why: lavapipe (Mesa 22) loads buffer and
// shared memory one lane at a time with a bounds check per lane (~67 ns per relaxed cell measured),
// while a private array indexed by uniform loop counters is one vector access (~7 ns per cell).
// Narrower levels run in every lane on a private copy (the tail below).
#include "sim_multigrid.glsl"
layout(local_size_x_id = 0) in;  // SIM_GROUP == the subgroup size (compute/simulation.cpp checks)

// Floats per lane for all register levels: sum over levels l < par of (n >> l)^2 / W
// (compute/simulation.cpp, laneRegisterLevels).
layout(constant_id = 1) const uint SIM_LANE_FLOATS = 1u;
float rp[SIM_LANE_FLOATS];  // pressure (unknown) of the register levels
float rb[SIM_LANE_FLOATS];  // right-hand side of the register levels

// The levels narrower than W (at most 8, 4, 2, 1 a side for W <= 16: 170 floats with their
// right-hand sides): every lane runs them on its own copy, so the indices are uniform and each
// access is one vector operation — no buffer, no barrier, no lane idling while one works.
float tailArr[192];
uint tailBase;  // mgOffset of the first tail level: tailArr[i - tailBase] is pyramid element i
#define MG(i) tailArr[(i) - tailBase]
#define MGF(name) name##Tail
#include "sim_multigrid_cells.glsl"
#undef MG
#undef MGF
#define MG_TAIL(i) tailArr[(i) - tailBase]

// Register index of (segment k, row j) on level l: level offset + k m + j.
uint regOffset(uint l) { return mgOffset(f.n, l) / (2u * SIM_GROUP); }
uint lane() { return gl_SubgroupInvocationID; }

// The five stencil values of the vector (segment k, row j) of a register level with m cells a side:
// own, left (x - 1), right (x + 1), below (j - 1), above (j + 1). Missing neighbours read 0; the
// caller weighs them by the side rules. Every lane runs this (shuffles need uniform control flow).
struct Stencil { float c, left, right, down, up; };
Stencil stencilAt(uint ro, uint m, uint k, uint j) {
  uint segs = m / SIM_GROUP, r = ro + k * m + j, L = lane(), W = SIM_GROUP;
  Stencil s;
  s.c = rp[r];
  // Indices clamped so the unused side never indexes outside the array.
  float prevSeg = rp[k > 0u ? r - m : r], nextSeg = rp[k + 1u < segs ? r + m : r];
  // Lane 0's left neighbour is lane W-1 of the previous segment; lane W-1's right one is lane 0 of the next.
  s.left = subgroupShuffle(L == W - 1u ? prevSeg : s.c, (L + W - 1u) & (W - 1u));
  s.right = subgroupShuffle(L == 0u ? nextSeg : s.c, (L + 1u) & (W - 1u));
  s.down = rp[j > 0u ? r - 1u : r];
  s.up = rp[j + 1u < m ? r + 1u : r];
  return s;
}

// relaxCell of sim_multigrid.glsl for the W cells of one vector, applied to the lanes of `color`.
void relaxLanes(uint l, uint color) {
  uint m = f.n >> l, segs = m / SIM_GROUP, ro = regOffset(l);
  for (uint k = 0u; k < segs; ++k) {
    uint x = k * SIM_GROUP + lane();
    bool hasL = x > 0u, hasR = x + 1u < m;
    for (uint j = 0u; j < m; ++j) {
      Stencil s = stencilAt(ro, m, k, j);
      bool hasD = j > 0u, hasU = j + 1u < m;
      float sum = 0.0, diag = 0.0;
      if (hasL) { sum += s.left; diag += 1.0; } else if (dl) diag += 2.0;
      if (hasR) { sum += s.right; diag += 1.0; } else if (dr) diag += 2.0;
      if (hasD) { sum += s.down; diag += 1.0; } else if (db) diag += 2.0;
      if (hasU) { sum += s.up; diag += 1.0; } else if (dtop) diag += 2.0;
      uint r = ro + k * m + j;
      float updated = (sum + rb[r]) / diag;
      rp[r] = ((x + j) & 1u) == color ? updated : s.c;
    }
  }
}

// residualAt of sim_multigrid.glsl for one vector.
float residualLanes(uint ro, uint m, uint k, uint j) {
  Stencil s = stencilAt(ro, m, k, j);
  uint x = k * SIM_GROUP + lane();
  float ap = 0.0;
  if (x > 0u) ap += s.c - s.left; else if (dl) ap += 2.0 * s.c;
  if (x + 1u < m) ap += s.c - s.right; else if (dr) ap += 2.0 * s.c;
  if (j > 0u) ap += s.c - s.down; else if (db) ap += 2.0 * s.c;
  if (j + 1u < m) ap += s.c - s.up; else if (dtop) ap += 2.0 * s.c;
  return rb[ro + k * m + j] - ap;
}

// The sum of the four children of coarse cell (x/2, J), valid in the even lanes (restrictCell's order).
float childSum(uint ro, uint m, uint k, uint J) {
  float r0 = residualLanes(ro, m, k, 2u * J), r1 = residualLanes(ro, m, k, 2u * J + 1u);
  return ((r0 + subgroupShuffleXor(r0, 1u)) + r1) + subgroupShuffleXor(r1, 1u);
}

// Restriction from register level l to level l + 1: into registers when that level is a register
// level too, else into the multigrid buffer for the serial tail.
void restrictLanes(uint l, bool coarseInRegisters) {
  uint n = f.n, m = n >> l, mc = m >> 1u, segs = m / SIM_GROUP, ro = regOffset(l), L = lane(), W = SIM_GROUP;
  if (coarseInRegisters) {
    // Coarse lane Lc of segment K takes fine segment 2K (Lc < W/2) or 2K+1, lane 2 Lc mod W.
    uint rc = regOffset(l + 1u), src = (2u * L) & (W - 1u);
    for (uint K = 0u; K < mc / W; ++K)
      for (uint J = 0u; J < mc; ++J) {
        float a = subgroupShuffle(childSum(ro, m, 2u * K, J), src);
        float b = subgroupShuffle(childSum(ro, m, 2u * K + 1u, J), src);
        rb[rc + K * mc + J] = L < W / 2u ? a : b;
        rp[rc + K * mc + J] = 0.0;
      }
  } else {
    // Into the tail: every lane takes every coarse cell (a broadcast from the even lane holding it).
    uint pco = mgOffset(n, l + 1u), bco = pco + mc * mc;
    for (uint k = 0u; k < segs; ++k)
      for (uint J = 0u; J < mc; ++J) {
        float v = childSum(ro, m, k, J);
        for (uint q = 0u; q < W / 2u; ++q) {
          uint X = k * (W / 2u) + q;
          MG_TAIL(bco + J * mc + X) = subgroupShuffle(v, 2u * q);
          MG_TAIL(pco + J * mc + X) = 0.0;
        }
      }
  }
}

// Pure-Neumann compatibility (subtractMean) of a register level's right-hand side or unknown.
void subtractMeanOf(uint l, bool rhs) {
  uint m = f.n >> l, ro = regOffset(l), count = m * m / SIM_GROUP;
  float s = 0.0;
  for (uint q = 0u; q < count; ++q) s += rhs ? rb[ro + q] : rp[ro + q];
  float mean = subgroupAdd(s) / float(m * m);
  for (uint q = 0u; q < count; ++q) {
    if (rhs) rb[ro + q] -= mean;
    else rp[ro + q] -= mean;
  }
}

// Coarse value of register level lc at row J for each lane's coarse column I (its own segment K)
// and at column I2 (segment K or `other`), with ghosted()'s rules for a column outside the level.
void coarseRow(uint rc, uint mc, uint K, uint other, uint J, uint I, int I2, out float own, out float nb) {
  uint W = SIM_GROUP;
  float vK = rp[rc + K * mc + J], vO = rp[rc + other * mc + J];
  own = subgroupShuffle(vK, I & (W - 1u));
  uint I2c = uint(clamp(I2, 0, int(mc) - 1));
  float inK = subgroupShuffle(vK, I2c & (W - 1u)), inO = subgroupShuffle(vO, I2c & (W - 1u));
  nb = (I2c / W) == K ? inK : inO;
  if (I2 < 0) nb = dl ? -own : own;
  if (I2 >= int(mc)) nb = dr ? -own : own;
}

// prolongCell for register level l from level l + 1 (registers or, for the first serial level, the buffer).
void prolongLanes(uint l, bool coarseInRegisters) {
  uint n = f.n, m = n >> l, mc = m >> 1u, segs = m / SIM_GROUP, ro = regOffset(l), L = lane(), W = SIM_GROUP;
  if (!coarseInRegisters) {
    uint eo = mgOffset(n, l + 1u);  // the first tail level
    for (uint k = 0u; k < segs; ++k)
      for (uint j = 0u; j < m; ++j) rp[ro + k * m + j] += prolongValueTail(eo, m, k * W + L, j);
    return;
  }
  uint rc = regOffset(l + 1u), segsC = mc / W;
  for (uint k = 0u; k < segs; ++k) {
    uint x = k * W + L, I = x >> 1u, K = k >> 1u;
    int I2 = int(I) + ((x & 1u) != 0u ? 1 : -1);
    // The segment a lane's neighbour column may fall into: the previous one for an even fine
    // segment (its lane 0 looks left), the next one for an odd one.
    uint other = (k & 1u) != 0u ? min(K + 1u, segsC - 1u) : (K > 0u ? K - 1u : 0u);
    for (uint j = 0u; j < m; ++j) {
      uint J = j >> 1u;
      int J2 = int(J) + ((j & 1u) != 0u ? 1 : -1);
      uint J2c = uint(clamp(J2, 0, int(mc) - 1));
      float g00, g10, g01, g11;
      coarseRow(rc, mc, K, other, J, I, I2, g00, g10);
      coarseRow(rc, mc, K, other, J2c, I, I2, g01, g11);
      if (J2 < 0 && db) { g01 = -g01; g11 = -g11; }
      if (J2 >= int(mc) && dtop) { g01 = -g01; g11 = -g11; }
      rp[ro + k * m + j] += 0.5625 * g00 + 0.1875 * g10 + 0.1875 * g01 + 0.0625 * g11;
    }
  }
}

void vCycleLanes(bool neumann, uint par) {
  uint n = f.n;
  for (uint l = 0u; l < par; ++l) {
    for (uint s = 0u; s < SIM_MG_PRE_SWEEPS; ++s) { relaxLanes(l, 0u); relaxLanes(l, 1u); }
    restrictLanes(l, l + 1u < par);
    if (neumann && l + 1u < par) subtractMeanOf(l + 1u, true);
  }
  if (neumann) {  // the first tail level's right-hand side, as subtractMean would
    uint m = n >> par, bo = mgOffset(n, par) + m * m;
    float s = 0.0;
    for (uint k = 0u; k < m * m; ++k) s += MG_TAIL(bo + k);
    s /= float(m * m);
    for (uint k = 0u; k < m * m; ++k) MG_TAIL(bo + k) -= s;
  }
  serialTailTail(par, neumann);
  for (uint l = par; l-- > 0u;) {
    prolongLanes(l, l + 1u < par);
    for (uint s = 0u; s < SIM_MG_POST_SWEEPS; ++s) { relaxLanes(l, 0u); relaxLanes(l, 1u); }
  }
}

// The velocity field in registers for the projection (docs/performance.md, "Simulation step"): u
// faces of columns 0..n-1 (segs x n), v faces (segs x (n + 1)), u column n in every lane. Loaded
// once after the boundary faces are set and stored once after the gradient, where the right-hand
// side read four faces per cell and the gradient read and wrote two (each a lane-by-lane buffer
// access on lavapipe).
layout(constant_id = 2) const uint SIM_LANE_VEL_FLOATS = 1u;
float rv[SIM_LANE_VEL_FLOATS];
uint segsV, uOff, vOff, uEdgeOff;  // register offsets of u, v and u column n

// The right neighbour along x of u face (segment k, row j): lane L + 1, lane 0 of the next segment,
// or column n. Every lane runs it (shuffles).
float uRight(uint k, uint j) {
  uint n = f.n, r = uOff + k * n + j, L = lane(), W = SIM_GROUP;
  float c = rv[r];
  float next = k + 1u < segsV ? rv[r + n] : rv[uEdgeOff + j];  // r + n: v's registers when unused
  return subgroupShuffle(L == 0u ? next : c, (L + 1u) & (W - 1u));
}

void loadVelocityLanes(uint o) {
  uint n = f.n, W = SIM_GROUP, L = lane();
  segsV = n / W;
  uOff = 0u;
  vOff = segsV * n;
  uEdgeOff = vOff + segsV * (n + 1u);
  for (uint k = 0u; k < segsV; ++k) {
    uint x = k * W + L;
    for (uint j = 0u; j < n; ++j) rv[uOff + k * n + j] = vel[o + macU(n, x, j)];
    for (uint j = 0u; j <= n; ++j) rv[vOff + k * (n + 1u) + j] = vel[o + macV(n, x, j)];
  }
  for (uint j = 0u; j < n; ++j) rv[uEdgeOff + j] = vel[o + macU(n, n, j)];
}

void storeVelocityLanes(uint o) {
  uint n = f.n, W = SIM_GROUP, L = lane();
  for (uint k = 0u; k < segsV; ++k) {
    uint x = k * W + L;
    for (uint j = 0u; j < n; ++j) vel[o + macU(n, x, j)] = rv[uOff + k * n + j];
    for (uint j = 0u; j <= n; ++j) vel[o + macV(n, x, j)] = rv[vOff + k * (n + 1u) + j];
  }
  if (L == 0u)
    for (uint j = 0u; j < n; ++j) vel[o + macU(n, n, j)] = rv[uEdgeOff + j];
}

// projectionRhs in registers: -h^2 (div u - q) of the field at o into level 0's right-hand side.
void rhsLanes(uint o, bool neumann) {
  uint n = f.n, W = SIM_GROUP, L = lane();
  float h = 1.0 / float(n);
  macBoundary(o);
  SYNC();
  loadVelocityLanes(o);
  for (uint k = 0u; k < n / W; ++k) {
    uint i = k * W + L;
    for (uint j = 0u; j < n; ++j) {
      uint vr = vOff + k * (n + 1u) + j;
      rb[k * n + j] = -h * (uRight(k, j) - rv[uOff + k * n + j] + rv[vr + 1u] - rv[vr]) +
                      h * h * motorSourcesAt(vec2((float(i) + 0.5) * h, (float(j) + 0.5) * h));
    }
  }
  if (neumann) subtractMeanOf(0u, true);
}

// subtractPressureGradient in registers; level 0's pressure also goes back to the multigrid buffer
// (the next projection's warm start).
void gradientLanes(uint o, bool neumann) {
  uint n = f.n, W = SIM_GROUP, L = lane();
  if (neumann) subtractMeanOf(0u, false);
  float invh = float(n);
  for (uint k = 0u; k < n / W; ++k) {
    uint i = k * W + L;
    for (uint j = 0u; j < n; ++j) {
      Stencil s = stencilAt(0u, n, k, j);
      mg[j * n + i] = s.c;
      uint ur = uOff + k * n + j, vr = vOff + k * (n + 1u) + j;
      if (i > 0u) rv[ur] -= (s.c - s.left) * invh;
      else if (dl) rv[ur] -= 2.0 * s.c * invh;
      if (j > 0u) rv[vr] -= (s.c - s.down) * invh;
      else if (db) rv[vr] -= 2.0 * s.c * invh;
      if (j + 1u == n && dtop) rv[vr + 1u] += 2.0 * s.c * invh;
      // Column n's face takes lane W - 1's cell of the last segment (k is uniform: every lane shuffles).
      if (k + 1u == n / W && dr) rv[uEdgeOff + j] += 2.0 * subgroupShuffle(s.c, W - 1u) * invh;
    }
  }
  storeVelocityLanes(o);
}

void main() {
  bool neumann = beginProjection();
  uint n = f.n, o = pc.phase == 0u ? 0u : velocityFloats(n), W = SIM_GROUP, L = lane();
  // Register levels: at least W wide (simulation.cpp selects this kernel only for n >= W and
  // 8 <= W <= 16, so the coarsest level, at most 4 wide, is always in the tail).
  uint par = 0u;
  while (par + 1u < f.mgLevels && (n >> par) >= W) ++par;
  tailBase = mgOffset(n, par);
  rhsLanes(o, neumann);
  for (uint k = 0u; k < n / W; ++k)
    for (uint j = 0u; j < n; ++j) rp[k * n + j] = mg[j * n + k * W + L];
  for (uint c = 0u; c < f.mgCycles; ++c) vCycleLanes(neumann, par);
  gradientLanes(o, neumann);
}
