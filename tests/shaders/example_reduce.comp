#version 460
#extension GL_GOOGLE_include_directive : require
#include "shared/example.h"

// One workgroup: each invocation folds a strided subset, then a shared-memory tree combines
// them. Deterministic order, so the result is stable frame to frame.
layout(local_size_x = 256) in;
layout(push_constant, scalar) uniform Push { ExampleReduceParams p; };
layout(binding = 0, r32f) readonly uniform image2D inImage;
layout(binding = 1, scalar) writeonly buffer Result { ExampleResult result; };

shared float sSum[256];
shared float sMin[256];
shared float sMax[256];

void main() {
  uint t = gl_LocalInvocationIndex;
  uint n = p.width * p.height;
  float s = 0.0, mn = 3.4e38, mx = -3.4e38;
  for (uint i = t; i < n; i += 256u) {
    float v = imageLoad(inImage, ivec2(i % p.width, i / p.width)).r;
    s += v;
    mn = min(mn, v);
    mx = max(mx, v);
  }
  sSum[t] = s; sMin[t] = mn; sMax[t] = mx;
  barrier();
  for (uint w = 128u; w > 0u; w >>= 1) {
    if (t < w) {
      sSum[t] += sSum[t + w];
      sMin[t] = min(sMin[t], sMin[t + w]);
      sMax[t] = max(sMax[t], sMax[t + w]);
    }
    barrier();
  }
  if (t == 0u) {
    result.sum = sSum[0];
    result.minValue = sMin[0];
    result.maxValue = sMax[0];
    result.count = n;
  }
}
