#version 460
#extension GL_GOOGLE_include_directive : require
// The depth pre-pass of shading once (docs/design.md "Layers: shading once"): only the material's
// alpha decides whether the fragment is there (layers_shade.glsl's test, for MASK materials; BLEND
// materials are drawn after, not in this pass); no colour is written.
#include "layers_common.glsl"

// The layer vertex shader's outputs, all declared so the interfaces match (only the UV is read).
layout(location = 0) in vec3 vNormal;
layout(location = 1) in vec2 vUv;
layout(location = 2) flat in uint vLeaf;
layout(location = 3) in vec3 vWorld;
layout(location = 5) flat in vec3 vTint;  // unused: declared so the vertex stage's output is consumed

void main() {
  if (pc.alphaMode == LAYER_ALPHA_MASK && pc.baseColor.a * texture(baseColorTex, vUv).a < pc.alphaCutoff) discard;
}
