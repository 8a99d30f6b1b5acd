// The per-vertex wind baseline (seed 004, Habel sections IV-VI; docs/design.md "Per-vertex wind
// baseline"): every vertex displaced each frame by hierarchical bending. Each vertex carries the
// index of its innermost branch and Habel's vector w (its normalised coordinate along that branch
// and, propagated down the hierarchy, the coordinate at which each ancestor carries it); each
// branch bends as a beam whose rotation grows along it (the tip more flexible: tapered), driven by
// a stochastic wind field (Kaimal's turbulence spectrum as random-phase components, frozen and
// carried by the mean wind over the plant) through a damped oscillator per hierarchy level
// (Habel VI's spectral synthesis); before 0.7 by one uniform wind and spectral noise per branch
// (BEND_WIND_UNIFORM). The same functions run in the vertex shader (shaders/per_vertex.vert), in
// the motion kernel, in the probe kernel the tests read back, and on the CPU.
#ifndef CANOPY_SHARED_BEND_H
#define CANOPY_SHARED_BEND_H
#include "interop.h"

#define BEND_LEVELS 4                 // branch levels a vertex carries (trunk, branch, twig, level 3)
#define BEND_NO_BRANCH 0xffffffffu    // no hierarchy: a trunk and a radial branch from the position (fallback)
#define BEND_LEAF_ONLY 0xfffffffeu    // only the leaf level moves (grass blades; ground, rock: nothing)
#define BEND_NO_PARENT 0xffffffffu

// BendFrame.windModel (PerVertexWind)
#define BEND_WIND_FIELD 0u    // Kaimal field through damped oscillators per level (default)
#define BEND_WIND_UNIFORM 1u  // one wind speed, Kolmogorov noise per branch (before 0.7)
// The field's random-phase components: log-spaced bands over [LOW, HIGH] Hz (the levels' sway
// frequencies and the leaves' lie inside).
#define BEND_FIELD_COMPONENTS 8u
#define BEND_FIELD_LOW_HZ 0.04f
#define BEND_FIELD_HIGH_HZ 10.0f
// Each component's wavefront tilts across the wind by a random slope in [-SPREAD, SPREAD] (lateral
// and vertical): two points dx apart across the wind then share a component of wavenumber k with
// coherence sinc(2 pi SPREAD k dx), which at SPREAD 3 falls to 1/2 at k dx = 0.1 as Davenport's
// exp(-7 k dx) does (wind engineering's usual coherence decay for lateral separations).
#define BEND_FIELD_SPREAD 3.0f

// BendFrame.flags
#define BEND_FLAG_HIERARCHY 1u  // the per-vertex BendVertex buffer is bound (else every vertex is BEND_NO_BRANCH)
#define BEND_FLAG_PREVIOUS 2u   // the motion table also holds last frame's tips (motion vectors)

// What the two languages spell differently: an in-out parameter, the cross product, atan2.
#ifdef __cplusplus
#define BEND_INOUT(T) T&
#define bendCross glm::cross
#define bendAtan2 std::atan2
#define bendTanh std::tanh
#else
#define BEND_INOUT(T) inout T
#define bendCross cross
#define bendAtan2 atan
#define bendTanh tanh
#endif

CANOPY_NAMESPACE_BEGIN

// Per vertex of the compact mesh (a buffer parallel to its vertices, read at gl_VertexIndex).
struct BendVertex {
  uint branch;  // innermost branch (index into the branch table), BEND_NO_BRANCH or BEND_LEAF_ONLY
  uint w;       // Habel's w: 4 x unorm8, level k in bits 8k..8k+7 (levels past the chain's are 0)
};
CANOPY_SIZE_CHECK(BendVertex, 8)

struct BendBranch {
  vec3 origin;  // rest position of the branch's base, world
  uint parent;  // BEND_NO_PARENT for a trunk (level 0)
  vec3 axis;    // unit rest direction from the base to the tip
  uint level;   // 0..BEND_LEVELS-1: the parent's + 1
};
CANOPY_SIZE_CHECK(BendBranch, 32)

