// Layer dynamics (paper 3.4-3.6, docs/design.md): the simulation-plane velocity projected to the view
// (eq. 1-2 as the general rotation), the layer delay (eq. 3-5) and the displacement of the warp
// grid's corners (eq. 6-7). The formulas are shared inline functions, compiled into the compute
// shader and into the C++ reference, so the two cannot drift.
#ifndef CANOPY_SHARED_ANIM_H
#define CANOPY_SHARED_ANIM_H
#include "interop.h"
#include "layers.h"

#define ANIM_DELAY_EXACT 0u        // sample the history ring at t - gamma_i (eq. 3)
#define ANIM_DELAY_APPROXIMATE 1u  // one lookup at B = A + gamma_i s V (eq. 5)
#define ANIM_OFFSET_DIRECTION 0u    // eq. 5: B = A + gamma s V/|V| (the paper's distance travelled)
#define ANIM_OFFSET_VELOCITY 1u     // B = A + gamma s V (before 0.7)
#define ANIM_GROUP_SIZE 64u
// AnimFrame.newestSlot when the ring's slots are not known to be in step order: search them all.
#define ANIM_RING_UNORDERED 0xffffffffu

CANOPY_NAMESPACE_BEGIN

struct AnimLayer {
  float depth;        // representative view depth, world units
  float distance;     // L_i: depth - depth of layer 0, domain units (or world: DynamicsParams.delayUnits)
  float attenuation;  // A_i = 1 - m (L_i / L_{n-1})^2 (docs/design.md's reading of eq. 6)
  float rootLineY;    // pixel row of the root line (y down)
  float height;       // h of eq. 7, pixels
  float vd;           // V_D of eq. 4 for this layer, domain units/s (DynamicsParams.vd and vdJitter)
  // Per-plant roots (docs/design.md "Per-plant roots"): this layer's plant rects in the frame
  // block's plant table (after the AnimFrame); plantCount 0: the layer's rootLineY and height.
  uint firstPlant;
  uint plantCount;
};
CANOPY_SIZE_CHECK(AnimLayer, 32)
// Plant rects the frame block holds after the AnimFrame (all layers together), ANIM_RECT_VEC4S vec4
// each: the rect (x lo, x hi, top, root row; pixels, y down), its species' wind response
// (flexibility, response speed; docs/design.md "Species: wind response"), and in its z 1 when the
// rect's root line is eq. 7's (per-plant roots), 0 when the layer's is (the rects then only carry
// the response), in w eq. 7's h; then in x the view depth at which the plant's corners read the
// wind field (its centre's: every layer of one plant in the same gust, docs/design.md "Rigid parts
// in wind"; 0: the layer's depth), in y 1 when the plant has no leaves in the layer (its rect serves
// its rigid parts only: plantRectBetter).
#define ANIM_MAX_PLANT_RECTS 3072u
#define ANIM_RECT_VEC4S 3u

