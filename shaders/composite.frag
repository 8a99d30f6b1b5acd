#version 460
#extension GL_GOOGLE_include_directive : require
// Fused inverse warp + compositing (paper 3.2, 3.6; docs/design.md "Conventions where the paper is silent", compositing). For every layer, the
// displacement d_i(p) is bilinear between the warp-grid corners; the layer's colour, alpha and
// depth are all read at p - d_i(p) (one warp for all three, so the alpha never sways apart from
// the leaves). Layers are composited in layer order with the rigid background and the host's scene
// inserted by depth: a layer sample behind the nearer of the two is hidden. The loop runs front to
// back (the same sum as far to near, "over" being associative) so it can stop once opaque.
#include "shared/anim.h"
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
// Debug views only (a stand-in buffer otherwise): the dynamics frame and the tiled field.
layout(binding = 8, scalar) readonly buffer AnimBuf { AnimFrame anim; };
layout(binding = 9, scalar) readonly buffer TiledBuf { vec2 tiled[]; };
layout(binding = 10, std140) uniform ViewBuf { CompositeView view; };  // reprojection
layout(push_constant, scalar) uniform Push { CompositePush pc; };

layout(location = 0) out vec4 outColor;   // premultiplied, blended over the host's colour
layout(location = 1) out vec4 outMotion;  // (motion * a, 0, a): a = 1 where the vegetation is frontmost

// Pixel p of the current camera on plane i (a layer, or the background) in the slice camera's
// layer pixels, homogeneous (shared/composite.h, CompositeView).
vec3 planePoint(uint i, vec2 p) {
  uint b = 3u * i;
  return compositeHomogeneous(view.homography[b], view.homography[b + 1u], view.homography[b + 2u], p);
}

#define COMPOSITE_SEARCH_BILINEAR ((pc.flags & COMPOSITE_BILINEAR) != 0u)
#include "composite_search.glsl"

vec2 displacementAt(uint base, GridSample g, bool previous) {
  if (previous)
    return blendCorners(g, prevDisp[base + g.i00], prevDisp[base + g.i10], prevDisp[base + g.i01], prevDisp[base + g.i11]);
  return blendCorners(g, disp[base + g.i00], disp[base + g.i10], disp[base + g.i01], disp[base + g.i11]);
}

// The tiled simulation field where the view ray through pixel p meets the simulation plane
// (docs/design.md: the plane is tiled with the one simulated tile). w = 0 where the ray misses it.
vec4 velocityOnPlane(vec2 p) {
  vec2 ndc = p / vec2(pc.layerWidth, pc.layerHeight) * 2.0 - 1.0;  // p: a layer pixel (the slice camera's)
  vec4 a = anim.invViewProj * vec4(ndc, 0.0, 1.0), b = anim.invViewProj * vec4(ndc, 1.0, 1.0);
  vec3 o = a.xyz / a.w, dir = b.xyz / b.w - o;
  vec3 normal = cross(anim.simRight.xyz, anim.simUp.xyz);
  float den = dot(dir, normal);
  if (abs(den) < 1e-8) return vec4(0.0);
  float t = dot(anim.simOrigin.xyz - o, normal) / den;
  if (t <= 0.0) return vec4(0.0);
  vec3 x = o + t * dir - anim.simOrigin.xyz;
  vec2 s = vec2(dot(x, anim.simRight.xyz), dot(x, anim.simUp.xyz)) / anim.simOrigin.w;  // domain units
  uint n = anim.n;
  vec2 c = fract(s) * float(n) - 0.5;  // cell centres at (i + 0.5) / n, periodic
  ivec2 i0 = ivec2(floor(c));
  vec2 f = c - vec2(i0);
  ivec2 i1 = (i0 + 1 + int(n)) % int(n);
  i0 = (i0 + int(n)) % int(n);
  vec2 v = mix(mix(tiled[i0.y * n + i0.x], tiled[i0.y * n + i1.x], f.x),
               mix(tiled[i1.y * n + i0.x], tiled[i1.y * n + i1.x], f.x), f.y);
  // Tile borders (within ~1.5 px) drawn as thin lines so the tiling shows.
  vec2 edge = min(fract(s), 1.0 - fract(s)) / max(fwidth(s), vec2(1e-6));
  return vec4(v, min(edge.x, edge.y) < 1.5 ? 2.0 : 1.0, 0.0);
}

