#version 460
#extension GL_GOOGLE_include_directive : require
// An impostor's pixel: the viewer's ray meets each of the two views' central planes; their texels
// (colour, alpha, depth) are blended by the views' shares, the depth is the leaf surface the nearer
// view recorded (so leaves and impostors occlude each other in the layer), and the result is
// weighted by the box's share at its level-of-detail transition (docs/design.md "Impostors").
#include "layers_impostor_common.glsl"

layout(location = 0) in vec3 vWorld;
layout(location = 1) flat in uvec4 vBoxViews;
layout(location = 2) flat in vec2 vWeights;
layout(location = 0) out vec4 outColor;

// View k's texel on the ray p + t * ray; .a of the colour is 0 off the view's image.
vec4 sampleView(ImpostorBox b, uint k, vec3 p, vec3 ray, out vec3 leaf) {
  ImpostorFrame fr = impostorFrameOf(k);
  vec3 c = b.center.xyz;
  vec3 e = impostorExtent(fr, b.halfExtent.xyz, 1e-4 * max(length(b.halfExtent.xyz), 1e-6));
  leaf = p;
  float dn = dot(ray, fr.n);
  if (abs(dn) < 0.05) return vec4(0.0);
  vec3 q = p + ray * (-dot(p - c, fr.n) / dn);
  float x = dot(q - c, fr.u), y = dot(q - c, fr.v);
  vec2 st = vec2(0.5 + 0.5 * x / e.x, 0.5 - 0.5 * y / e.y);
  if (any(lessThan(st, vec2(0.0))) || any(greaterThan(st, vec2(1.0)))) return vec4(0.0);
  uint tile = b.firstTile + k, perLayer = pc.tilesPerRow * pc.rowsPerLayer, index = tile % perLayer;
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
  vec3 ray = f.eye.w > 0.0 ? normalize(vWorld - f.eye.xyz) : -f.eye.xyz;
  vec3 leaf1, leaf2;
  vec4 c1 = sampleView(b, vBoxViews.y, vWorld, ray, leaf1);
  vec4 c2 = sampleView(b, vBoxViews.z, vWorld, ray, leaf2);
  vec4 color = vWeights.x * c1 + (1.0 - vWeights.x) * c2;
  if (color.a < 1.0 / 255.0) discard;
  vec3 leaf = vWeights.x * c1.a >= (1.0 - vWeights.x) * c2.a ? leaf1 : leaf2;
  if (pc.fading != 0u) leaf = b.center.xyz - ray * length(b.halfExtent.xyz);
  vec4 clip = f.viewProj * vec4(leaf, 1.0);
  gl_FragDepth = clamp(clip.z / clip.w, 0.0, 1.0);
  if (pc.debugLevels != 0u) color.rgb = lodLevelColor(vBoxViews.w) * color.a;
  outColor = color * vWeights.y;
}