struct AnimFrame {
  mat4 invViewProj;   // Vulkan clip -> world (unprojects grid corners)
  mat4 viewRotation;  // world -> view rotation (R_view), translation zero
  vec4 depthRow;      // view depth of world p: dot(depthRow, vec4(p, 1))
  vec4 simOrigin;     // xyz: world point at simulation coordinate (0, 0); w: tile size, world units
  vec4 simRight;      // xyz: the simulation plane's x axis (unit, world)
  vec4 simUp;         // xyz: its y axis (unit, world)
  vec4 bendOrigin;    // the pushers' bend field: xyz the world point at its coordinate (0, 0); w: tile size, world units
  vec4 bendX;         // xyz: its first axis (unit, horizontal)
  vec4 bendZ;         // xyz: its second axis (unit, horizontal)
  vec4 lambda;        // xyz: lambda_x, lambda_y, lambda_z, pixels per domain unit; w: dt of eq. 6, s
  float time;         // time of the newest simulation field, s
  uint halfResolution;  // LayerFrame.halfResolution of the layers drawn (the composite's reads)
  float propagation;  // s of eq. 5 (ANIM_OFFSET_DIRECTION: domain units/s; B moves gamma s domain units)
  float rigidity;     // r of eq. 7, [0, 10]
  uint everyPartMoves;  // 1: R = 1 (eq. 7)
  uint delayMode;     // ANIM_DELAY_*
  uint n;             // simulation grid, cells per side
  uint ringSize;      // H
  uint layerCount;
  uint gridX;         // warp-grid corners per row
  uint gridY;         // corners per column
  float cellSize;     // pixels
  float width;        // image, pixels
  float height;
  float maxDelay;     // |gamma| clamp for a vanishing denominator, s
  // The ring slot holding the newest field when slots are written in step order (slot = step % H,
  // so going back k slots goes back k steps and the times never increase): the exact delay then
  // finds its two slots by binary search. ANIM_RING_UNORDERED: by a search of every slot.
  uint newestSlot;
  uint offsetMode;    // ANIM_OFFSET_*: eq. 5's offset along V's direction or V itself
  uint bend;          // 1: add the pushers' bend field (the tiled buffer after V_s and V_wind: shared/sim.h)
  float maxShrink;    // eq. 6's lambda_z |V_z| at most this share of a corner's height above its root (DynamicsParams.maxShrink)
  uint heightRelative;  // 1: eq. 6 times the plant's height h (World wind: lambda in shares of h per metre)
  float maxStretch;   // the displacement's largest change across one warp cell, in cells (DynamicsParams.maxStretch; 0: unbounded)
  uint pad0, pad1, pad2;
  AnimLayer layers[CANOPY_MAX_LAYERS];
};
CANOPY_SIZE_CHECK(AnimFrame, 64 * 2 + 16 * 8 + 4 * 24 + 32 * CANOPY_MAX_LAYERS)

// Eq. 1-2 in general: simulation-plane velocity -> world -> view.
CANOPY_INLINE vec3 simToView(AnimFrame f, vec2 vs) {
  vec3 w = vs.x * vec3(f.simRight) + vs.y * vec3(f.simUp);
  return vec3(f.viewRotation * vec4(w, 0.0f));
}

// Eq. 4: gamma_i = L_i / (-V_0z + V_D), bounded by maxDelay when the denominator vanishes. L_i
// and V_D are the layer's (both in domain units by default, so gamma does not depend on the model's
// scale), maxDelay the frame's.
CANOPY_INLINE float layerDelay(float maxDelay, AnimLayer layer, float v0z) {
  float denom = -v0z + layer.vd;
  float g = layer.distance / (abs(denom) > 1e-6f ? denom : (denom < 0.0f ? -1e-6f : 1e-6f));
  return clamp(g, -maxDelay, maxDelay);
}

// Eq. 5: B = A + gamma s V/|V| (a steady wave travelling along V at speed s makes the field at B now
// what it was at A gamma earlier), or A + gamma s V (ANIM_OFFSET_VELOCITY). A still field stays at A.
CANOPY_INLINE vec2 approximateLookup(AnimFrame f, vec2 a, float gamma, vec2 vs) {
  if (f.offsetMode == ANIM_OFFSET_VELOCITY) return a + gamma * f.propagation * vs;
  float speed = length(vs);
  return speed > 1e-12f ? a + (gamma * f.propagation / speed) * vs : a;
}

// The helpers below take the layer's record (f.layers[i]) rather than indexing the frame's array:
// GLSL passes a struct by value, and lavapipe copies a frame whose array the callee indexes
// dynamically on every call (measured on the simulation's motors, docs/performance.md).

// Eq. 7: R = 1, or (l / h)^r with l the height above the root line, clamped to [0, 1] (the paper's
// range, with the world wind too: a reach of 2 let the top of a plant whose box's projection put h
// low lean past its crown and cost the field's gale orbit 7 % of its foliage's coverage; h held to
// the plant's span above its foot, render/layer_placement.cpp, puts its top leaves at R = 1).
CANOPY_INLINE float rigidityFactor(AnimFrame f, AnimLayer layer, float pixelY) {
  if (f.everyPartMoves != 0u) return 1.0f;
  float l = layer.rootLineY - pixelY;
  float x = clamp(l / max(layer.height, 1.0f), 0.0f, 1.0f);
  return f.rigidity == 0.0f ? 1.0f : pow(x, f.rigidity);
}

