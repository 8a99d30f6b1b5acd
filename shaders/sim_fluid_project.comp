#version 460
#extension GL_GOOGLE_include_directive : require
// MAC projection (docs/design.md, "Conventions where the paper is silent", projection):
// A p = -h^2 (div u - q) on the cell-centred grid (q: the motors' mass sources, shared/sim.h), solved
// by f.mgCycles multigrid V-cycles (red-black Gauss-Seidel smoothing, sum restriction, bilinear
// prolongation), warm-started from the previous pressure; then u -= grad p. Because the MAC
// divergence of the MAC gradient is exactly the 5-point Laplacian being solved, the result is
// divergence-free up to the solver's residual — which Stam's collocated scheme cannot reach.
// Neumann on inflow/wall sides, p = 0 outside outflow sides. One workgroup;
// pc.phase selects the field (0: A, 1: B).
#include "sim_multigrid.glsl"
layout(local_size_x_id = 0) in;  // SIM_GROUP

void vCycle(bool neumann) {
  uint n = f.n, L = f.mgLevels;
  // Parallel levels: those wider than the serial threshold (the coarsest is always serial).
  uint par = 0u;
  while (par + 1u < L && (n >> par) > f.mgSerialSize) ++par;
  for (uint l = 0u; l < par; ++l) {
    uint m = n >> l, mc = m >> 1u;
    uint po = mgOffset(n, l), bo = po + m * m, pco = mgOffset(n, l + 1u), bco = pco + mc * mc;
    for (uint s = 0u; s < SIM_MG_PRE_SWEEPS; ++s) { relax(po, bo, m, 0u); relax(po, bo, m, 1u); }
    FOR_EACH(k, mc * mc) restrictCell(po, bo, m, pco, bco, k);
    SYNC();
    if (neumann && l + 1u < par) subtractMean(bco, mc * mc);
  }
  if (gl_LocalInvocationIndex == 0u) {
    if (neumann && par > 0u) {  // the first serial level's right-hand side, as subtractMean would
      uint m = n >> par, bo = mgOffset(n, par) + m * m;
      float s = 0.0;
      for (uint k = 0u; k < m * m; ++k) s += mg[bo + k];
      s /= float(m * m);
      for (uint k = 0u; k < m * m; ++k) mg[bo + k] -= s;
    }
    serialTail(par, neumann);
  }
  SYNC();
  for (uint l = par; l-- > 0u;) {
    uint m = n >> l;
    uint po = mgOffset(n, l), bo = po + m * m, eo = mgOffset(n, l + 1u);
    FOR_EACH(k, m * m) prolongCell(po, eo, m, k);
    SYNC();
    for (uint s = 0u; s < SIM_MG_POST_SWEEPS; ++s) { relax(po, bo, m, 0u); relax(po, bo, m, 1u); }
  }
}

void main() {
  bool neumann = beginProjection();
  uint o = pc.phase == 0u ? 0u : velocityFloats(f.n);
  projectionRhs(o, neumann);
  for (uint c = 0u; c < f.mgCycles; ++c) vCycle(neumann);
  subtractPressureGradient(o, neumann);
}
