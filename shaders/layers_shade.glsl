// Fragment shading of layers and background: base colour (factor x texture), alpha per glTF
// alphaMode, Habel's leaf shading (shared/leaf_shading.h: specular front, diffuse back, diffuse
// transmission on the unlit side) under a directional light plus ambient; premultiplied output.
#include "layers_common.glsl"

layout(location = 0) in vec3 vNormal;
layout(location = 1) in vec2 vUv;
layout(location = 2) flat in uint vLeaf;
layout(location = 3) in vec3 vWorld;
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
  vec3 v = f.eye.w > 0.0 ? normalize(f.eye.xyz - vWorld) : f.eye.xyz;
  // The normal is the leaf's front (glTF: the side it points to); the viewer sees the front where
  // it faces them, else the back, lit with the flipped normal.
  vec3 n = normalize(vNormal);
  bool front = dot(n, v) >= 0.0;
  if (!front) n = -n;
  vec3 lit = leafShade(base.rgb, n, front, v, f.lightDirection.xyz, f.lightColor.rgb, f.lightDirection.w,
                       f.leafShading.x, f.leafShading.y, pc.specular, pc.transmission.a * f.leafShading.z,
                       pc.transmission.rgb * (pc.transmissionFromBase != 0u ? leafTransmissionTint(base.rgb) : vec3(1.0)));
  outColor = vec4(lit * alpha, alpha);
  return true;
}
