#version 460
#extension GL_GOOGLE_include_directive : require
// Compute path, resolve: one quad per listed tile (instance = list entry), so only tiles the
// composite kernel wrote are blended into the host's targets (the host's depth cannot be a
// storage image, so this raster pass writes it; docs/performance.md).
#include "shared/composite.h"

layout(binding = 0, scalar) readonly buffer TileBuf { CompositeTileHeader header; uvec2 tiles[]; };
layout(push_constant, scalar) uniform Push { CompositePush pc; };

void main() {
  uvec2 entry = tiles[gl_InstanceIndex];
  vec2 tile = vec2(float(compositeTileX(entry.x)), float(compositeTileY(entry.x)));
  // Two triangles: corners (0,0) (1,0) (0,1) / (1,0) (1,1) (0,1).
  const vec2 corner[6] = vec2[6](vec2(0, 0), vec2(1, 0), vec2(0, 1), vec2(1, 0), vec2(1, 1), vec2(0, 1));
  vec2 pixel = min((tile + corner[gl_VertexIndex]) * float(COMPOSITE_TILE), vec2(pc.width, pc.height));
  gl_Position = vec4(pixel / vec2(pc.width, pc.height) * 2.0 - 1.0, 0.0, 1.0);
}
