#version 460
// The example host's only shader: a unit cube from gl_VertexIndex (36 vertices), placed by the
// push constants' model-view-projection; each face gets a fixed shade.
layout(push_constant) uniform Push {
  mat4 mvp;
  vec4 color;
} pc;
layout(location = 0) out vec3 vColor;

const vec3 kCorners[8] = vec3[](vec3(-1, -1, -1), vec3(1, -1, -1), vec3(1, 1, -1), vec3(-1, 1, -1),
                                vec3(-1, -1, 1), vec3(1, -1, 1), vec3(1, 1, 1), vec3(-1, 1, 1));
const int kFaces[36] = int[](0, 2, 1, 0, 3, 2,  4, 5, 6, 4, 6, 7,  0, 1, 5, 0, 5, 4,
                             3, 6, 2, 3, 7, 6,  0, 4, 7, 0, 7, 3,  1, 2, 6, 1, 6, 5);
const float kShade[6] = float[](0.7, 0.9, 0.5, 1.0, 0.6, 0.8);

void main() {
  gl_Position = pc.mvp * vec4(kCorners[kFaces[gl_VertexIndex]] * 0.5, 1.0);
  vColor = pc.color.rgb * kShade[gl_VertexIndex / 6];
}