struct BendFrame {
  vec4 wind;          // xyz: unit world direction the wind blows towards; w: mean speed S*b (domain units/s)
  vec4 lateral;       // xyz: unit, across the wind (horizontal); w: lateral share of the sway
  vec4 up;            // xyz: world up (fallback trunk axis); w: fallback trunk height H (world)
  vec4 root;          // xyz: fallback trunk root; w: fallback crown radius R (world)
  vec4 flexibility;   // levels 0..3: tip bend at the reference wind speed (drag: ~ speed^2), rad
  vec4 frequency;     // levels 0..3: sway frequency at the reference wind speed, Hz
  float leafFlexibility;  // the leaf level's (a leaf turning about its root)
  float leafFrequency;
  float referenceSpeed;   // wind speed at which the frequencies are the given ones, units/s
  float maxAngle;         // bend saturation, rad
  float strength;         // WindParams: speed(t) = strength * (baseline + modulation sin(2 pi frequency t))
  float baseline;
  float modulation;
  float windFrequency;
  float gust;             // relative amplitude of the spectral noise about the mean bend
  float taper;            // exponent p: the rotation at coordinate x along a branch is tip * x^p
  float time;             // seconds
  float previousTime;     // last frame's time (motion vectors)
  vec2 targetSize;        // pixels (motion vectors)
  uint seed;
  uint flags;             // BEND_FLAG_*
  // The motion table (shaders/per_vertex_tips.comp): entries [0, branchCount) the branches' tip
  // bends, then the leaves'; tipCount entries at this frame's time, then (BEND_FLAG_PREVIOUS) as
  // many at the previous frame's.
  uint branchCount;
  uint tipCount;
  // Placed copies (CanopyInstance): each has its own motion table, copy c's at entries
  // [c * sets * tipCount, (c + 1) * sets * tipCount), sets 2 with BEND_FLAG_PREVIOUS else 1.
  uint copyCount;
  // The previous frame's camera (projection x view; this frame's on the first frame and after a
  // camera cut): motion vectors carry the camera's motion as well as the bend's (issue 34).
  mat4 previousViewProj;
  // The wind field (BEND_WIND_FIELD; docs/design.md "Per-vertex wind baseline").
  vec4 damping;          // levels 0..3: damping ratio zeta of each level's oscillator
  vec4 fieldOrigin;      // xyz: where the field's coordinates start (the root); w: world units per domain unit
  float leafDamping;     // the leaf level's zeta
  float integralScale;   // Kaimal's length scale L, domain units
  uint windModel;        // BEND_WIND_*
  // Entries of the trunk table (BendTrunk; at least 1): a BEND_NO_BRANCH vertex's w names its
  // species' entry (bendFrameForTrunk), so each species of a vegetation bends about its own trunk.
  uint trunkCount;
};
CANOPY_SIZE_CHECK(BendFrame, 16 * 6 + 4 * 12 + 8 + 16 + 4 + 64 + 32 + 16)

// The bend frame as one placed copy sees it (CanopyInstance; docs/design.md "Instances"): the wind
// and its lateral direction taken into the copy's model space by the inverse of its linear part
// (the transpose of its normal matrix, whose columns are n0, n1, n2), and its time shifted by the
// copy's wind phase (s), so copies of one plant do not sway in lockstep.
CANOPY_INLINE BendFrame bendFrameForCopy(BendFrame f, vec3 n0, vec3 n1, vec3 n2, float phase) {
  vec3 w = vec3(dot(n0, vec3(f.wind)), dot(n1, vec3(f.wind)), dot(n2, vec3(f.wind)));
  vec3 l = vec3(dot(n0, vec3(f.lateral)), dot(n1, vec3(f.lateral)), dot(n2, vec3(f.lateral)));
  float wl = sqrt(dot(w, w)), ll = sqrt(dot(l, l));
  if (wl > 0.0f) f.wind = vec4(w / wl, f.wind.w);
  if (ll > 0.0f) f.lateral = vec4(l / ll, f.lateral.w);
  f.time = f.time + phase;
  f.previousTime = f.previousTime + phase;
  return f;
}

