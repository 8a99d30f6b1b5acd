#version 460
// canopy-game-host's falling leaves: a small quad facing the camera at each leaf (six corners a
// leaf, from the leaves' buffer that host_leaves.comp moves).
layout(set = 0, binding = 1, std430) readonly buffer Leaves { vec4 leaf[]; };
layout(push_constant, std430) uniform Push {
  mat4 viewProj;
  vec4 right;  // xyz: the camera's right, times half a leaf's size; w: the nearest a leaf is drawn (view depth)
  vec4 up;     // xyz: the camera's up, times half a leaf's size
} pc;
layout(location = 0) out vec3 vColor;

const vec2 kCorner[6] = vec2[](vec2(-1, -1), vec2(1, -1), vec2(1, 1), vec2(-1, -1), vec2(1, 1), vec2(-1, 1));

void main() {
  uint i = uint(gl_VertexIndex) / 6u;
  vec2 c = kCorner[gl_VertexIndex % 6];
  vec4 p = leaf[2u * i];
  // A leaf brushing the lens is not drawn (it would fill the view).
  float near = (pc.viewProj * vec4(p.xyz, 1.0)).w < pc.right.w ? 0.0 : 1.0;
  gl_Position = pc.viewProj * vec4(p.xyz + near * (c.x * pc.right.xyz + c.y * pc.up.xyz), 1.0);
  vColor = mix(vec3(0.75, 0.45, 0.1), vec3(0.9, 0.75, 0.2), fract(p.w * 7.0));
}
