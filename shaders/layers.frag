#version 460
#extension GL_GOOGLE_include_directive : require
#include "layers_shade.glsl"

void main() {
  if (!shade()) discard;
}