// The fallback trunk of one species (a model without a branch hierarchy: BEND_NO_BRANCH): the
// vertical through its bounds' centre from their bottom, in its model space. Entry 0 is the
// vegetation's own (BendFrame.root and up.w); with several species, entry s is species s's and its
// BEND_NO_BRANCH vertices carry s in BendVertex.w.
struct BendTrunk {
  vec4 root;  // xyz: the trunk's root; w: crown radius R (half the bounds' horizontal diagonal)
  vec4 up;    // xyz: the trunk's axis (world up); w: its height H
};
CANOPY_SIZE_CHECK(BendTrunk, 32)

// The bend frame for a BEND_NO_BRANCH vertex of species `t` (its trunk in place of the frame's;
// the wind field's origin stays the vegetation's, so neighbouring species feel the same field).
CANOPY_INLINE BendFrame bendFrameForTrunk(BendFrame f, BendTrunk t) {
  f.root = t.root;
  f.up = t.up;
  return f;
}

// One rest vertex for the probe kernel (shaders/per_vertex_probe.comp; tests).
#define BEND_NO_LEAF 0xffffffffu
struct BendProbeVertex {
  vec3 position;
  uint leaf;      // model-wide leaf index, BEND_NO_LEAF for rigid parts
  vec3 leafRoot;  // the leaf's root vertex (rest)
  uint pad0;
  vec3 normal;
  uint pad1;
};
CANOPY_SIZE_CHECK(BendProbeVertex, 48)

// A vertex's branch chain, trunk first (b[0]) to its innermost branch (b[count - 1]).
struct BendChain {
  BendBranch b[BEND_LEVELS];
  uint id[BEND_LEVELS];
  uint count;
};

CANOPY_INLINE uint bendHashU(uint x) {
  x ^= x >> 16u;
  x *= 0x7feb352du;
  x ^= x >> 15u;
  x *= 0x846ca68bu;
  x ^= x >> 16u;
  return x;
}
CANOPY_INLINE float bendHash(uint x) { return float(bendHashU(x) >> 8u) * (1.0f / 16777216.0f); }

// Spectral noise of unit RMS (Habel VI: noise with the frequency distribution of observed sway, in
// place of integrating the oscillators): four sinusoids at 0.5, 1, 1.9 and 3.3 times the sway
// frequency f, amplitudes following a Kolmogorov spectrum S(f) ~ f^(-5/3) (amplitude ~ f^(-5/6)),
// phases hashed from `key` so every branch has its own.
CANOPY_INLINE float bendNoise(float t, float f, uint key) {
  const float tau = 6.2831853f;
  uint k = bendHashU(key) * 4u;
  float s = 1.1680f * sin(tau * (0.5f * f * t + bendHash(k)));
  s += 0.6554f * sin(tau * (1.0f * f * t + bendHash(k + 1u)));
  s += 0.3842f * sin(tau * (1.9f * f * t + bendHash(k + 2u)));
  s += 0.2424f * sin(tau * (3.3f * f * t + bendHash(k + 3u)));
  return s;
}

// Wind speed at time t: the 2D method's boundary-wind profile (WindParams), without its gust
// noise, which the spectral noise replaces.
CANOPY_INLINE float bendWindSpeed(BendFrame f, float t) {
  return f.strength * (f.baseline + f.modulation * sin(6.2831853f * f.windFrequency * t));
}

// Kaimal's one-sided spectrum of a wind component over its variance, S(f) / sigma^2 =
// (4 L / U) / (1 + 6 f L / U)^(5/3) (Kaimal et al. 1972; IEC 61400-1's turbulence model): flat
// below the energy-containing scale U / L, Kolmogorov's f^(-5/3) above it, and it moves to higher
// frequencies as the mean speed U grows.
CANOPY_INLINE float bendKaimal(float frequency, float L, float U) {
  return (4.0f * L / U) / pow(1.0f + 6.0f * frequency * L / U, 5.0f / 3.0f);
}

// The response of a damped oscillator (natural frequency f0, damping ratio zeta) to a unit force
// at frequency f, relative to its static response: gain |H| and phase lag (radians), H(r) =
// 1 / (1 - r^2 + 2 i zeta r), r = f / f0.
CANOPY_INLINE vec2 bendOscillator(float frequency, float f0, float zeta) {
  float r = frequency / max(f0, 1e-3f);
  float re = 1.0f - r * r, im = 2.0f * zeta * r;
  return vec2(1.0f / sqrt(re * re + im * im), bendAtan2(im, re));
}

