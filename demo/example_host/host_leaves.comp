#version 460
#extension GL_GOOGLE_include_directive : require
// canopy-game-host's falling leaves: each carried by Canopy's wind where it is (canopyWindAt from
// <canopy/canopy_wind.glsl>, the image recordCanopy left for the host's shaders), drawn toward it
// with a leaf's drag time and falling at a leaf's speed; a leaf on the ground or out of the area
// starts again under the canopy's top.
#include "canopy/canopy_wind.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = 0) uniform sampler2D windImage;
// Two vec4 a leaf: position (w: its phase), velocity (w: 0).
layout(set = 0, binding = 1, std430) buffer Leaves { vec4 leaf[]; };
layout(push_constant, std430) uniform Push {
  CanopyWindInfo wind;
  vec4 area;  // xy: the area's centre (x, z); z: its half width; w: the canopy's top (y)
  vec4 step;  // x: dt (s); y: time (s); z: leaves
} pc;

const float kDragTime = 0.35;  // s: how fast a leaf takes up the wind's speed
const float kFall = 0.6;       // world units/s: a leaf's falling speed in still air

float hash(uint x) {
  x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
  return float(x & 0xffffu) / 65535.0;
}

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= uint(pc.step.z)) return;
  vec3 p = leaf[2u * i].xyz, v = leaf[2u * i + 1u].xyz;
  float phase = leaf[2u * i].w;
  vec3 w = canopyWindAt(windImage, pc.wind, p);
  // Flutter: the fall speed swings with the leaf's own phase.
  vec3 target = w + vec3(0.0, -kFall * (1.0 + 0.5 * sin(6.2831853 * (0.7 * pc.step.y + phase))), 0.0);
  v += (target - v) * (1.0 - exp(-pc.step.x / kDragTime));
  p += v * pc.step.x;
  vec2 off = p.xz - pc.area.xy;
  if (p.y < 0.0 || abs(off.x) > pc.area.z || abs(off.y) > pc.area.z) {
    uint seed = i * 747796405u + uint(pc.step.y * 1000.0) * 2891336453u;
    p = vec3(pc.area.x + (2.0 * hash(seed) - 1.0) * pc.area.z, pc.area.w * (0.6 + 0.4 * hash(seed ^ 0x9e3779b9u)),
             pc.area.y + (2.0 * hash(seed ^ 0x85ebca6bu) - 1.0) * pc.area.z);
    v = canopyWindAt(windImage, pc.wind, p);
  }
  leaf[2u * i] = vec4(p, phase);
  leaf[2u * i + 1u] = vec4(v, 0.0);
}
