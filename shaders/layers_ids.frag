#version 460
#extension GL_GOOGLE_include_directive : require
// Debug/test variant: also writes (leaf + 1, triangle + 1) per pixel so tests can read which leaf
// and which triangle landed in which layer.
#include "layers_shade.glsl"

layout(location = 1) out uvec2 outIds;

void main() {
  if (!shade()) discard;
  outIds = uvec2(vLeaf == LAYER_NO_LEAF ? 0u : vLeaf + 1u, pc.triangleBase + uint(gl_PrimitiveID) + 1u);
}
