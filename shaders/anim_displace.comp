#version 460
#extension GL_GOOGLE_include_directive : require
// Displacement of every warp-grid corner of every layer (paper 3.4-3.6): the corner's pixel is
// unprojected at the layer's depth, mapped to the tiled simulation field (orthogonal projection on
// the simulation plane, fract(coord / tile)), its velocity projected to the view (eq. 1-2), delayed
// for the layer (eq. 3-4 exact: the history ring at t - gamma, linear in time; eq. 5 approximate:
// one lookup at B = A + gamma s V_s), and turned into d_i (eq. 6-7).
#include "shared/anim.h"
#include "shared/sim.h"

layout(local_size_x = ANIM_GROUP_SIZE) in;
layout(binding = 0, scalar) readonly buffer FrameBuf {
  AnimFrame frameIn;
  vec4 plantRects[];  // per-plant roots (AnimLayer.firstPlant, plantCount), ANIM_RECT_VEC4S each
};
// Loaded once per invocation: the shared helpers take the frame by value, and passing the buffer
// member copies it from memory at every call (shaders/sim_common.glsl).
AnimFrame f;
layout(binding = 1, scalar) readonly buffer TiledBuf { vec2 tiled[]; };
layout(binding = 2, scalar) readonly buffer RingBuf { vec2 ring[]; };
layout(binding = 3, scalar) readonly buffer RingTimesBuf { float ringTimes[]; };
layout(binding = 4, scalar) readonly buffer DispBuf { vec2 disp[]; };
// Last frame's displacement, kept for motion vectors (each invocation moves its own corner).
layout(binding = 5, scalar) writeonly buffer PrevBuf { vec2 prevDisp[]; };
// Eq. 6-7 of the wind before the stretch bound (anim_stretch_cols.comp, anim_stretch_rows.comp
// write disp), and the pushers' share added after it: the bound smooths the wind's field between
// plants, a pusher parts the grass where it walks (a hole it made in the wind's magnitude would
// spread as a cone of the bound's slope: docs/design.md "Layers: the warp's stretch").
layout(binding = 6, scalar) writeonly buffer RawBuf { vec2 raw[]; };
layout(binding = 7, scalar) writeonly buffer BendShareBuf { vec2 bendShare[]; };

// Bilinear, periodic sample of an n*n field (cell centres at (i + 0.5) / n, row 0 at the bottom)
// at tile coordinates a (any real; the field repeats with period 1). base: offset of the field.
vec2 sampleTiled(bool fromRing, uint base, vec2 a) {
  uint n = f.n;
  vec2 x = fract(a) * float(n) - 0.5;
  vec2 fl = floor(x);
  vec2 t = x - fl;
  int i0 = int(fl.x), j0 = int(fl.y);
  uint ia = uint((i0 + int(n)) % int(n)), ib = uint((i0 + 1 + int(n)) % int(n));
  uint ja = uint((j0 + int(n)) % int(n)), jb = uint((j0 + 1 + int(n)) % int(n));
  vec2 v00, v10, v01, v11;
  if (fromRing) {
    v00 = ring[base + ja * n + ia]; v10 = ring[base + ja * n + ib];
    v01 = ring[base + jb * n + ia]; v11 = ring[base + jb * n + ib];
  } else {
    v00 = tiled[ja * n + ia]; v10 = tiled[ja * n + ib];
    v01 = tiled[jb * n + ia]; v11 = tiled[jb * n + ib];
  }
  return mix(mix(v00, v10, t.x), mix(v01, v11, t.x), t.y);
}

// The two slots bracketing tau (latest at or before it, earliest at or after it), tau clamped to
// the history that exists. In step order (f.newestSlot known) the time k slots back never increases
// with k (unwritten slots read 0), so a binary search finds them: log2(H) loads per corner instead
// of 2H — the linear search was most of the dynamics pass's cost on lavapipe (docs/performance.md).
// Both searches pick the same slots (the linear one remains for rings in any order).
void historySlots(inout float tau, out uint lo, out uint hi) {
  uint H = f.ringSize, newest = f.newestSlot;
  float tNewest = ringTimes[newest], tOldest = ringTimes[(newest + 1u) % H];
  tau = clamp(tau, min(tOldest, tNewest), tNewest);
  uint a = 0u, b = H - 1u;  // smallest k with time(k) <= tau (time(H - 1) is the minimum)
  while (a < b) {
    uint mid = (a + b) >> 1u;
    if (ringTimes[(newest + H - mid) % H] <= tau) b = mid;
    else a = mid + 1u;
  }
  lo = (newest + H - a) % H;
  hi = a > 0u ? (newest + H - a + 1u) % H : lo;
}

