#version 460
#extension GL_GOOGLE_include_directive : require
// Compute path, resolve: the composite kernel's premultiplied colour blended over the host's colour
// ("over" by the blend state), its depth written as is, its motion where the vegetation is frontmost.
#include "shared/composite.h"

layout(binding = 1) uniform sampler2D compColor;
layout(binding = 2) uniform sampler2D compDepth;
layout(binding = 3) uniform sampler2D compMotion;
layout(push_constant, scalar) uniform Push { CompositePush pc; };

layout(location = 0) out vec4 outColor;
layout(location = 1) out vec4 outMotion;

void main() {
  ivec2 ip = ivec2(gl_FragCoord.xy);
  outColor = texelFetch(compColor, ip, 0);
  gl_FragDepth = texelFetch(compDepth, ip, 0).r;
  outMotion = (pc.flags & COMPOSITE_MOTION) != 0u ? texelFetch(compMotion, ip, 0) : vec4(0.0);
}
