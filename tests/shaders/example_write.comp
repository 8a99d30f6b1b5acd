#version 460
#extension GL_GOOGLE_include_directive : require
#include "shared/example.h"

layout(local_size_x = 64) in;
layout(push_constant, scalar) uniform Push { ExampleWriteParams p; };
layout(binding = 0, scalar) writeonly buffer Values { float values[]; };

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= p.count) return;
  values[i] = float(canopyHash(i + p.seed) & 0xffffu) * (p.scale / 65536.0);
}