// The wind field's fluctuation at model-space point p and time t as an oscillator (f0, zeta) there
// responds to it, in units of the component's standard deviation (unit variance before the
// oscillator): BEND_FIELD_COMPONENTS random-phase cosines of Kaimal amplitudes sqrt(2 S df),
// frozen and carried along the wind at the mean speed (Taylor's hypothesis: a gust reaches the lee
// side later) and decorrelated across it (each component's wavefront tilted by a random slope in
// the lateral and vertical directions, BEND_FIELD_SPREAD), each through H. `component` 0: along the wind (u), 1:
// across it (v).
CANOPY_INLINE float bendFieldResponse(BendFrame f, vec3 p, float t, float f0, float zeta, uint component) {
  const float tau = 6.2831853f;
  float U = max(abs(f.wind.w), 1e-3f);
  float L = max(f.integralScale, 1e-4f);
  vec3 rel = (p - vec3(f.fieldOrigin)) / max(f.fieldOrigin.w, 1e-9f);
  float sAlong = dot(rel, vec3(f.wind)), sLat = dot(rel, vec3(f.lateral)), sUp = dot(rel, vec3(f.up));
  float ratio = BEND_FIELD_HIGH_HZ / BEND_FIELD_LOW_HZ;
  float sum = 0.0f;
  for (uint j = 0u; j < BEND_FIELD_COMPONENTS; ++j) {
    uint key = bendHashU(f.seed * 7919u + component * 104729u + j * 31u) * 4u;
    // Band j of the log-spaced bands; its frequency jittered within it (no common period).
    float lo = BEND_FIELD_LOW_HZ * pow(ratio, float(j) / float(BEND_FIELD_COMPONENTS));
    float hi = BEND_FIELD_LOW_HZ * pow(ratio, float(j + 1u) / float(BEND_FIELD_COMPONENTS));
    float fj = lo + (hi - lo) * (0.25f + 0.5f * bendHash(key));
    float amp = sqrt(2.0f * bendKaimal(fj, L, U) * (hi - lo));
    float k = fj / U;  // cycles per domain unit along the wind
    float slopeLat = BEND_FIELD_SPREAD * (2.0f * bendHash(key + 1u) - 1.0f);
    float slopeUp = BEND_FIELD_SPREAD * (2.0f * bendHash(key + 2u) - 1.0f);
    float phase = bendHash(key + 3u);
    vec2 h = bendOscillator(fj, f0, zeta);
    // The phase in cycles, reduced to one before the cosine: a GPU's cos is only accurate near
    // [-pi, pi] (far from it llvmpipe's drifted ~1e-3 from the CPU's).
    float cycles = fract(fj * t - k * sAlong + k * (slopeLat * sLat + slopeUp * sUp) + phase);
    sum += amp * h.x * cos(tau * cycles - h.y);
  }
  return sum;
}

// The tip bend with the wind field (BEND_WIND_FIELD): the mean wind's drag as before (quasi-static,
// flexibility x s|s|, s = speed(t) / referenceSpeed), plus the fluctuation's drag linearised about
// the mean speed U (2 U u' / referenceSpeed^2, u' = gust x U x the field's response at p, so gust is
// the turbulence intensity sigma_u / U), across the wind the v component scaled by `lateral`.
CANOPY_INLINE vec3 bendFieldTip(BendFrame f, vec3 p, float t, float flexibility, float f0, float zeta) {
  float u = bendWindSpeed(f, t) / max(f.referenceSpeed, 1e-6f);
  float m = abs(f.wind.w) / max(f.referenceSpeed, 1e-6f);
  float gain = 2.0f * flexibility * m * m * f.gust;
  float along = flexibility * u * abs(u) + gain * bendFieldResponse(f, p, t, f0, zeta, 0u);
  float across = gain * f.lateral.w * bendFieldResponse(f, p, t, f0, zeta, 1u);
  if (f.strength == 0.0f) return vec3(0.0f);
  vec3 b = along * vec3(f.wind) + across * vec3(f.lateral);
  float a = sqrt(dot(b, b));
  if (a <= 0.0f) return vec3(0.0f);
  return b * (f.maxAngle * bendTanh(a / f.maxAngle) / a);
}

