#version 460
#extension GL_EXT_scalar_block_layout : require
// The ground's colour: its albedo lit by the sun where the shadow map (the vegetation's caster,
// drawn by recordCanopyShadow) does not hide it, 3x3 percentage-closer filtered; ambient elsewhere.
layout(binding = 0, scalar) readonly buffer GroundBuf {
  mat4 light;
  vec4 origin;
  vec4 u;
  vec4 v;
  vec4 albedo;
  vec4 lightTexel;
} ground;
layout(binding = 1) uniform sampler2D shadowMap;  // depth, 0 near the light
layout(location = 0) in vec3 vWorld;
layout(location = 0) out vec4 outColor;

void main() {
  vec4 c = ground.light * vec4(vWorld, 1.0);
  vec3 ndc = c.xyz / c.w;
  vec2 uv = ndc.xy * 0.5 + 0.5;
  float lit = 0.0;
  for (int y = -1; y <= 1; ++y)
    for (int x = -1; x <= 1; ++x) lit += texture(shadowMap, uv + vec2(x, y) * ground.lightTexel.w).r + 1e-3 >= ndc.z ? 1.0 : 0.0;
  lit /= 9.0;
  float sun = max(ground.lightTexel.y, 0.0);  // the ground faces up: n . l
  outColor = vec4(ground.albedo.rgb * (ground.albedo.a + (1.0 - ground.albedo.a) * sun * lit), 1.0);
}