// Per-plant roots: the distance (squared, pixels) from pixel p to plant rect r (0 inside) and the
// rect's rank; a corner takes the nearest rect, of those it lies in a rect of a plant with leaves in
// the layer before one that only its rigid parts reach (`woodOnly` 1; they follow the layer of their
// own depth: docs/design.md "Rigid parts in wind"), then the smallest (a plant inside a larger one's
// rect: a tree in a grass patch).
CANOPY_INLINE float plantRectDistance2(vec4 r, vec2 p) {
  float dx = max(max(r.x - p.x, p.x - r.y), 0.0f), dy = max(max(r.z - p.y, p.y - r.w), 0.0f);
  return dx * dx + dy * dy;
}
CANOPY_INLINE float plantRectRank(vec4 r, float woodOnly) {
  return (r.y - r.x) * (r.w - r.z) + (woodOnly > 0.0f ? 1.0e9f : 0.0f);
}
CANOPY_INLINE bool plantRectBetter(vec4 r, float woodOnly, vec2 p, float bestDistance2, float bestRank) {
  float d = plantRectDistance2(r, p);
  return d < bestDistance2 || (d == bestDistance2 && plantRectRank(r, woodOnly) < bestRank);
}
// The layer's record with eq. 7's root line of plant rect r and height h (pixels; 0: the rect's rows).
CANOPY_INLINE AnimLayer withPlantRoot(AnimLayer layer, vec4 r, float h) {
  layer.rootLineY = r.w;
  layer.height = max(h > 0.0f ? h : r.w - r.z, 1.0f);
  return layer;
}

// A species' response speed (docs/design.md "Species: wind response") divides eq. 4's delay: a
// slow species lags the nearest layer's wind further, a fast one follows it sooner.
CANOPY_INLINE float speciesDelay(float maxDelay, float gamma, float responseSpeed) {
  return clamp(gamma / max(responseSpeed, 0.25f), -maxDelay, maxDelay);
}

// Eq. 6 (docs/design.md's reading) in pixels, y pointing down the image (view y points up).
CANOPY_INLINE vec2 displacementPixels(AnimFrame f, AnimLayer layer, float pixelY, vec3 vi) {
  float k = rigidityFactor(f, layer, pixelY) * layer.attenuation * f.lambda.w;
  if (f.heightRelative != 0u) k *= layer.height;
  float dx = k * f.lambda.x * vi.x;
  // The shrink along the view (the paper's Figure 9) is bounded by a share of the height above the
  // root: with the wind along the view the whole of V is V_z, and the unbounded term would pull a
  // crown's top down by more than the crown (docs/design.md "World wind"). World wind: the
  // foreshortening of the lean itself, l - sqrt(l^2 - e^2) for a corner l above its root leaning
  // e = k lambda_x |V_z| along the view (the lean it shows when seen across), not the paper's
  // linear term, which shrank a crown in a breeze ten times more than the lean can.
  float l = max(layer.rootLineY - pixelY, 0.0f);
  float e = k * f.lambda.x * abs(vi.z);
  float shrink = f.heightRelative != 0u ? l - sqrt(max(l * l - e * e, 0.0f)) : k * f.lambda.z * abs(vi.z);
  shrink = min(shrink, f.maxShrink * l);
  float dyUp = k * f.lambda.y * vi.y - shrink;
  return vec2(dx, -dyUp);
}

// The warp's stretch bound (docs/design.md "Layers: the warp's stretch"): d shortened to the
// bounded magnitude m of its corner, its direction kept (anim_stretch_rows.comp and the reference).
CANOPY_INLINE vec2 stretchBounded(vec2 d, float m) {
  float l = length(d);
  return l > m ? d * (m / l) : d;
}

CANOPY_NAMESPACE_END
#endif