// The tip bend of one branch (or leaf) as a vector: its direction the way the branch leans, its
// length the angle in radians (BEND_WIND_UNIFORM, before 0.7). Drag grows with the square of the
// speed (the flexibility is the bend at the reference speed); the noise frequencies
// scale with the mean speed (a stronger wind sways faster); a lateral noise sways across the wind.
CANOPY_INLINE vec3 bendTip(BendFrame f, float t, float flexibility, float frequency, uint key) {
  float u = bendWindSpeed(f, t) / max(f.referenceSpeed, 1e-6f);
  float drag = flexibility * u * abs(u);
  float fr = frequency * (0.5f + 0.5f * abs(f.wind.w) / max(f.referenceSpeed, 1e-6f));
  float along = drag * (1.0f + f.gust * bendNoise(t, fr, key * 2u + f.seed));
  float across = abs(drag) * f.gust * f.lateral.w * bendNoise(t, fr, key * 2u + 1u + f.seed * 7919u);
  vec3 b = along * vec3(f.wind) + across * vec3(f.lateral);
  float a = sqrt(dot(b, b));
  if (a <= 0.0f) return vec3(0.0f);
  // Saturation: large winds lean a branch towards maxAngle, never past it.
  return b * (f.maxAngle * bendTanh(a / f.maxAngle) / a);
}

// Rotation of v about the unit axis k by angle a, returned as the change v' - v (Rodrigues), so a
// zero angle changes nothing, exactly.
CANOPY_INLINE vec3 bendRotateDelta(vec3 v, vec3 k, float a) {
  float c = cos(a), s = sin(a);
  return v * (c - 1.0f) + bendCross(k, v) * s + k * (dot(k, v) * (1.0f - c));
}

// Rotates point p (and direction n) about the line through `pivot` so that `axis` leans towards
// the tip-bend vector `tip` by |tip| * x^taper.
CANOPY_INLINE void bendAbout(vec3 pivot, vec3 axis, vec3 tip, float x, float taper, BEND_INOUT(vec3) p, BEND_INOUT(vec3) n) {
  float a = sqrt(dot(tip, tip));
  if (a <= 0.0f || x <= 0.0f) return;
  vec3 k = bendCross(axis, tip);
  float kl = sqrt(dot(k, k));
  if (kl <= 1e-6f * a) return;  // the branch points along the wind: no lean
  k = k / kl;
  float angle = a * pow(x, taper);
  p = p + bendRotateDelta(p - pivot, k, angle);
  n = n + bendRotateDelta(n, k, angle);
}

CANOPY_INLINE float bendW(uint w, uint level) { return float((w >> (8u * level)) & 255u) * (1.0f / 255.0f); }

// The tip bend of branch `id` (at `level`, its base at `origin`) and of leaf `leaf` (its root at
// `root`) at time t: what the motion kernel (shaders/per_vertex_tips.comp) writes once per branch
// and leaf each frame, so the vertex shader reads a branch's motion instead of synthesising it for
// each of its vertices. With the field a branch feels the wind at its base, a leaf at its root.
CANOPY_INLINE float bendLevelOf(vec4 v, uint l) { return l == 0u ? v.x : l == 1u ? v.y : l == 2u ? v.z : v.w; }
CANOPY_INLINE vec3 bendBranchTip(BendFrame f, float t, uint level, uint id, vec3 origin) {
  uint l = min(level, uint(BEND_LEVELS - 1));
  float flex = bendLevelOf(f.flexibility, l), freq = bendLevelOf(f.frequency, l);
  if (f.windModel == BEND_WIND_FIELD) return bendFieldTip(f, origin, t, flex, freq, bendLevelOf(f.damping, l));
  return bendTip(f, t, flex, freq, id + 2u);
}
CANOPY_INLINE vec3 bendLeafTip(BendFrame f, float t, uint leaf, vec3 root) {
  if (f.windModel == BEND_WIND_FIELD) return bendFieldTip(f, root, t, f.leafFlexibility, f.leafFrequency, f.leafDamping);
  return bendTip(f, t, f.leafFlexibility, f.leafFrequency, 0x9e3779b9u ^ leaf);
}

