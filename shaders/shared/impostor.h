// Image-based levels of detail for the foliage (seed 002, Lluch et al.; issues 18 and 36;
// docs/design.md "Impostors"): per foliage box orthographic views of its leaves (colour, alpha and
// depth) baked once into an atlas of square tiles — by default the paper's six diagonally aligned
// planes (Figure 6), or (before 0.7) those and the six box faces; at a re-slice the far boxes are
// drawn in the layer of their root depth, either as the paper's crossed polygons (every view on its
// own plane through the box, alpha-blended by how squarely it faces the viewer) or as one polygon
// facing the viewer blended from the two views nearest the viewer's direction. The bake
// (render/impostors.cpp) and the draw (shaders/layers_impostor.*) use the same view frames below.
#ifndef CANOPY_SHARED_IMPOSTOR_H
#define CANOPY_SHARED_IMPOSTOR_H
#include "interop.h"

// View directions k = 0..11: the 6 box faces (+X, -X, +Y, -Y, +Z, -Z), then the 6 diagonal planes.
// A box stores the views [firstView, IMPOSTOR_VIEWS) of its view set (ImpostorDesc.views): view k in
// tile firstTile + k - firstView.
#define IMPOSTOR_VIEWS 12u
#define IMPOSTOR_FACE_VIEWS 6u
#define IMPOSTOR_FIRST_VIEW_DIAGONAL 6u  // ImpostorViews::Diagonal6: the paper's six (default)
#define IMPOSTOR_FIRST_VIEW_ALL 0u       // ImpostorViews::FacesAndDiagonals12: before 0.7
#define IMPOSTOR_SHAPE_CROSSED 0u        // ImpostorShape::CrossedPolygons (default)
#define IMPOSTOR_SHAPE_FACING 1u         // ImpostorShape::FacingPolygon

CANOPY_NAMESPACE_BEGIN

// One box of the atlas (bound as a storage buffer; render/impostors.cpp fills it at creation).
struct ImpostorBox {
  vec4 center;      // xyz: the box's centre (world)
  vec4 halfExtent;  // xyz: half its size per axis (world); w: its level in the hierarchy
  vec4 root;        // xyz: the box's root, the mean of its leaves' roots (its layer, paper 3.2); w unused
  uint firstTile;   // its view k is atlas tile firstTile + k
  uint pad0;
  uint pad1;
  uint pad2;
};
CANOPY_SIZE_CHECK(ImpostorBox, 64)

// One box drawn as its impostor by a re-slice (instance i of the draw).
struct ImpostorInstance {
  uint box;      // into the ImpostorBox table
  float weight;  // its share of the box's pixels, (0, 1]: 1 beyond the transition band
  uint level;    // the box's level (the debug view's colour)
  uint copy;     // the copy it stands for: its index in the placed copies' table (gpu::LayerInstance)
};
CANOPY_SIZE_CHECK(ImpostorInstance, 16)

struct ImpostorPush {
  uint passKind;     // LAYER_PASS_LAYERED or LAYER_PASS_ONE_LAYER (shared/layers.h)
  uint targetLayer;  // LAYER_PASS_ONE_LAYER: the layer drawn
  uint tileSize;     // pixels per tile side
  uint tilesPerRow;  // tiles per atlas row
  uint debugLevels;  // 1: colour by hierarchy level (the debug view)
  uint rowsPerLayer; // tile rows per atlas layer
  uint fading;       // 1: boxes inside the transition band, drawn over their fading leaves: depth at
                     // the front of the box's bounding sphere (their own leaves never hide them)
  uint firstView;    // the first stored view direction (IMPOSTOR_FIRST_VIEW_*)
  uint shape;        // IMPOSTOR_SHAPE_*
  uint pad0;
  uint pad1;
  uint pad2;
};
CANOPY_SIZE_CHECK(ImpostorPush, 48)

// A view's frame: n points from the box towards the view's (orthographic) camera, u and v span the
// image (u to the right, v up; texel row 0 is +v).
struct ImpostorFrame {
  vec3 n;
  vec3 u;
  vec3 v;
};

