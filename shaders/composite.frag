#version 460
#extension GL_GOOGLE_include_directive : require
// Fused inverse warp + compositing (paper 3.2, 3.6; design.md "Compositing"). For every layer, the
// displacement d_i(p) is bilinear between the warp-grid corners; the layer's colour, alpha and
// depth are all read at p - d_i(p) (one warp for all three, so the alpha never sways apart from
// the leaves). Layers are composited in layer order with the rigid background and the host's scene
// inserted by depth: a layer sample behind the nearer of the two is hidden. The loop runs front to
// back (the same sum as far to near, "over" being associative) so it can stop once opaque.
#include "shared/composite.h"
#include "shared/layers.h"

layout(binding = 0) uniform sampler2DArray layerColor;  // premultiplied, linear or nearest sampler
layout(binding = 1) uniform sampler2DArray layerDepth;  // nearest, border = 1 (far)
layout(binding = 2) uniform sampler2D backgroundColor;
layout(binding = 3) uniform sampler2D backgroundDepth;
layout(binding = 4, scalar) readonly buffer DispBuf { vec2 disp[]; };
layout(binding = 5, scalar) readonly buffer PrevBuf { vec2 prevDisp[]; };
layout(binding = 6, scalar) readonly buffer OccBuf { uint occupancy[]; };
layout(binding = 7, scalar) readonly buffer SceneBuf { float sceneDepth[]; };
layout(push_constant, scalar) uniform Push { CompositePush pc; };

layout(location = 0) out vec4 outColor;   // premultiplied, blended over the host's colour
layout(location = 1) out vec4 outMotion;  // (motion * a, 0, a): a = 1 where the vegetation is frontmost

vec2 displacementAt(uint base, GridSample g, bool previous) {
  if (previous)
    return blendCorners(g, prevDisp[base + g.i00], prevDisp[base + g.i10], prevDisp[base + g.i01], prevDisp[base + g.i11]);
  return blendCorners(g, disp[base + g.i00], disp[base + g.i10], disp[base + g.i01], disp[base + g.i11]);
}

void main() {
  vec2 p = gl_FragCoord.xy;
  ivec2 ip = ivec2(p);
  uint pixel = uint(ip.y) * uint(pc.width) + uint(ip.x);
  vec2 size = vec2(pc.width, pc.height);
  float sceneZ = (pc.flags & COMPOSITE_SCENE_DEPTH) != 0u ? sceneDepth[pixel] : 1.0;
  vec4 bg = vec4(0.0);
  float bgZ = 1.0;
  if ((pc.flags & COMPOSITE_BACKGROUND) != 0u) {
    bg = texelFetch(backgroundColor, ip, 0);
    bgZ = bg.a > 0.0 ? texelFetch(backgroundDepth, ip, 0).r : 1.0;
  }
  if (bgZ >= sceneZ) { bg = vec4(0.0); bgZ = 1.0; }  // the host's scene hides the trunk
  float opaqueZ = min(sceneZ, bgZ);                    // what hides a layer sample

  GridSample g = gridSample(pc, p);
  uint corners = pc.gridX * pc.gridY;
  bool bilinear = (pc.flags & COMPOSITE_BILINEAR) != 0u;
  vec4 acc = vec4(0.0);
  float frontZ = 1.0;
  vec2 motion = vec2(0.0);
  bool front = false;
  for (uint i = 0u; i < pc.layerCount; ++i) {
    vec2 d = displacementAt(i * corners, g, false);
    vec2 q = p - d;
    if (any(lessThan(q, vec2(-1.0))) || any(greaterThan(q, size + 1.0))) continue;
    if ((pc.flags & COMPOSITE_SKIP_EMPTY) != 0u) {
      uvec2 tile = uvec2(clamp(q, vec2(0.0), size - 1.0)) / COMPOSITE_TILE;
      if (occupancy[(i * pc.tilesY + tile.y) * pc.tilesX + tile.x] == 0u) continue;
    }
    vec3 uvw = vec3(q / size, float(i));
    vec4 c = texture(layerColor, uvw);
    if (c.a < COMPOSITE_MIN_ALPHA) continue;
    // Depth of the sample: the nearest texel of the footprint (bilinear reads four texels, and a
    // leaf edge must not be hidden because one of them is empty).
    float z;
    if (bilinear) {
      vec4 z4 = textureGather(layerDepth, uvw, 0);
      z = min(min(z4.x, z4.y), min(z4.z, z4.w));
    } else {
      z = texture(layerDepth, uvw).r;
    }
    if (z >= opaqueZ) continue;
    acc = underPremultiplied(acc, c);
    if (!front && c.a >= pc.depthAlpha) {
      front = true;
      frontZ = z;
      if ((pc.flags & COMPOSITE_MOTION_VALID) != 0u) motion = d - displacementAt(i * corners, g, true);
    }
    if ((pc.flags & COMPOSITE_EARLY_EXIT) != 0u && acc.a >= COMPOSITE_OPAQUE) break;
  }
  acc = underPremultiplied(acc, bg);
  outColor = acc;
  // Depth output: the nearest layer where its alpha >= depthAlpha, else the trunk, else the scene.
  gl_FragDepth = min(min(frontZ, bgZ), sceneZ);
  bool vegetationFront = front && frontZ < bgZ;
  outMotion = vegetationFront ? vec4(motion, 0.0, 1.0) : vec4(0.0);
}
