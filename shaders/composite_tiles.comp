#version 460
#extension GL_GOOGLE_include_directive : require
// Compute path of the inverse warp + compositing (paper 3.2, 3.6; docs/design.md "Conventions where the paper is silent", compositing,
// docs/performance.md): a workgroup per tilesPerGroup listed screen tiles (composite_classify.comp),
// one pixel of each per invocation. Only the tile's layers are visited, so the skip decision is the workgroup's, not each
// lane's; front to back, a pixel stops once opaque. The displacement (current and previous) comes
// from one hardware-filtered fetch of the displacement image. The same sums as composite.frag:
// results go to Canopy's intermediate image and the resolve pass (composite_resolve.*) blends
// them into the host's targets and writes its depth, on the listed tiles only.
#include "shared/composite.h"

layout(local_size_x = COMPOSITE_TILE, local_size_y = COMPOSITE_TILE) in;
layout(binding = 0) uniform sampler2DArray layerColor;  // premultiplied, linear or nearest sampler
layout(binding = 1) uniform sampler2DArray layerDepth;  // nearest, border = 1 (far)
layout(binding = 2) uniform sampler2D backgroundColor;
layout(binding = 3) uniform sampler2D backgroundDepth;
layout(binding = 4) uniform sampler2D hostDepth;        // the host's depth, read before the resolve writes it
layout(binding = 5) uniform sampler2DArray dispImage;   // (d_i, previous d_i) per corner, linear, clamp to edge
layout(binding = 6, scalar) readonly buffer TileBuf { CompositeTileHeader header; uvec2 tiles[]; };
// Colour (premultiplied), the host's depth to write and motion where frontmost, packed
// (compositePackPixel, shared/composite.h).
layout(binding = 7, rgba32ui) writeonly uniform uimage2D outPixel;
layout(binding = 8, std140) uniform ViewBuf { CompositeView view; };  // reprojection
layout(push_constant, scalar) uniform Push { CompositePush pc; };
// The kernel's variant (COMPOSITE_VARIANT_*, compositeTileVariant): one pipeline per case, so a
// still frame's kernel holds no reprojection code and no kernel holds both depth reads — CPU
// drivers run both sides of every branch, masked (docs/design.md "Layers: reprojection", cost).
layout(constant_id = 0) const uint kVariant = 0u;
const bool reproject = (kVariant & COMPOSITE_VARIANT_REPROJECT) != 0u;
const bool bilinear = (kVariant & COMPOSITE_VARIANT_BILINEAR) != 0u;
#define COMPOSITE_SEARCH_BILINEAR bilinear

#include "composite_search.glsl"