CANOPY_INLINE vec3 impostorCross(vec3 a, vec3 b) {
  return vec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

CANOPY_INLINE vec3 impostorDirection(uint k) {
  const float s = 0.70710678f;
  if (k == 0u) return vec3(1.0f, 0.0f, 0.0f);
  if (k == 1u) return vec3(-1.0f, 0.0f, 0.0f);
  if (k == 2u) return vec3(0.0f, 1.0f, 0.0f);
  if (k == 3u) return vec3(0.0f, -1.0f, 0.0f);
  if (k == 4u) return vec3(0.0f, 0.0f, 1.0f);
  if (k == 5u) return vec3(0.0f, 0.0f, -1.0f);
  // The diagonal planes: each contains two opposite edges of the box (Lluch et al. Figure 6).
  if (k == 6u) return vec3(s, s, 0.0f);
  if (k == 7u) return vec3(s, -s, 0.0f);
  if (k == 8u) return vec3(s, 0.0f, s);
  if (k == 9u) return vec3(s, 0.0f, -s);
  if (k == 10u) return vec3(0.0f, s, s);
  return vec3(0.0f, s, -s);
}

CANOPY_INLINE ImpostorFrame impostorFrameOf(uint k) {
  ImpostorFrame f;
  f.n = impostorDirection(k);
  vec3 up = abs(f.n.y) > 0.9f ? vec3(0.0f, 0.0f, -1.0f) : vec3(0.0f, 1.0f, 0.0f);
  f.u = normalize(impostorCross(up, f.n));
  f.v = impostorCross(f.n, f.u);
  return f;
}

// Half the box's extent along u, v and n (its support): the image spans [-x, x] x [-y, y], the
// depth [-z, z]. Never below `floor` (a flat box still gets a non-degenerate image).
CANOPY_INLINE vec3 impostorExtent(ImpostorFrame f, vec3 h, float floorValue) {
  vec3 e = vec3(abs(h.x * f.u.x) + abs(h.y * f.u.y) + abs(h.z * f.u.z),
                abs(h.x * f.v.x) + abs(h.y * f.v.y) + abs(h.z * f.v.z),
                abs(h.x * f.n.x) + abs(h.y * f.n.y) + abs(h.z * f.n.z));
  return max(e, vec3(floorValue));
}

// How well view k shows a box seen from direction w (unit, towards the viewer): the face views are
// one-sided, a diagonal plane's image serves both of its sides.
CANOPY_INLINE float impostorViewScore(uint k, vec3 w) {
  float c = dot(impostorDirection(k), w);
  return k < IMPOSTOR_FACE_VIEWS ? c : abs(c);
}

// A crossed polygon's weight (ImpostorShape::CrossedPolygons) from its view's score for the viewer's
// direction: 0 edge-on (a polygon seen edge-on is a streak, not an image), rising to 1 where the
// polygon faces the viewer at least as squarely as a box face's diagonal planes do when the box is
// seen along an axis (cos 45 deg): from any direction the best-facing views carry the image.
CANOPY_INLINE float impostorCrossWeight(float score) {
  return clamp((score - 0.2f) / (0.70710678f - 0.2f), 0.0f, 1.0f);
}

// The impostor's share of a box at a level-of-detail switch (docs/design.md "Impostors"): 0 while
// the box's projected size is at least switchPixels * (1 + band), 1 at switchPixels or below,
// linear in between (projected size is inversely proportional to distance: a distance band).
// Monotone: never increases with the projected size.
CANOPY_INLINE float impostorSizeWeight(float projectedPixels, float switchPixels, float band) {
  if (band <= 0.0f) return projectedPixels <= switchPixels ? 1.0f : 0.0f;
  return clamp((switchPixels * (1.0f + band) - projectedPixels) / (switchPixels * band), 0.0f, 1.0f);
}

// 0..1 ramp over [start, start + width] of view depth (the far region's start, FarRegion mode).
CANOPY_INLINE float impostorDepthWeight(float depth, float start, float width) {
  if (width <= 0.0f) return depth >= start ? 1.0f : 0.0f;
  return clamp((depth - start) / width, 0.0f, 1.0f);
}

CANOPY_NAMESPACE_END
#endif
