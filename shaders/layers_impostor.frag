#version 460
#extension GL_GOOGLE_include_directive : require
// An impostor's pixel (docs/design.md "Impostors"). Crossed polygons (Lluch et al. section 4 and
// Figure 6): every stored view lies on its plane through the box centre; the viewer's ray meets
// those planes, and their texels are composited "over" in the order the ray meets them, each
// polygon's alpha scaled by how squarely it faces the viewer (impostorCrossWeight) — the paper's
// alpha-blended polygons, ordered per pixel. Facing polygon (before 0.7): the two views nearest
// the viewer's direction, blended by their shares. The depth is the recorded leaf surface where the
// pixel becomes mostly opaque (so leaves and impostors occlude each other in the layer), and the
// result is weighted by the box's share at its level-of-detail transition.
#include "layers_impostor_common.glsl"

layout(location = 0) in vec3 vModel;
layout(location = 1) flat in uvec4 vBoxViews;
layout(location = 2) flat in vec2 vWeights;
layout(location = 3) flat in vec4 vEye;
layout(location = 4) flat in uint vCopy;
layout(location = 0) out vec4 outColor;

// Where the ray p + t * ray meets view k's central plane (t), or a negative t' sentinel when the
// ray runs along the plane (a polygon seen edge-on shows nothing).
bool rayOnView(ImpostorBox b, uint k, vec3 p, vec3 ray, out float t) {
  vec3 n = impostorDirection(k);
  float dn = dot(ray, n);
  t = abs(dn) < 0.05 ? 0.0 : -dot(p - b.center.xyz, n) / dn;
  return abs(dn) >= 0.05;
}

// View k's texel where the ray p + t * ray meets its plane; .a is 0 off the view's image. `leaf`:
// the leaf surface the view recorded there.
vec4 sampleView(ImpostorBox b, uint k, vec3 p, vec3 ray, out vec3 leaf) {
  leaf = p;
  float t;
  if (!rayOnView(b, k, p, ray, t)) return vec4(0.0);
  ImpostorFrame fr = impostorFrameOf(k);
  vec3 c = b.center.xyz;
  vec3 e = impostorExtent(fr, b.halfExtent.xyz, 1e-4 * max(length(b.halfExtent.xyz), 1e-6));
  vec3 q = p + ray * t;
  float x = dot(q - c, fr.u), y = dot(q - c, fr.v);
  vec2 st = vec2(0.5 + 0.5 * x / e.x, 0.5 - 0.5 * y / e.y);
  if (any(lessThan(st, vec2(0.0))) || any(greaterThan(st, vec2(1.0)))) return vec4(0.0);
  uint tile = b.firstTile + k - pc.firstView, perLayer = pc.tilesPerRow * pc.rowsPerLayer, index = tile % perLayer;
  float size = float(pc.tileSize);
  vec2 atlas = vec2(pc.tilesPerRow, pc.rowsPerLayer) * size;
  vec2 texel = vec2(index % pc.tilesPerRow, index / pc.tilesPerRow) * size + clamp(st * size, vec2(0.5), vec2(size - 0.5));
  vec3 at = vec3(texel / atlas, float(tile / perLayer));
  float d = texture(atlasDepth, at).r;
  leaf = c + fr.u * x + fr.v * y + fr.n * (e.z - 2.0 * e.z * d);
  return texture(atlasColor, at);
}

void main() {
  ImpostorBox b = boxes[vBoxViews.x];
  LayerInstance copy = copies[vCopy];
  modelEye = vEye;
  vec3 ray = modelEye.w > 0.0 ? normalize(vModel - modelEye.xyz) : -modelEye.xyz;
  vec4 color = vec4(0.0);
  vec3 leaf = vModel;
  if (pc.shape == IMPOSTOR_SHAPE_CROSSED) {
    // The polygons the ray meets, weighted, then composited front to back (at most 12: insertion).
    vec3 w = towardsViewer(b.center.xyz);
    float ts[IMPOSTOR_VIEWS];
    uint ks[IMPOSTOR_VIEWS];
    uint n = 0u;
    for (uint k = pc.firstView; k < IMPOSTOR_VIEWS; ++k) {
      float t;
      if (impostorCrossWeight(impostorViewScore(k, w)) <= 0.0 || !rayOnView(b, k, vModel, ray, t)) continue;
      uint i = n++;
      for (; i > 0u && ts[i - 1u] > t; --i) {
        ts[i] = ts[i - 1u];
        ks[i] = ks[i - 1u];
      }
      ts[i] = t;
      ks[i] = k;
    }
    bool placed = false;
    float strongest = 0.0;
    for (uint i = 0u; i < n; ++i) {
      vec3 at;
      vec4 ck = sampleView(b, ks[i], vModel, ray, at) * impostorCrossWeight(impostorViewScore(ks[i], w));
      vec4 add = (1.0 - color.a) * ck;
      color += add;
      if (!placed && (color.a >= 0.5 || add.a > strongest)) leaf = at;
      strongest = max(strongest, add.a);
      placed = placed || color.a >= 0.5;
    }
  } else {
    vec3 leaf1, leaf2;
    vec4 c1 = sampleView(b, vBoxViews.y, vModel, ray, leaf1);
    vec4 c2 = sampleView(b, vBoxViews.z, vModel, ray, leaf2);
    color = vWeights.x * c1 + (1.0 - vWeights.x) * c2;
    leaf = vWeights.x * c1.a >= (1.0 - vWeights.x) * c2.a ? leaf1 : leaf2;
  }
  if (color.a < 1.0 / 255.0) discard;
  if (pc.fading != 0u) leaf = b.center.xyz - ray * length(b.halfExtent.xyz);
  vec4 clip = f.viewProj * (copy.model * vec4(leaf, 1.0));
  gl_FragDepth = clamp(clip.z / clip.w, 0.0, 1.0);
  // The copy's tint multiplies the baked colour as it multiplies the leaves' base colour.
  color.rgb *= copy.tint.rgb;
  if (pc.debugLevels != 0u) color.rgb = lodLevelColor(vBoxViews.w) * color.a;
  outColor = color * vWeights.y;
}
