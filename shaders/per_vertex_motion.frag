#version 460
#extension GL_GOOGLE_include_directive : require
// The per-vertex baseline's fragment shader with motion vectors: the layers' shading, and the
// vertex's motion where the vegetation is drawn (the 2D composite's resolve writes its motion so).
#include "layers_shade.glsl"

layout(location = 4) in vec2 vMotion;
layout(location = 1) out vec4 outMotion;

void main() {
  if (!shade()) discard;
  outMotion = vec4(vMotion, 0.0, 1.0);
}
