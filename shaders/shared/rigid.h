// Rigid parts in wind (docs/design.md "Rigid parts in wind"): the trunks and branches are drawn
// every frame into the host's targets, each vertex displaced as the composite displaces the foliage
// layer of its anchor's depth, by its share (shared/layers.h LAYER_CHUNK_RIGID). The displacement
// lives in the slice camera's layer pixels (docs/design.md "Layers: reprojection"): a vertex goes to
// its slice pixel p, takes d = share x d_i(p) of layer i = layerOfDepth(its anchor's depth), and is unprojected
// from p + d at its own depth, then drawn by the current camera. Read by shaders/rigid_follow.vert,
// shaders/shadow.vert and the CPU (rigidDisplacedNdc; the attachment-gap bench).
#ifndef CANOPY_SHARED_RIGID_H
#define CANOPY_SHARED_RIGID_H
#include "anim.h"

#define RIGID_FLAG_DISPLACE 1u       // the warp grid is valid (a frame of the 2D method was prepared)
#define RIGID_FLAG_MOTION_VALID 2u   // the previous displacement and camera are last frame's

CANOPY_NAMESPACE_BEGIN

struct RigidFrame {
  mat4 currentViewProj;   // the host's camera this frame (its own depth convention)
  mat4 previousViewProj;  // last frame's (motion vectors); this frame's after a cut
  vec2 targetSize;        // the host's targets, pixels
  uint flags;             // RIGID_FLAG_*
  uint pad0;
};
CANOPY_SIZE_CHECK(RigidFrame, 144)

// The warp grid's bilinear lookup at layer pixel p (pixel centres at +0.5, y down): the four corner
// indices and weights, as the composite's gridSample (corner (gx, gy) at (min(gx cell, width),
// min(gy cell, height))), clamped to the grid.
struct AnimGridSample {
  uint i00;
  uint i10;
  uint i01;
  uint i11;
  vec2 t;
};
CANOPY_INLINE AnimGridSample animGridSample(float cellSize, uint gridX, uint gridY, vec2 size, vec2 p) {
  AnimGridSample s;
  float cx = clamp(floor(p.x / cellSize), 0.0f, float(gridX - 2u));
  float cy = clamp(floor(p.y / cellSize), 0.0f, float(gridY - 2u));
  float x0 = cx * cellSize, y0 = cy * cellSize;
  float x1 = min(x0 + cellSize, size.x), y1 = min(y0 + cellSize, size.y);
  s.t = vec2(clamp((p.x - x0) / max(x1 - x0, 1e-6f), 0.0f, 1.0f), clamp((p.y - y0) / max(y1 - y0, 1e-6f), 0.0f, 1.0f));
  uint gx = uint(cx), gy = uint(cy);
  s.i00 = gy * gridX + gx;
  s.i10 = s.i00 + 1u;
  s.i01 = s.i00 + gridX;
  s.i11 = s.i01 + 1u;
  return s;
}
CANOPY_INLINE vec2 animGridBlend(AnimGridSample s, vec2 d00, vec2 d10, vec2 d01, vec2 d11) {
  return mix(mix(d00, d10, s.t.x), mix(d01, d11, s.t.x), s.t.y);
}

// Where the inverse warp shows layer pixel p (docs/design.md "Rigid parts in wind"): the composite
// reads pixel s at s - d(s), so p is shown at the s with s - d(s) = p, found by fixed-point steps
// s <- p + d(s) from s = p + d(p) (d changes by at most maxStretch of a cell per cell, so each
// step shrinks the error by that factor). A forward p + d(p) would put a branch off its leaves by
// the change of d over the displacement itself (10 px of 130 in a gale).
#define RIGID_SHOWN_STEPS 4u

// The slice camera's NDC (x, y, z) of a point displaced by d layer pixels (layer images of `size`):
// the point shown at p + d at the same depth. invViewProj unprojects it (AnimFrame.invViewProj).
CANOPY_INLINE vec3 rigidDisplacedNdc(vec3 ndc, vec2 d, vec2 size) {
  return vec3(ndc.x + 2.0f * d.x / size.x, ndc.y + 2.0f * d.y / size.y, ndc.z);
}

CANOPY_NAMESPACE_END
#endif