// A vertex's tip bends: its leaf's, and each branch of its chain's (chain order, trunk first).
struct BendTips {
  vec3 leaf;
  vec3 level[BEND_LEVELS];
};

// The displaced position of rest point p (n: its normal, rotated alike) at time t from its tips.
// Innermost level first, each in its parent's rest frame, so the composition is the hierarchy's: a
// leaf turns about its root, a twig leans about its base, then the branch carrying it turns the
// twig with it as it bends at the twig's w, then the trunk.
CANOPY_INLINE vec3 bendApply(BendFrame f, BendChain chain, BendTips tips, BendVertex v, bool hasLeaf, vec3 leafRoot,
                             vec3 p, float t, BEND_INOUT(vec3) n) {
  vec3 up = vec3(f.up);
  if (hasLeaf) bendAbout(leafRoot, up, tips.leaf, 1.0f, 1.0f, p, n);
  if (v.branch == BEND_LEAF_ONLY) return p;
  if (v.branch == BEND_NO_BRANCH) {
    // Fallback (a model without a hierarchy): a radial branch from the trunk axis at the height of
    // the vertex's leaf root (its own position for rigid parts) out to it, w = distance / R, then
    // the trunk, w = height / H. The radial branch's noise is shifted in time by a smooth function
    // of its azimuth, so neighbouring parts sway together and nothing tears (evaluated here: it
    // depends on the vertex's position, not on a branch).
    vec3 ref = hasLeaf ? leafRoot : p;
    vec3 rel = ref - vec3(f.root);
    float h = dot(rel, up);
    vec3 radial = rel - h * up;
    float r = sqrt(dot(radial, radial));
    if (r > 1e-6f * max(f.root.w, 1e-6f)) {
      vec3 dir = radial / r;
      vec3 tip;
      if (f.windModel == BEND_WIND_FIELD) {
        // The field where the part is: neighbouring parts feel nearly the same wind.
        tip = bendFieldTip(f, ref, t, f.flexibility.y, f.frequency.y, f.damping.y);
      } else {
        float az = bendAtan2(dot(dir, vec3(f.lateral)), dot(dir, vec3(f.wind)));
        float shift = (0.6f * sin(az) + 0.4f * cos(2.0f * az)) / max(f.frequency.y, 1e-3f);
        tip = bendTip(f, t + shift, f.flexibility.y, f.frequency.y, 1u);
      }
      bendAbout(vec3(f.root) + h * up, dir, tip, clamp(r / max(f.root.w, 1e-6f), 0.0f, 1.0f), f.taper, p, n);
    }
    vec3 tip0 = f.windModel == BEND_WIND_FIELD ? bendFieldTip(f, vec3(f.root), t, f.flexibility.x, f.frequency.x, f.damping.x)
                                               : bendTip(f, t, f.flexibility.x, f.frequency.x, 0u);
    bendAbout(vec3(f.root), up, tip0, clamp(h / max(f.up.w, 1e-6f), 0.0f, 1.0f), f.taper, p, n);
    return p;
  }
  for (int i = int(chain.count) - 1; i >= 0; --i) {
    BendBranch b = chain.b[i];
    bendAbout(b.origin, b.axis, tips.level[i], bendW(v.w, min(b.level, uint(BEND_LEVELS - 1))), f.taper, p, n);
  }
  return p;
}

// The same with the tips synthesised in place: the CPU reference of what the motion kernel and the
// vertex shader compute together.
CANOPY_INLINE vec3 bendPosition(BendFrame f, BendChain chain, BendVertex v, bool hasLeaf, vec3 leafRoot, uint leaf,
                                vec3 p, float t, BEND_INOUT(vec3) n) {
  BendTips tips;
  tips.leaf = hasLeaf ? bendLeafTip(f, t, leaf, leafRoot) : vec3(0.0f);
  for (uint i = 0u; i < uint(BEND_LEVELS); ++i)
    tips.level[i] = i < chain.count ? bendBranchTip(f, t, chain.b[i].level, chain.id[i], chain.b[i].origin) : vec3(0.0f);
  return bendApply(f, chain, tips, v, hasLeaf, leafRoot, p, t, n);
}

CANOPY_NAMESPACE_END
#endif
