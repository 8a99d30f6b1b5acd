// The multigrid's cell operations and its serial tail, on an array given by the includer:
// MG(i) is element i of the pyramid (shared/sim.h mgOffset layout), MGF(name) names the functions.
// sim_multigrid.glsl includes it on the multigrid buffer; sim_fluid_project_lanes.comp again on a
// private copy of the smallest levels. One text, so every copy does the same operations in the same
// order as the CPU reference (compute/sim_reference.cpp).

void MGF(relaxCell)(uint po, uint bo, uint m, uint i, uint j) {
  float sum = 0.0, diag = 0.0;
  if (i > 0u) { sum += MG(po + j * m + i - 1u); diag += 1.0; } else if (dl) diag += 2.0;
  if (i + 1u < m) { sum += MG(po + j * m + i + 1u); diag += 1.0; } else if (dr) diag += 2.0;
  if (j > 0u) { sum += MG(po + (j - 1u) * m + i); diag += 1.0; } else if (db) diag += 2.0;
  if (j + 1u < m) { sum += MG(po + (j + 1u) * m + i); diag += 1.0; } else if (dtop) diag += 2.0;
  MG(po + j * m + i) = (sum + MG(bo + j * m + i)) / diag;
}

float MGF(residualAt)(uint po, uint bo, uint m, uint i, uint j) {
  float c = MG(po + j * m + i), ap = 0.0;
  if (i > 0u) ap += c - MG(po + j * m + i - 1u); else if (dl) ap += 2.0 * c;
  if (i + 1u < m) ap += c - MG(po + j * m + i + 1u); else if (dr) ap += 2.0 * c;
  if (j > 0u) ap += c - MG(po + (j - 1u) * m + i); else if (db) ap += 2.0 * c;
  if (j + 1u < m) ap += c - MG(po + (j + 1u) * m + i); else if (dtop) ap += 2.0 * c;
  return MG(bo + j * m + i) - ap;
}

void MGF(restrictCell)(uint po, uint bo, uint m, uint pco, uint bco, uint k) {
  uint mc = m >> 1u, I = k & (mc - 1u), J = k >> findMSB(mc);
  // The sum of the four children: the coarse operator is 4x the fine one.
  MG(bco + k) = MGF(residualAt)(po, bo, m, 2u * I, 2u * J) + MGF(residualAt)(po, bo, m, 2u * I + 1u, 2u * J) +
                MGF(residualAt)(po, bo, m, 2u * I, 2u * J + 1u) + MGF(residualAt)(po, bo, m, 2u * I + 1u, 2u * J + 1u);
  MG(pco + k) = 0.0;
}

float MGF(ghosted)(uint eo, uint m, int I, int J) {
  float s = 1.0;
  if (I < 0) { I = 0; if (dl) s = -s; }
  if (I >= int(m)) { I = int(m) - 1; if (dr) s = -s; }
  if (J < 0) { J = 0; if (db) s = -s; }
  if (J >= int(m)) { J = int(m) - 1; if (dtop) s = -s; }
  return s * MG(eo + uint(J) * m + uint(I));
}

// Bilinear (cell-centred) prolongation of the coarse correction at eo to fine cell (i, j): 9/16 own
// coarse cell, 3/16 the two nearest, 1/16 the diagonal.
float MGF(prolongValue)(uint eo, uint m, uint i, uint j) {
  uint mc = m >> 1u;
  int I = int(i >> 1u), J = int(j >> 1u);
  int di = (i & 1u) != 0u ? 1 : -1, dj = (j & 1u) != 0u ? 1 : -1;
  return 0.5625 * MGF(ghosted)(eo, mc, I, J) + 0.1875 * MGF(ghosted)(eo, mc, I + di, J) +
         0.1875 * MGF(ghosted)(eo, mc, I, J + dj) + 0.0625 * MGF(ghosted)(eo, mc, I + di, J + dj);
}

void MGF(prolongCell)(uint po, uint eo, uint m, uint k) {
  MG(po + k) += MGF(prolongValue)(eo, m, k & (m - 1u), k >> findMSB(m));
}

// Serial tail: levels from `first` down to the coarsest and back, by one invocation. Small levels
// are mostly barrier cost when spread over the workgroup (docs/design.md: lavapipe runs a workgroup on
// one core), so below f.mgSerialSize they run here without any barrier. Same operations, same order
// within each colour, so the result is identical.
void MGF(serialTail)(uint first, bool neumann) {
  uint n = f.n, L = f.mgLevels;
  for (uint l = first; l + 1u < L; ++l) {
    uint m = n >> l, mc = m >> 1u;
    uint po = mgOffset(n, l), bo = po + m * m, pco = mgOffset(n, l + 1u), bco = pco + mc * mc;
    for (uint s = 0u; s < SIM_MG_PRE_SWEEPS; ++s)
      for (uint c = 0u; c < 2u; ++c)
        for (uint k = 0u; k < m * m; ++k)
          if ((((k % m) + (k / m)) & 1u) == c) MGF(relaxCell)(po, bo, m, k % m, k / m);
    for (uint k = 0u; k < mc * mc; ++k) MGF(restrictCell)(po, bo, m, pco, bco, k);
    if (neumann) {
      float s = 0.0;
      for (uint k = 0u; k < mc * mc; ++k) s += MG(bco + k);
      s /= float(mc * mc);
      for (uint k = 0u; k < mc * mc; ++k) MG(bco + k) -= s;
    }
  }
  {
    uint m = n >> (L - 1u);
    uint po = mgOffset(n, L - 1u), bo = po + m * m;
    for (uint s = 0u; s < SIM_MG_COARSE_SWEEPS; ++s)
      for (uint c = 0u; c < 2u; ++c)
        for (uint k = 0u; k < m * m; ++k)
          if ((((k % m) + (k / m)) & 1u) == c) MGF(relaxCell)(po, bo, m, k % m, k / m);
  }
  for (uint l = L - 1u; l-- > first;) {
    uint m = n >> l;
    uint po = mgOffset(n, l), bo = po + m * m, eo = mgOffset(n, l + 1u);
    for (uint k = 0u; k < m * m; ++k) MGF(prolongCell)(po, eo, m, k);
    for (uint s = 0u; s < SIM_MG_POST_SWEEPS; ++s)
      for (uint c = 0u; c < 2u; ++c)
        for (uint k = 0u; k < m * m; ++k)
          if ((((k % m) + (k / m)) & 1u) == c) MGF(relaxCell)(po, bo, m, k % m, k / m);
  }
}