// The debug views draw layer 0's plane (the dynamics frame is the slice camera's).
vec2 layerPixel0(vec2 p) {
  if ((pc.flags & COMPOSITE_REPROJECT) == 0u) return p + vec2(pc.originX, pc.originY);
  vec3 h = planePoint(0u, p);
  return h.xy / max(h.z, 1e-6);
}

void main() {
  vec2 p = gl_FragCoord.xy;
  ivec2 ip = ivec2(p);
  uint pixel = uint(ip.y) * uint(pc.width) + uint(ip.x);
  vec2 size = vec2(pc.layerWidth, pc.layerHeight), outSize = vec2(pc.width, pc.height);
  vec2 origin = vec2(pc.originX, pc.originY);  // layer pixel = p + origin for the slice camera (guard band)
  float sceneRaw = (pc.flags & COMPOSITE_SCENE_DEPTH) != 0u ? sceneDepth[pixel] : compositeStandardDepth(pc.flags, 1.0);
  float sceneZ = (pc.flags & COMPOSITE_SCENE_DEPTH) != 0u ? compositeStandardDepth(pc.flags, sceneRaw) : 1.0;
  vec4 bg = vec4(0.0);
  float bgZ = 1.0;
  bool reproject = (pc.flags & COMPOSITE_REPROJECT) != 0u;
  // The view's matrices read once, before the layer loop (as composite_tiles.comp; docs/performance.md).
  mat4 toCurrent = view.sliceToCurrent, toPrevious = view.sliceToPrevious, toSlice = view.currentToSlice;
  vec4 rayA = reproject ? compositeRayOrigin(toSlice, p, outSize) : vec4(0.0), rayB = toSlice[2];
  if ((pc.flags & COMPOSITE_BACKGROUND) != 0u) {
    ivec2 is = ivec2(floor(p + origin));  // origin is fractional under a jitter
    bool inside = true;
    float bgSearched = 1.0;  // the depth search's depth (reprojected)
    if (reproject) {
      vec3 h = planePoint(COMPOSITE_VIEW_BACKGROUND, p);
      vec2 s = h.xy / h.z;
      // The depth search (composite_search.glsl) from the background plane's point.
      inside = h.z > 0.0 && compositeDepthSearch(true, 0u, rayA, rayB, vec2(0.0), size, s, bgSearched);
      is = ivec2(floor(s));
      inside = inside && all(greaterThanEqual(s, vec2(0.0))) && all(lessThan(s, size));
    }
    if (inside) {
      bg = texelFetch(backgroundColor, is, 0);
      bgZ = bg.a > 0.0 ? texelFetch(backgroundDepth, is, 0).r : 1.0;
      if (reproject && bg.a > 0.0) bgZ = compositeClipDepth(compositeClipOf(toCurrent, vec2(is) + 0.5, bgSearched, size));
    }
  }
  if (bgZ >= sceneZ) { bg = vec4(0.0); bgZ = 1.0; }  // the host's scene hides the trunk
  float opaqueZ = min(sceneZ, bgZ);                    // what hides a layer sample

  vec2 s = p + origin;  // layer i's pixel under p (the slice camera's)
  GridSample g = gridSample(pc, s);
  uint corners = pc.gridX * pc.gridY;
  bool bilinear = (pc.flags & COMPOSITE_BILINEAR) != 0u;
  vec4 acc = vec4(0.0);
  float frontZ = 1.0;
  vec2 motion = vec2(0.0);
  bool front = false;
  for (uint i = 0u; i < pc.layerCount; ++i) {
    if (reproject) {
      vec3 h = planePoint(i, p);
      if (h.z <= 0.0) continue;
      s = h.xy / h.z;
      g = gridSample(pc, s);
    }
    vec2 d = displacementAt(i * corners, g, false);
    // The depth search (composite_search.glsl): the layer pixel the ray meets, or nothing here.
    float zSearch;
    if (reproject && !compositeDepthSearch(false, i, rayA, rayB, d, size, s, zSearch)) continue;
    vec2 q = s - d;
    if (any(lessThan(q, vec2(-1.0))) || any(greaterThan(q, size + 1.0))) continue;
    if (bilinear) q = compositeSharpPoint(q, pc.sharpness);  // composite.h
    if ((pc.flags & COMPOSITE_SKIP_EMPTY) != 0u) {
      uvec2 tile = uvec2(clamp(q, vec2(0.0), size - 1.0)) / COMPOSITE_TILE;
      if (occupancy[(i * pc.layerTilesY + tile.y) * pc.layerTilesX + tile.x] == 0u) continue;
    }
    vec3 uvw = vec3(q * layerTexelScale(pc.halfResolution, i) / size, float(i));  // half resolution: the quarter
    vec4 c = texture(layerColor, uvw);
    if (c.a < COMPOSITE_MIN_ALPHA) continue;
    if (bilinear && c.a < 1.0 - COMPOSITE_EDGE_TOLERANCE) {  // an edge: cut it (composite.h)
      c = compositeSharpenEdge(c, textureGather(layerColor, uvw, 3));
      if (c.a < COMPOSITE_MIN_ALPHA) continue;
    }
    // Depth of the sample: the nearest texel of the footprint (bilinear reads four texels, and a
    // leaf edge must not be hidden because one of them is empty); reprojected, the depth the search
    // found.
    float z = reproject ? zSearch : layerDepthAt(i, q);
    vec4 clip = vec4(0.0);
    float zSlice = z;
    if (reproject) {
      clip = compositeClipOf(toCurrent, s, z, size);
      z = compositeClipDepth(clip);
    }
    if (z >= opaqueZ) continue;
    if (pc.debugView == COMPOSITE_DEBUG_LAYERS) {
      float shade = 0.55 + 0.45 * dot(c.rgb / c.a, vec3(0.3, 0.59, 0.11));
      c.rgb = debugLayerColor(i) * shade * c.a;
    }
    acc = underPremultiplied(acc, c);
    if (!front && c.a >= pc.depthAlpha) {
      front = true;
      frontZ = z;
      // Where the texel is shown now minus where it was shown in the previous frame (its
      // displacement then and the previous camera).
      if ((pc.flags & COMPOSITE_MOTION_VALID) != 0u) {
        vec2 dPrev = displacementAt(i * corners, g, true);
        motion = reproject ? compositeClipPixel(clip, outSize) -
                                 compositeClipPixel(compositeClipOf(toPrevious, s - d + dPrev, zSlice, size), outSize)
                           : d - dPrev;
      }
    }
    if ((pc.flags & COMPOSITE_EARLY_EXIT) != 0u && acc.a >= COMPOSITE_OPAQUE) break;
  }
  acc = underPremultiplied(acc, bg);
  if (pc.debugView == COMPOSITE_DEBUG_VELOCITY) {
    // Hue = direction, brightness = speed / debugScale, over 40 % of the composite.
    vec4 v = velocityOnPlane(layerPixel0(p));
    if (v.z > 0.0) {
      vec3 col = debugHue(fract(atan(v.y, v.x) / 6.2831853 + 1.0)) * min(length(v.xy) / max(pc.debugScale, 1e-6), 1.0);
      if (v.z > 1.5) col = vec3(1.0);
      acc = vec4(col * 0.6 + acc.rgb * 0.4, 0.6 + acc.a * 0.4);
    }
  } else if (pc.debugView == COMPOSITE_DEBUG_GRID) {
    // p is on a displaced grid line where p - d_0(p) is on an undisplaced one.
    vec2 s0 = layerPixel0(p);
    vec2 q = (s0 - displacementAt(0u, gridSample(pc, s0), false)) / pc.cellSize;
    vec2 dist = min(fract(q), 1.0 - fract(q)) * pc.cellSize;
    if (min(dist.x, dist.y) < 0.75) acc = vec4(1.0, 0.85, 0.1, 1.0);
  }
  outColor = vec4(acc.rgb * pc.exposure, acc.a);
  // Depth output: the nearest layer where its alpha >= depthAlpha, else the trunk, else the scene
  // (the scene's own value, bit for bit, in the host's convention).
  float vegZ = min(frontZ, bgZ);
  gl_FragDepth = vegZ < sceneZ ? compositeStandardDepth(pc.flags, vegZ) : sceneRaw;
  bool vegetationFront = front && frontZ < bgZ;
  outMotion = vegetationFront ? vec4(motion, 0.0, 1.0) : vec4(0.0);
}
