#version 460
#extension GL_GOOGLE_include_directive : require
// The vegetation's shadow caster (docs/design.md "Shadows"). Each foliage vertex goes into the layer
// of its leaf's root as the layers place it (layerOfDepth on the slice camera's frame block, the
// visible placement's), reads that layer's warp displacement d at its own pixel of the slice
// camera (bilinear between the warp-grid corners, as the composite does), and moves to where the
// screen shows it: the composite shows the layer's content at p + d, so the vertex is unprojected
// from p + d at its own depth. Rigid parts follow by their share with RigidMotion::FollowFoliage
// (shared/rigid.h); vertices behind the slice camera stay where they are. Then it is drawn from the light.
#define CANOPY_VERTEX
#include "layers_common.glsl"
#include "shared/rigid.h"
#include "shared/shadow.h"

layout(binding = 6, scalar) readonly buffer ShadowBuf { ShadowFrame sf; };
layout(binding = 7, scalar) readonly buffer AnimBuf { AnimFrame anim; };
layout(binding = 8, scalar) readonly buffer DispBuf { vec2 disp[]; };

// Layer `layer`'s displacement at `pixel` (layer-image pixels, y down): bilinear between the grid's
// corners as the composite reads it, clamped to the grid (a leaf off the slice camera's image takes
// the edge's).
vec2 displacementAt(uint layer, vec2 pixel) {
  AnimGridSample s = animGridSample(anim.cellSize, anim.gridX, anim.gridY, vec2(anim.width, anim.height), pixel);
  uint base = layer * anim.gridX * anim.gridY;
  return animGridBlend(s, disp[base + s.i00], disp[base + s.i10], disp[base + s.i01], disp[base + s.i11]);
}

void main() {
  emitVertex();
  vec3 world = vWorld;
  bool leaf = hasLeaf();
  // A leaf goes with its root's layer; a rigid vertex (rigid parts in wind) with its share of the
  // layer of its own depth, as rigid_follow_draw.glsl draws it.
  float share = leaf ? 1.0 : (sf.displaceRigid != 0u ? rigidShare() : 0.0);
  if (sf.displace != 0u && share > 0.0 && anim.gridX >= 2u && anim.gridY >= 2u) {
    uint layer = min(leaf ? triangleLayer() : rigidLayer(world), anim.layerCount - 1u);
    vec4 clip = f.viewProj * vec4(world, 1.0);
    if (clip.w > 0.0) {
      vec3 ndc = clip.xyz / clip.w;
      vec2 size = vec2(anim.width, anim.height);
      // Where the composite shows the vertex's pixel p: s - d(s) = p (shared/rigid.h RIGID_SHOWN_STEPS).
      vec2 p = (ndc.xy * 0.5 + 0.5) * size;
      vec2 d = displacementAt(layer, p);
      for (uint k = 0u; k < RIGID_SHOWN_STEPS; ++k) d = displacementAt(layer, p + d);
      d *= share;
      vec4 q = anim.invViewProj * vec4(rigidDisplacedNdc(ndc, d, size), 1.0);
      world = q.xyz / q.w;
    }
  }
  gl_Position = sf.lightViewProj * vec4(world, 1.0);
}
