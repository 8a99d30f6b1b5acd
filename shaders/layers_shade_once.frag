#version 460
#extension GL_GOOGLE_include_directive : require
// The shading after the depth pre-pass (docs/design.md "Layers: shading once"): the depth test
// (EQUAL, no write) runs before the shader, so Habel's shading runs only on the fragment that
// stays in front at each texel, not on every leaf behind it (depth complexity ~8).
layout(early_fragment_tests) in;
#include "layers_shade.glsl"

void main() {
  if (!shade()) discard;
}
