// Fragment shading of layers and background: base colour (factor x texture), alpha per glTF
// alphaMode, a directional light plus ambient on two-sided leaves; premultiplied output.
#include "layers_common.glsl"

layout(location = 0) in vec3 vNormal;
layout(location = 1) in vec2 vUv;
layout(location = 2) flat in uint vLeaf;
layout(location = 0) out vec4 outColor;

// False when the fragment is discarded by its material's alpha.
bool shade() {
  vec4 base = pc.baseColor * texture(baseColorTex, vUv);
  float alpha = 1.0;
  if (pc.alphaMode == LAYER_ALPHA_MASK) {
    if (base.a < pc.alphaCutoff) return false;
  } else if (pc.alphaMode == LAYER_ALPHA_BLEND) {
    alpha = base.a;
    if (alpha <= 0.0) return false;  // keeps fully transparent texels out of the depth layer
  }
  vec3 n = normalize(vNormal);
  if (!gl_FrontFacing) n = -n;  // leaves are lit from whichever side faces the viewer
  float ambient = f.lightDirection.w;
  float diffuse = max(dot(n, f.lightDirection.xyz), 0.0);
  vec3 lit = base.rgb * f.lightColor.rgb * (ambient + (1.0 - ambient) * diffuse);
  outColor = vec4(lit * alpha, alpha);
  return true;
}
