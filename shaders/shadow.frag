#version 460
#extension GL_GOOGLE_include_directive : require
// The shadow caster's fragment (docs/design.md "Shadows"): only the material's alpha decides
// whether the leaf is there (MASK: below the cutoff; BLEND: below one half), so a leaf's shadow has
// its shape; no colour is written.
#include "layers_common.glsl"

// The vertex stage's outputs, all declared so the interfaces match (only the UV is read).
layout(location = 0) in vec3 vNormal;
layout(location = 1) in vec2 vUv;
layout(location = 2) flat in uint vLeaf;
layout(location = 3) in vec3 vWorld;
layout(location = 5) flat in vec3 vTint;

void main() {
  float a = pc.baseColor.a * texture(baseColorTex, vUv).a;
  if ((pc.alphaMode == LAYER_ALPHA_MASK && a < pc.alphaCutoff) || (pc.alphaMode == LAYER_ALPHA_BLEND && a < 0.5)) discard;
}