// The pushers' bend field at world point w (docs/design.md "Pushers"): a horizontal world vector,
// tile units/s; bilinear over its cells, zero outside them (it is not tiled), and above the height
// its pushers reached (the world's +Y up).
vec3 sampleBend(vec3 w) {
  uint n = f.n, bn = SIM_BEND_SCALE * n;
  vec3 rel = w - f.bendOrigin.xyz;
  vec2 g = vec2(dot(rel, f.bendX.xyz), dot(rel, f.bendZ.xyz)) / f.bendOrigin.w;
  vec2 x = g * float(n) - 0.5;
  vec2 fl = floor(x);
  vec2 t = x - fl;
  int i0 = int(fl.x), j0 = int(fl.y);
  // Each cell's bend counts up to the height its pusher reached, fading over its radius above:
  // what is higher (a farther plant's part seen above the path in the same slab) is not touched.
  vec2 v[4];
  for (int k = 0; k < 4; ++k) {
    int i = i0 + (k & 1), j = j0 + (k >> 1);
    bool inside = i >= 0 && j >= 0 && i < int(bn) && j < int(bn);
    uint c = uint(j) * bn + uint(i);
    vec2 reach = inside ? tiled[bendReachOffset(n) + c] : vec2(0.0, 1.0);
    float above = clamp((w.y - reach.x) / max(reach.y, 1e-6), 0.0, 1.0);
    v[k] = inside ? tiled[bendOffset(n) + c] * (1.0 - above) : vec2(0.0);
  }
  vec2 b = mix(mix(v[0], v[1], t.x), mix(v[2], v[3], t.x), t.y);
  return b.x * f.bendX.xyz + b.y * f.bendZ.xyz;
}

// The simulation-plane velocity at time tau from the ring: the two slots bracketing tau, linear in
// time; tau is clamped to the history that exists.
vec2 sampleHistory(vec2 a, float tau) {
  if (f.newestSlot != ANIM_RING_UNORDERED) {
    uint lo, hi;
    historySlots(tau, lo, hi);
    float span = ringTimes[hi] - ringTimes[lo];
    float w = span > 0.0 ? (tau - ringTimes[lo]) / span : 0.0;
    uint nn = f.n * f.n;
    return mix(sampleTiled(true, lo * nn, a), sampleTiled(true, hi * nn, a), w);
  }
  uint newest = 0u, oldest = 0u;
  for (uint s = 1u; s < f.ringSize; ++s) {
    if (ringTimes[s] > ringTimes[newest]) newest = s;
    if (ringTimes[s] < ringTimes[oldest]) oldest = s;
  }
  tau = clamp(tau, ringTimes[oldest], ringTimes[newest]);
  uint lo = oldest, hi = newest;
  for (uint s = 0u; s < f.ringSize; ++s) {
    float ts = ringTimes[s];
    if (ts <= tau && ts >= ringTimes[lo]) lo = s;
    if (ts >= tau && ts <= ringTimes[hi]) hi = s;
  }
  float span = ringTimes[hi] - ringTimes[lo];
  float w = span > 0.0 ? (tau - ringTimes[lo]) / span : 0.0;
  uint nn = f.n * f.n;
  return mix(sampleTiled(true, lo * nn, a), sampleTiled(true, hi * nn, a), w);
}

