#version 460
#extension GL_GOOGLE_include_directive : require
// A host's compute shader reading Canopy's wind (tests/wind_test.cpp): canopyWindAt from the
// public include at each point, written back for the test to compare with sampleCanopyWind and
// the simulation's own field.
#include "canopy/canopy_wind.glsl"

layout(local_size_x = 64) in;
layout(binding = 0) uniform sampler2D windImage;
layout(binding = 1, std430) readonly buffer InfoBuf { CanopyWindInfo info; };
layout(binding = 2, std430) readonly buffer PointBuf { vec4 points[]; };
layout(binding = 3, std430) writeonly buffer OutBuf { vec4 winds[]; };
layout(push_constant) uniform Push { uint count; };

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  winds[i] = vec4(canopyWindAt(windImage, info, points[i].xyz), 0.0);
}
