#version 460
#extension GL_GOOGLE_include_directive : require
// The vegetation's shadow caster (docs/design.md "Shadows"). Each foliage vertex goes into the layer
// of its leaf's root as the layers place it (layerOfDepth on the slice camera's frame block, the
// visible placement's), reads that layer's warp displacement d at its own pixel of the slice
// camera (bilinear between the warp-grid corners, as the composite does), and moves to where the
// screen shows it: the composite shows the layer's content at p + d, so the vertex is unprojected
// from p + d at its own depth. Rigid parts and vertices behind the slice camera stay where they are.
// Then it is drawn from the light.
#define CANOPY_VERTEX
#include "layers_common.glsl"
#include "shared/anim.h"
#include "shared/shadow.h"

layout(binding = 6, scalar) readonly buffer ShadowBuf { ShadowFrame sf; };
layout(binding = 7, scalar) readonly buffer AnimBuf { AnimFrame anim; };
layout(binding = 8, scalar) readonly buffer DispBuf { vec2 disp[]; };

// Layer `layer`'s displacement at `pixel` (layer-image pixels, y down): bilinear between the grid's
// corners, clamped to the grid (a leaf off the slice camera's image takes the edge's).
vec2 displacementAt(uint layer, vec2 pixel) {
  vec2 g = clamp(pixel / anim.cellSize, vec2(0.0), vec2(anim.gridX - 1u, anim.gridY - 1u));
  uvec2 i0 = uvec2(min(floor(g), vec2(anim.gridX - 2u, anim.gridY - 2u)));
  vec2 t = g - vec2(i0);
  uint base = layer * anim.gridX * anim.gridY;
  vec2 d00 = disp[base + i0.y * anim.gridX + i0.x], d10 = disp[base + i0.y * anim.gridX + i0.x + 1u];
  vec2 d01 = disp[base + (i0.y + 1u) * anim.gridX + i0.x], d11 = disp[base + (i0.y + 1u) * anim.gridX + i0.x + 1u];
  return mix(mix(d00, d10, t.x), mix(d01, d11, t.x), t.y);
}

void main() {
  emitVertex();
  vec3 world = vWorld;
  if (sf.displace != 0u && hasLeaf() && anim.gridX >= 2u && anim.gridY >= 2u) {
    uint layer = min(triangleLayer(), anim.layerCount - 1u);
    vec4 clip = f.viewProj * vec4(world, 1.0);
    if (clip.w > 0.0) {
      vec3 ndc = clip.xyz / clip.w;
      vec2 size = vec2(anim.width, anim.height);
      vec2 d = displacementAt(layer, (ndc.xy * 0.5 + 0.5) * size);
      vec4 q = anim.invViewProj * vec4(ndc.xy + 2.0 * d / size, ndc.z, 1.0);
      world = q.xyz / q.w;
    }
  }
  gl_Position = sf.lightViewProj * vec4(world, 1.0);
}
