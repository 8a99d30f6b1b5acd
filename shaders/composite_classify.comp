#version 460
#extension GL_GOOGLE_include_directive : require
// Compute path, tile classification (docs/performance.md): for every COMPOSITE_TILE screen tile, which
// layers can reach it under q = s - d_i(s), s = H_i p (the reprojection, shared/composite.h; s = p
// for a still camera; the depth search reads within CompositeView.search[i].w of H_i p, with d_i
// taken at H_i p). d_i is bilinear between warp-grid corners, so over the tile it stays within the
// per-axis min/max of the corners of the grid cells the tile's plane rectangle touches; the layer
// reaches the tile when any occupancy cell (foliage, dilated by a pixel) meets the source rectangle
// [tile - dmax - reach, tile - dmin + reach], asked of the occupancy's summed-area table
// (composite_occupancy_sums.comp: four reads whatever its width). Tiles with any layer or the
// background append themselves (position with the background bit, layer mask) to the list that
// sizes the composite's indirect dispatch and the resolve's indirect draw. Without
// COMPOSITE_SKIP_EMPTY every tile lists every layer (the unclassified kernel, kept for tests and
// the benchmark).
#include "shared/composite.h"

layout(local_size_x = COMPOSITE_CLASSIFY_GROUP) in;
// The warp grid's corners as the displacement image holds them (composite_displacement.comp): a
// texel fetch is one vector read on a CPU driver, where a storage buffer is read lane by lane.
layout(binding = 0) uniform sampler2DArray dispImage;
layout(binding = 1, scalar) readonly buffer SumBuf { uint sums[]; };  // the occupancy's summed-area table
layout(binding = 2, scalar) buffer TileBuf { CompositeTileHeader header; uvec2 tiles[]; };
layout(binding = 3, std140) uniform ViewBuf { CompositeView view; };  // reprojection
layout(push_constant, scalar) uniform Push { CompositePush pc; };

// Whether an occupied cell of an occupancy tile of `slot` (a layer, or layerCount: the
// background) meets the layer-pixel rectangle [qlo, qhi] (the composite reads within [-1, size + 1]).
bool reaches(uint slot, vec2 qlo, vec2 qhi, vec2 size) {
  qlo = max(qlo, vec2(-1.0));
  qhi = min(qhi, size + 1.0);
  if (any(greaterThan(qlo, qhi))) return false;
  uvec2 t0 = uvec2(clamp(qlo, vec2(0.0), size - 1.0)) / COMPOSITE_OCCUPANCY_CELL;
  uvec2 t1 = uvec2(clamp(qhi, vec2(0.0), size - 1.0)) / COMPOSITE_OCCUPANCY_CELL + 1u;  // exclusive
  uint base = compositeSumsBase(pc, slot), stride = compositeSumsStride(pc);
  // Unsigned wrap-around cancels: the four-corner sum is the rectangle's count.
  uint n = sums[base + t1.y * stride + t1.x] - sums[base + t0.y * stride + t1.x] - sums[base + t1.y * stride + t0.x] +
           sums[base + t0.y * stride + t0.x];
  return n != 0u;
}

// The layer-pixel bounds of the screen rectangle [lo, hi] through plane `plane`'s homography (the
// image of a convex region in front of the camera is the hull of its corners' images); false where
// a corner is behind either camera.
bool layerBounds(uint plane, vec2 lo, vec2 hi, out vec2 slo, out vec2 shi) {
  slo = vec2(1e30);
  shi = vec2(-1e30);
  uint b = 3u * plane;
  for (uint k = 0u; k < 4u; ++k) {
    vec2 p = vec2((k & 1u) != 0u ? hi.x : lo.x, (k & 2u) != 0u ? hi.y : lo.y);
    vec3 h = compositeHomogeneous(view.homography[b], view.homography[b + 1u], view.homography[b + 2u], p);
    if (h.z <= 0.0) return false;
    slo = min(slo, h.xy / h.z);
    shi = max(shi, h.xy / h.z);
  }
  return true;
}

// Where the depth search of `slot` (a layer, or COMPOSITE_VIEW_BACKGROUND) can read for the screen
// rectangle whose corners' rays (compositeRayOrigin, the same for every layer) are `rays`: the box
// [slo, shi] (the plane's points) grown to hold the ray's points at the search range's two ends at
// the rectangle's corners, and 1/16 pixel for rounding (a range end is projective in the pixel, so
// the ends of the rectangle's pixels lie in the hull of its corners' ends, and the samples and
// meeting points between them); by the view's bound on the whole image
// (CompositeView.search[slot].w) where an end is behind a camera. Nothing where it takes no samples.
void searchBounds(uint slot, vec4 rays[4], inout vec2 slo, inout vec2 shi) {
  vec4 search = view.search[slot];
  if (search.z <= 0.0) return;
  vec2 size = vec2(pc.layerWidth, pc.layerHeight);
  vec4 b = view.currentToSlice[2];
  vec2 nlo = slo, nhi = shi;
  for (uint k = 0u; k < 4u; ++k) {
    vec4 a = rays[k];
    vec2 tn = compositeRayT(a, b, search.x), tf = compositeRayT(a, b, search.y);
    vec4 xn = a + tn.x * b, xf = a + tf.x * b;
    if (tn.y == 0.0 || tf.y == 0.0 || xn.w <= 0.0 || xf.w <= 0.0) {
      slo -= search.w;
      shi += search.w;
      return;
    }
    vec2 pn = (xn.xy / xn.w + 1.0) * 0.5 * size, pf = (xf.xy / xf.w + 1.0) * 0.5 * size;
    nlo = min(nlo, min(pn, pf));
    nhi = max(nhi, max(pn, pf));
  }
  slo = nlo - 0.0625;
  shi = nhi + 0.0625;
}

