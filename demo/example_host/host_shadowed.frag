#version 460
// The sun's share at this fragment: 3x3 percentage-closer filtering of the host's shadow map (the
// boxes drawn by the host, the vegetation by recordCanopyShadow); ambient where it is hidden.
layout(set = 0, binding = 0) uniform sampler2D shadowMap;  // depth, 0 near the sun
layout(location = 0) in vec3 vColor;
layout(location = 1) in vec4 vLight;
layout(location = 0) out vec4 outColor;

void main() {
  vec3 ndc = vLight.xyz / vLight.w;
  vec2 uv = ndc.xy * 0.5 + 0.5;
  vec2 texel = 1.0 / vec2(textureSize(shadowMap, 0));
  float lit = 0.0;
  for (int y = -1; y <= 1; ++y)
    for (int x = -1; x <= 1; ++x) lit += texture(shadowMap, uv + vec2(x, y) * texel).r + 2e-3 >= ndc.z ? 1.0 : 0.0;
  outColor = vec4(vColor * (0.45 + 0.55 * lit / 9.0), 1.0);
}
