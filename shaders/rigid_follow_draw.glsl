// Rigid parts in wind (docs/design.md "Rigid parts in wind"; shared/rigid.h): the rigid chunks drawn
// every frame into the host's targets, each vertex displaced by its share of the displacement of
// the foliage layer its depth falls in, at its own pixel of the slice camera, then drawn by the
// current camera; shaded by the layers' fragment shader. The frame block (binding 0) is the visible
// placement's (the slice camera, the layers' boundaries) with the composite's exposure in its light.
#define CANOPY_VERTEX
#include "layers_common.glsl"
#include "shared/rigid.h"

layout(binding = 6, scalar) readonly buffer RigidBuf { RigidFrame rf; };
layout(binding = 7, scalar) readonly buffer AnimBuf { AnimFrame anim; };
layout(binding = 8, scalar) readonly buffer DispBuf { vec2 disp[]; };
#ifdef RIGID_MOTION
layout(binding = 9, scalar) readonly buffer PrevBuf { vec2 prevDisp[]; };
// Screen-space motion in pixels: this frame's position under this frame's camera minus last frame's
// (its displacement then) under last frame's camera, as the composite writes the foliage's.
layout(location = 4) out vec2 vMotion;
#endif

void main() {
  emitVertex();  // the still vertex: vWorld (the shading's), normal, uv, tint
  vec3 world = vWorld, before = vWorld;
  float share = hasLeaf() ? 0.0 : rigidShare();
  vec4 clip = f.viewProj * vec4(vWorld, 1.0);
  if ((rf.flags & RIGID_FLAG_DISPLACE) != 0u && share > 0.0 && clip.w > 0.0 && anim.gridX >= 2u && anim.gridY >= 2u) {
    vec3 ndc = clip.xyz / clip.w;
    vec2 size = vec2(anim.width, anim.height);
    vec2 p = (ndc.xy * 0.5 + 0.5) * size;
    uint layer = min(rigidLayer(vWorld), anim.layerCount - 1u);
    AnimGridSample s = animGridSample(anim.cellSize, anim.gridX, anim.gridY, size, p);
    uint base = layer * anim.gridX * anim.gridY;
    // Shown where the inverse warp shows p (shared/rigid.h RIGID_SHOWN_STEPS).
    vec2 d = animGridBlend(s, disp[base + s.i00], disp[base + s.i10], disp[base + s.i01], disp[base + s.i11]);
    for (uint k = 0u; k < RIGID_SHOWN_STEPS; ++k) {
      AnimGridSample at = animGridSample(anim.cellSize, anim.gridX, anim.gridY, size, p + d);
      d = animGridBlend(at, disp[base + at.i00], disp[base + at.i10], disp[base + at.i01], disp[base + at.i11]);
    }
    vec4 q = anim.invViewProj * vec4(rigidDisplacedNdc(ndc, share * d, size), 1.0);
    world = q.xyz / q.w;
#ifdef RIGID_MOTION
    vec2 d0 = animGridBlend(s, prevDisp[base + s.i00], prevDisp[base + s.i10], prevDisp[base + s.i01], prevDisp[base + s.i11]);
    for (uint k = 0u; k < RIGID_SHOWN_STEPS; ++k) {
      AnimGridSample at = animGridSample(anim.cellSize, anim.gridX, anim.gridY, size, p + d0);
      d0 = animGridBlend(at, prevDisp[base + at.i00], prevDisp[base + at.i10], prevDisp[base + at.i01], prevDisp[base + at.i11]);
    }
    vec4 q0 = anim.invViewProj * vec4(rigidDisplacedNdc(ndc, share * d0, size), 1.0);
    before = q0.xyz / q0.w;
#endif
  }
  gl_Position = rf.currentViewProj * vec4(world, 1.0);
#ifdef RIGID_MOTION
  vec4 c0 = rf.previousViewProj * vec4(before, 1.0);
  vMotion = (rf.flags & RIGID_FLAG_MOTION_VALID) != 0u ? (gl_Position.xy / gl_Position.w - c0.xy / c0.w) * 0.5 * rf.targetSize
                                                        : vec2(0.0);
#endif
}