void main() {
  uint tileCount = pc.tilesX * pc.tilesY;
  uint id = gl_GlobalInvocationID.x;
  if (id >= tileCount) return;
  uvec2 tile = uvec2(id % pc.tilesX, id / pc.tilesX);
  vec2 size = vec2(pc.layerWidth, pc.layerHeight), origin = vec2(pc.originX, pc.originY);
  // Pixel centres of the tile (clipped to the image).
  vec2 lo = vec2(tile * COMPOSITE_TILE) + 0.5;
  vec2 hi = min(lo + float(COMPOSITE_TILE - 1u), vec2(pc.width, pc.height) - 0.5);
  bool reproject = (pc.flags & COMPOSITE_REPROJECT) != 0u;
  uint mask = 0u;
  uint position = compositeTilePosition(tile.x, tile.y);
  vec4 rays[4];
  for (uint k = 0u; k < 4u; ++k)
    rays[k] = reproject ? compositeRayOrigin(view.currentToSlice, vec2((k & 1u) != 0u ? hi.x : lo.x, (k & 2u) != 0u ? hi.y : lo.y),
                                             vec2(pc.width, pc.height))
                        : vec4(0.0);
  if ((pc.flags & COMPOSITE_BACKGROUND) != 0u) {
    // The background is read at the nearest texel of H p, or p + origin (the occupancy tiles are
    // dilated by a pixel).
    vec2 slo = lo + origin, shi = hi + origin;
    bool unbounded = reproject && !layerBounds(COMPOSITE_VIEW_BACKGROUND, lo, hi, slo, shi);
    if (reproject && !unbounded) searchBounds(COMPOSITE_VIEW_BACKGROUND, rays, slo, shi);
    bool reached = unbounded || reaches(pc.layerCount, slo, shi, size);
    if (reached) position |= COMPOSITE_TILE_BACKGROUND;
  }
  if ((pc.flags & COMPOSITE_SKIP_EMPTY) == 0u) {
    mask = compositeLayerBits(pc.layerCount);
  } else {
    for (uint i = 0u; i < pc.layerCount; ++i) {
      // The tile in layer i's pixels (the slice camera's), where its warp grid lies.
      vec2 slo = lo + origin, shi = hi + origin;
      if (reproject && !layerBounds(i, lo, hi, slo, shi)) {
        mask |= 1u << i;
        continue;
      }
      if (shi.x - slo.x > float(COMPOSITE_TILE * COMPOSITE_CLASSIFY_MAX_SPAN) ||
          shi.y - slo.y > float(COMPOSITE_TILE * COMPOSITE_CLASSIFY_MAX_SPAN)) {
        mask |= 1u << i;
        continue;
      }
      // d_i is read at the plane's point (composite_search.glsl): its bounds over the plane's rectangle.
      GridSample g0 = gridSample(pc, slo), g1 = gridSample(pc, shi);
      uint gx0 = uint(g0.cell.x), gy0 = uint(g0.cell.y), gx1 = uint(g1.cell.x) + 1u, gy1 = uint(g1.cell.y) + 1u;
      vec2 dmin = vec2(1e30), dmax = vec2(-1e30);
      for (uint gy = gy0; gy <= gy1; ++gy)
        for (uint gx = gx0; gx <= gx1; ++gx) {
          vec2 d = texelFetch(dispImage, ivec3(gx, gy, i), 0).xy;
          dmin = min(dmin, d);
          dmax = max(dmax, d);
        }
      // Where the depth search reads from the plane's points.
      if (reproject) searchBounds(i, rays, slo, shi);
      // The composite samples layer i at q = s - d in [-1, size + 1] (bilinear reach included by the
      // occupancy's one-pixel dilation).
      if (reaches(i, slo - dmax, shi - dmin, size)) mask |= 1u << i;
    }
  }
  if (mask == 0u && (position & COMPOSITE_TILE_BACKGROUND) == 0u) return;
  uint slot = atomicAdd(header.instanceCount, 1u);
  atomicMax(header.groupsX, slot / pc.tilesPerGroup + 1u);
  tiles[slot] = uvec2(position, mask);
}
