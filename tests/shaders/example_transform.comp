#version 460
#extension GL_GOOGLE_include_directive : require
#include "shared/example.h"

layout(local_size_x = 8, local_size_y = 8) in;
layout(push_constant, scalar) uniform Push { ExampleTransformParams p; };
layout(binding = 0, scalar) readonly buffer Values { float values[]; };
layout(binding = 1, r32f) writeonly uniform image2D outImage;

void main() {
  uvec2 q = gl_GlobalInvocationID.xy;
  if (q.x >= p.width || q.y >= p.height) return;
  float v = values[q.y * p.width + q.x];
  imageStore(outImage, ivec2(q), vec4(p.gain * v + p.bias));
}
