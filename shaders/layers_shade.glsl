// Fragment shading of layers and background: base colour (factor x texture), alpha per glTF
// alphaMode, Habel's leaf shading (shared/leaf_shading.h: specular front, diffuse back, diffuse
// transmission on the unlit side) under a directional light plus ambient; premultiplied output.
#include "layers_common.glsl"

layout(location = 0) in vec3 vNormal;
layout(location = 1) in vec2 vUv;
layout(location = 2) flat in uint vLeaf;
layout(location = 3) in vec3 vWorld;
layout(location = 5) flat in vec3 vTint;  // the instance's tint (CanopyInstance.tint)
layout(location = 0) out vec4 outColor;

// The inputs this pipeline's draws may meet (LAYER_FEATURE_*), specialised per model and settings
// (render/layers.cpp shadingFeatures): lavapipe runs both sides of a branch under a lane mask, so
// an input no draw has would still cost every fragment (docs/lab/performance-notebook.md "Specialised shading").
layout(constant_id = 0) const uint LAYER_FEATURES = LAYER_FEATURE_ALL;
bool mayMeet(uint feature) { return (LAYER_FEATURES & feature) != 0u; }

// Normal mapping without tangents, as the glTF sample viewer does for meshes that have none: dp/du
// solved from the screen-space derivatives of position and UV (independent of the screen's
// handedness, which Vulkan's y-down flips), made orthogonal to n; the bitangent n x t. `m`: the
// map's unit-range vector.
vec3 perturbNormal(vec3 n, vec3 p, vec2 uv, vec3 m, float scale) {
  vec3 dp1 = dFdx(p), dp2 = dFdy(p);
  vec2 duv1 = dFdx(uv), duv2 = dFdy(uv);
  float det = duv1.x * duv2.y - duv2.x * duv1.y;
  if (abs(det) < 1e-20) return n;  // no UV gradient: nothing to map
  vec3 t = (dp1 * duv2.y - dp2 * duv1.y) / det;
  t -= n * dot(n, t);
  if (dot(t, t) < 1e-30) return n;  // no UV gradient: nothing to map
  t = normalize(t);
  vec3 b = cross(n, t);
  return normalize(m.x * scale * t + m.y * scale * b + m.z * n);
}

// False when the fragment is discarded by its material's alpha.
bool shade() {
  vec4 base = pc.baseColor * texture(baseColorTex, vUv) * vec4(vTint, 1.0);
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
  vec3 nGeom = front ? n : -n;
  if (mayMeet(LAYER_FEATURE_NORMAL_MAP) && pc.normalScale != 0.0)
    n = perturbNormal(n, vWorld, vUv, texture(normalTex, vUv).xyz * 2.0 - 1.0, pc.normalScale);
  if (!front) n = -n;
  float t = pc.transmission.a * f.leafShading.z;
  vec3 tc = pc.transmission.rgb;
  if (mayMeet(LAYER_FEATURE_TRANSMISSION_TEXTURE) && (pc.shadingFlags & LAYER_SHADE_TRANSMISSION_TEXTURE) != 0u)
    t *= texture(transmissionTex, vUv).a;
  if (mayMeet(LAYER_FEATURE_TRANSMISSION_COLOR_TEXTURE) && (pc.shadingFlags & LAYER_SHADE_TRANSMISSION_COLOR_TEXTURE) != 0u)
    tc *= texture(transmissionColorTex, vUv).rgb;
  if ((pc.shadingFlags & LAYER_SHADE_TINT_FROM_BASE) != 0u) tc *= leafTransmissionTint(base.rgb);
  // leafShading.w: the translucency model (docs/design.md "Layers: leaf shading").
  float sigma = pc.volume.a > 0.0 ? pc.volume.a : f.leafShading.y;  // the material's gloss, else the frame's
  bool habel = !mayMeet(LAYER_FEATURE_DIFFUSE_BTDF) || (mayMeet(LAYER_FEATURE_HABEL) && f.leafShading.w == LAYER_TRANSLUCENCY_HABEL);
  vec3 lit = habel
                 ? leafShadeHabel(base.rgb, n, nGeom, front, v, f.lightDirection.xyz, f.lightColor.rgb, f.lightDirection.w,
                                  f.leafShading.x, sigma, pc.specular, t, tc, pc.volume.rgb)
                 : leafShade(base.rgb, n, front, v, f.lightDirection.xyz, f.lightColor.rgb, f.lightDirection.w,
                             f.leafShading.x, sigma, pc.specular, t, tc);
  // The impostor debug view: leaves in their box level's colour, darker than impostors.
  if (mayMeet(LAYER_FEATURE_LEVEL_COLORS) && pc.lod.y > 0.0)
    lit = lodLevelColor(uint(pc.lod.y) - 1u) * (0.2 + 0.35 * max(dot(n, f.lightDirection.xyz), 0.0));
  // A box fading towards its impostor (issue 18): its leaves' share of the pixels, premultiplied.
  outColor = vec4(lit * alpha, alpha) * pc.lod.x;
  return true;
}
