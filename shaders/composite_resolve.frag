#version 460
#extension GL_GOOGLE_include_directive : require
// Compute path, resolve: the composite kernel's premultiplied colour blended over the host's colour
// ("over" by the blend state), its depth written as is, its motion where the vegetation is frontmost.
#include "shared/composite.h"

layout(binding = 1) uniform usampler2D composed;  // compositePackPixel (shared/composite.h)
layout(push_constant, scalar) uniform Push { CompositePush pc; };

layout(location = 0) out vec4 outColor;
layout(location = 1) out vec4 outMotion;

void main() {
  uvec4 px = texelFetch(composed, ivec2(gl_FragCoord.xy), 0);
  outColor = compositeUnpackColor(px);
  gl_FragDepth = compositeUnpackDepth(px);
  outMotion = (pc.flags & COMPOSITE_MOTION) != 0u ? compositeUnpackMotion(px) : vec4(0.0);
}