void main() {
  f = frameIn;
  uint corners = f.gridX * f.gridY;
  uint id = gl_GlobalInvocationID.x;
  uint layer = gl_GlobalInvocationID.y;
  if (id >= corners || layer >= f.layerCount) return;
  uint gx = id % f.gridX, gy = id / f.gridX;
  vec2 pixel = min(vec2(gx, gy) * f.cellSize, vec2(f.width, f.height));
  // Eq. 7 about the root of the plant this corner belongs to (per-plant roots), else the layer's;
  // the plant's species' wind response with it (flexibility, response speed), and the depth its
  // corners read the field at (the plant's centre: one gust for the plant's every layer).
  AnimLayer rooted = f.layers[layer];
  vec2 response = vec2(1.0);
  float sampleDepth = f.layers[layer].depth;
  float bestD = 3.0e38, bestA = 3.0e38;
  for (uint j = rooted.firstPlant; j < rooted.firstPlant + rooted.plantCount; ++j) {
    vec4 r = plantRects[ANIM_RECT_VEC4S * j];
    vec4 place = plantRects[ANIM_RECT_VEC4S * j + 2u];  // sample depth, wood only
    if (plantRectBetter(r, place.y, pixel, bestD, bestA)) {
      bestD = plantRectDistance2(r, pixel);
      bestA = plantRectRank(r, place.y);
      vec4 species = plantRects[ANIM_RECT_VEC4S * j + 1u];
      rooted = species.z > 0.0 ? withPlantRoot(f.layers[layer], r, species.w) : f.layers[layer];
      response = species.xy;
      sampleDepth = place.x > 0.0 ? place.x : f.layers[layer].depth;
    }
  }
  // Unproject: the point on the pixel's ray at that view depth (depth is affine along the ray).
  vec2 ndc = pixel / vec2(f.width, f.height) * 2.0 - 1.0;
  vec4 h0 = f.invViewProj * vec4(ndc, 0.0, 1.0);
  vec4 h1 = f.invViewProj * vec4(ndc, 1.0, 1.0);
  vec3 p0 = h0.xyz / h0.w, p1 = h1.xyz / h1.w;
  float d0 = dot(f.depthRow, vec4(p0, 1.0)), d1 = dot(f.depthRow, vec4(p1, 1.0));
  vec3 world = p0 + (p1 - p0) * ((sampleDepth - d0) / (d1 - d0));
  // Simulation-plane coordinates in tile units (the tiled field repeats with period 1).
  vec3 rel = world - f.simOrigin.xyz;
  vec2 a = vec2(dot(rel, f.simRight.xyz), dot(rel, f.simUp.xyz)) / f.simOrigin.w;
  vec2 vs = sampleTiled(false, 0u, a);
  // The pushers bend each layer where its foliage meets them, undelayed (docs/design.md "Pushers"):
  // the corner's ray is taken where it crosses the pushers' height (bendOrigin.y), held inside the
  // layer's slab (half-way to its neighbours' depths), so the layer holding the pushed plants gets
  // the bend at their place and the others only where their slab comes near it.
  vec3 bend = vec3(0.0);
  if (f.bend != 0u) {
    float zLayer = f.layers[layer].depth;
    float lo = layer > 0u ? 0.5 * (f.layers[layer - 1u].depth + zLayer) : -3.0e38;
    float hi = layer + 1u < f.layerCount ? 0.5 * (zLayer + f.layers[layer + 1u].depth) : 3.0e38;
    float dy = p1.y - p0.y;
    float zHit = abs(dy) > 1e-12 ? d0 + (d1 - d0) * ((f.bendOrigin.y - p0.y) / dy) : zLayer;
    float z = zHit > 0.0 ? clamp(zHit, lo, hi) : zLayer;
    vec3 at = p0 + (p1 - p0) * ((z - d0) / (d1 - d0));
    bend = vec3(f.viewRotation * vec4(sampleBend(at), 0.0));
  }
  vec3 v0 = simToView(f, vs);  // eq. 4's V_0 (the delays): the wind's
  vec3 vi = v0 + bend;
  if (layer > 0u) {
    float gamma = speciesDelay(f.maxDelay, layerDelay(f.maxDelay, f.layers[layer], v0.z), response.y);
    if (f.delayMode == ANIM_DELAY_EXACT) {
      vi = simToView(f, sampleHistory(a, f.time - gamma)) + bend;
    } else {
      // Simulation coordinates are domain units = tile units (eq. 5: shared/anim.h).
      vi = simToView(f, sampleTiled(false, 0u, approximateLookup(f, a, gamma, vs))) + bend;
    }
  }
  uint at = layer * corners + id;
  prevDisp[at] = disp[at];
  vec2 full = response.x * displacementPixels(f, rooted, pixel.y, vi);
  vec2 wind = f.bend != 0u ? response.x * displacementPixels(f, rooted, pixel.y, vi - bend) : full;
  raw[at] = wind;
  bendShare[at] = full - wind;
}
