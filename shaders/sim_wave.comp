#version 460
#extension GL_GOOGLE_include_directive : require
// The wave oscillator (docs/design.md): V'' = c^2 lap V - k (V - g V_wind) - zeta V', integrated with
// position Verlet, V+ = V + (1 - zeta dt)(V - V-) + dt^2 (c^2 lap V - k (V - g V_wind)), in
// f.waveSubsteps substeps chosen on the host so that every substep is stable. V_wind is the
// fluid velocity at cell centres (MAC faces averaged, or Stam's collocated interior).
// One workgroup.
#include "sim_common.glsl"
layout(local_size_x_id = 0) in;  // SIM_GROUP

void main() {
  LOAD_FRAME();
  uint n = f.n, nn = n * n;
  FOR_EACH(c, nn) {
    uint i = c & (n - 1u), j = c >> findMSB(n);
    vec2 w;
    if (f.scheme == SIM_SCHEME_STAM) {
      w = vec2(vel[stamIX(n, 0u, i + 1u, j + 1u)], vel[stamIX(n, 1u, i + 1u, j + 1u)]);
    } else {
      uint B = velocityFloats(n);
      w = vec2(0.5 * (vel[B + macU(n, i, j)] + vel[B + macU(n, i + 1u, j)]),
               0.5 * (vel[B + macV(n, i, j)] + vel[B + macV(n, i, j + 1u)]));
    }
    wave[waveWind(n, c)] = w;
  }
  SYNC();
  float dt = f.waveDt, damp = 1.0 - f.waveZeta * dt, c2 = f.waveC * f.waveC * float(n) * float(n);
  // The newest state lives in slot `cur`, the previous one in the other slot; each substep
  // overwrites the previous one in place (it is read only at the same cell).
  uint cur = 0u;
  for (uint sub = 0u; sub < f.waveSubsteps; ++sub) {
    uint curOff = cur * nn, prevOff = (1u - cur) * nn;
    FOR_EACH(c, nn) {
      uint i = c & (n - 1u), j = c >> findMSB(n);
      vec2 x = wave[curOff + c];
      vec2 l = i > 0u ? wave[curOff + c - 1u] : x;
      vec2 r = i + 1u < n ? wave[curOff + c + 1u] : x;
      vec2 d = j > 0u ? wave[curOff + c - n] : x;
      vec2 u = j + 1u < n ? wave[curOff + c + n] : x;
      vec2 lap = (l + r + d + u - 4.0 * x) * c2;
      wave[prevOff + c] = x + damp * (x - wave[prevOff + c]) + dt * dt * (lap - f.waveK * (x - f.waveGain * wave[waveWind(n, c)]));
    }
    SYNC();
    cur = 1u - cur;
  }
  if (cur == 1u) {
    FOR_EACH(c, nn) {
      vec2 t = wave[c];
      wave[c] = wave[nn + c];
      wave[nn + c] = t;
    }
  }
}
