#version 460
// canopy-game-host's ground and boxes lit by the sun through its shadow map: host_box.vert's unit
// cube, placed by mvp, and the same corner through the light (lightMvp) for the shadow lookup; the
// colour from the draw's first instance (0 ground, 1 the outlined box, 2 the other boxes).
layout(push_constant) uniform Push {
  mat4 mvp;
  mat4 lightMvp;
} pc;
layout(location = 0) out vec3 vColor;
layout(location = 1) out vec4 vLight;

const vec3 kCorners[8] = vec3[](vec3(-1, -1, -1), vec3(1, -1, -1), vec3(1, 1, -1), vec3(-1, 1, -1),
                                vec3(-1, -1, 1), vec3(1, -1, 1), vec3(1, 1, 1), vec3(-1, 1, 1));
const int kFaces[36] = int[](0, 2, 1, 0, 3, 2,  4, 5, 6, 4, 6, 7,  0, 1, 5, 0, 5, 4,
                             3, 6, 2, 3, 7, 6,  0, 4, 7, 0, 7, 3,  1, 2, 6, 1, 6, 5);
const float kShade[6] = float[](0.7, 0.9, 0.5, 1.0, 0.6, 0.8);
const vec3 kColors[3] = vec3[](vec3(0.35, 0.45, 0.25), vec3(0.8, 0.3, 0.25), vec3(0.6, 0.6, 0.65));

void main() {
  vec4 p = vec4(kCorners[kFaces[gl_VertexIndex]] * 0.5, 1.0);
  gl_Position = pc.mvp * p;
  vLight = pc.lightMvp * p;
  vColor = kColors[min(gl_InstanceIndex, 2)] * kShade[gl_VertexIndex / 6];
}