// One listed tile: its pixel at this invocation.
void compositeTile(uvec2 tileEntry, mat4 toCurrent, mat4 toPrevious, mat4 toSlice) {
  uvec2 tile = uvec2(compositeTileX(tileEntry.x), compositeTileY(tileEntry.x));
  uint mask = tileEntry.y;
  ivec2 ip = ivec2(tile * COMPOSITE_TILE + gl_LocalInvocationID.xy);
  if (ip.x >= int(pc.width) || ip.y >= int(pc.height)) return;  // the tile's part outside the image
  vec2 p = vec2(ip) + 0.5;
  vec2 size = vec2(pc.layerWidth, pc.layerHeight), outSize = vec2(pc.width, pc.height);
  vec2 origin = vec2(pc.originX, pc.originY);  // layer pixel = p + origin for the slice camera (guard band)
  float sceneRaw = texelFetch(hostDepth, ip, 0).r;
  float sceneZ = compositeStandardDepth(pc.flags, sceneRaw);
  vec4 bg = vec4(0.0);
  float bgZ = 1.0;
  vec4 rayA = reproject ? compositeRayOrigin(toSlice, p, outSize) : vec4(0.0), rayB = toSlice[2];
  if ((tileEntry.x & COMPOSITE_TILE_BACKGROUND) != 0u) {
    if (reproject) {
      const uint b = 3u * COMPOSITE_VIEW_BACKGROUND;
      vec3 h = compositeHomogeneous(view.homography[b], view.homography[b + 1u], view.homography[b + 2u], p);
      vec2 s = h.xy / h.z;
      // The depth search (composite_search.glsl) from the background plane's point; the depth it
      // found is the one shown.
      float zs;
      bool inside = h.z > 0.0 && compositeDepthSearch(true, 0u, rayA, rayB, vec2(0.0), size, s, zs);
      inside = inside && all(greaterThanEqual(s, vec2(0.0))) && all(lessThan(s, size));
      if (inside) {
        ivec2 is = ivec2(floor(s));
        bg = texelFetch(backgroundColor, is, 0);
        if (bg.a > 0.0) bgZ = compositeClipDepth(compositeClipOf(toCurrent, vec2(is) + 0.5, zs, size));
      }
    } else {
      ivec2 is = ivec2(floor(p + origin));  // origin is fractional under a jitter
      bg = texelFetch(backgroundColor, is, 0);
      bgZ = bg.a > 0.0 ? texelFetch(backgroundDepth, is, 0).r : 1.0;
    }
  }
  if (bgZ >= sceneZ) { bg = vec4(0.0); bgZ = 1.0; }  // the host's scene hides the trunk
  float opaqueZ = min(sceneZ, bgZ);

  vec2 s = p + origin;  // layer i's pixel under p (the slice camera's)
  vec2 uvGrid = gridTexcoord(pc, gridSample(pc, s));
  vec4 acc = vec4(0.0);
  float frontZ = 1.0;
  bool front = false;
  // The frontmost sample's motion inputs, its motion computed once after the loop.
  vec2 frontS = vec2(0.0);
  vec4 frontDisp = vec4(0.0), frontClip = vec4(0.0);
  float frontSlice = 0.0;
  uint layers = mask & compositeLayerBits(pc.layerCount);
  while (layers != 0u) {
    uint i = uint(findLSB(layers));
    layers &= layers - 1u;
    if (reproject) {
      const uint b = 3u * i;
      vec3 h = compositeHomogeneous(view.homography[b], view.homography[b + 1u], view.homography[b + 2u], p);
      if (h.z <= 0.0) continue;
      s = h.xy / h.z;
      uvGrid = gridTexcoord(pc, gridSample(pc, s));
    }
    vec4 dd = textureLod(dispImage, vec3(uvGrid, float(i)), 0.0);
    // The depth search (composite_search.glsl): the layer pixel the ray meets and the depth shown
    // there, or nothing here.
    float z = 1.0;
    if (reproject && !compositeDepthSearch(false, i, rayA, rayB, dd.xy, size, s, z)) continue;
    vec2 q = s - dd.xy;
    if (any(lessThan(q, vec2(-1.0))) || any(greaterThan(q, size + 1.0))) continue;
    if (bilinear) q = compositeSharpPoint(q, pc.sharpness);  // composite.h
    vec3 uvw = vec3(q * layerTexelScale(pc.halfResolution, i) / size, float(i));  // half resolution: the quarter
    vec4 c = textureLod(layerColor, uvw, 0.0);
    if (c.a < COMPOSITE_MIN_ALPHA) continue;
    if (bilinear && c.a < 1.0 - COMPOSITE_EDGE_TOLERANCE) {  // an edge: cut it (composite.h)
      c = compositeSharpenEdge(c, textureGather(layerColor, uvw, 3));
      if (c.a < COMPOSITE_MIN_ALPHA) continue;
    }
    if (!reproject) z = layerDepthAt(i, q);  // the footprint's nearest depth (composite_search.glsl)
    vec4 clip = vec4(0.0);
    float zSlice = z;
    if (reproject) {
      clip = compositeClipOf(toCurrent, s, z, size);
      z = compositeClipDepth(clip);
    }
    if (z >= opaqueZ) continue;
    acc = underPremultiplied(acc, c);
    if (!front && c.a >= pc.depthAlpha) {
      front = true;
      frontZ = z;
      frontS = s;
      frontDisp = dd;
      frontClip = clip;
      frontSlice = zSlice;
    }
    if ((pc.flags & COMPOSITE_EARLY_EXIT) != 0u && acc.a >= COMPOSITE_OPAQUE) break;
  }
  // Where the frontmost texel is shown now minus where it was shown in the previous frame (its
  // displacement then, zw, and the previous camera); zw = xy when that frame is not valid.
  vec2 motion = frontDisp.xy - frontDisp.zw;
  if (reproject && (pc.flags & COMPOSITE_MOTION_VALID) != 0u)
    motion = compositeClipPixel(frontClip, outSize) -
             compositeClipPixel(compositeClipOf(toPrevious, frontS - frontDisp.xy + frontDisp.zw, frontSlice, size), outSize);
  acc = underPremultiplied(acc, bg);
  float vegZ = min(frontZ, bgZ);
  bool vegetationFront = (pc.flags & COMPOSITE_MOTION) != 0u && front && frontZ < bgZ;
  imageStore(outPixel, ip, compositePackPixel(vec4(acc.rgb * pc.exposure, acc.a),
                                              vegZ < sceneZ ? compositeStandardDepth(pc.flags, vegZ) : sceneRaw,
                                              vegetationFront, motion));
}

// A workgroup takes tilesPerGroup consecutive entries of the list: on CPU devices each workgroup
// launch has a fixed cost that one 8x8 tile does not amortise (CompositorDesc.tilesPerGroup).
void main() {
  // The view's matrices read once per invocation, not in the layer loop: lavapipe reloads them lane
  // by lane for every layer visited otherwise (docs/lab/performance-notebook.md, "What a reprojected frame costs").
  mat4 toCurrent = view.sliceToCurrent, toPrevious = view.sliceToPrevious, toSlice = view.currentToSlice;
  uint first = gl_WorkGroupID.x * pc.tilesPerGroup, end = min(first + pc.tilesPerGroup, header.instanceCount);
  for (uint k = first; k < end; ++k) compositeTile(tiles[k], toCurrent, toPrevious, toSlice);
}
