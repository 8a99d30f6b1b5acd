#version 460
#extension GL_GOOGLE_include_directive : require
// Which COMPOSITE_TILE-sized tiles of each layer hold any foliage, cell by cell (a bit per cell,
// COMPOSITE_OCCUPANCY_SPLIT a side; run after a layer rebuild), and,
// in slot layerCount, which tiles the rigid background covers (the compute path's classification).
// With COMPOSITE_OCCUPANCY_UNION the next layer set of a spread re-slice (bindings 3, 4) is read
// and ORed into the occupancy, so it covers every step of the cross-fade (render/layers.cpp).
// A tile counts texels one pixel around it too, so any bilinear footprint whose sample point lies
// in an empty tile reads only empty texels: skipping it changes nothing.
#include "shared/composite.h"

layout(local_size_x = COMPOSITE_OCCUPANCY_GROUP) in;
layout(binding = 0) uniform sampler2DArray layerColor;
layout(binding = 1, scalar) buffer OccBuf { uint occupancy[]; };
layout(binding = 2) uniform sampler2D backgroundColor;
layout(binding = 3) uniform sampler2DArray nextLayerColor;
layout(binding = 4) uniform sampler2D nextBackgroundColor;
layout(push_constant, scalar) uniform Push { CompositePush pc; };

void main() {
  uint tiles = pc.layerTilesX * pc.layerTilesY;  // over the layer images
  uint id = gl_GlobalInvocationID.x;
  uint layer = gl_GlobalInvocationID.y;
  if (id >= tiles || layer > pc.layerCount) return;
  bool background = layer == pc.layerCount;
  bool unite = (pc.flags & COMPOSITE_OCCUPANCY_UNION) != 0u;
  if (unite && occupancy[layer * tiles + id] == COMPOSITE_OCCUPANCY_FULL) return;  // every cell already occupied
  if (background && (pc.flags & COMPOSITE_BACKGROUND) == 0u) {
    occupancy[layer * tiles + id] = 0u;
    return;
  }
  // Tiles outside the layers' footprint (CompositePush.occupancy*) hold nothing.
  uvec2 tile = uvec2(id % pc.layerTilesX, id / pc.layerTilesX);
  if (tile.x < pc.occupancyX0 || tile.y < pc.occupancyY0 || tile.x >= pc.occupancyX1 || tile.y >= pc.occupancyY1) {
    if (!unite) occupancy[layer * tiles + id] = 0u;
    return;
  }
  // Each cell of the tile (COMPOSITE_OCCUPANCY_SPLIT a side, a bit each) with one texel around it,
  // 2x2 texels per gather: a gather at the corner shared by texels (x, y) and (x + 1, y + 1)
  // returns those four (the border sampler reads outside texels as transparent; a clamped read
  // would land on an edge texel of this tile, read anyway). A quarter of the texel reads of one
  // fetch each, which is what this pass costs on CPU devices. The classification asks the cells;
  // the fragment path asks the tile (any bit). A layer at half resolution (shared/layers.h
  // layerTexelScale) holds the tile's pixels in half as many texels per side (a cell then at
  // least one texel); the margin stays one texel of its own (a bilinear footprint's).
  const float scale = background ? 1.0 : layerTexelScale(pc.halfResolution, layer);
  const int extent = int(float(COMPOSITE_TILE) * scale), side = max(extent / int(COMPOSITE_OCCUPANCY_SPLIT), 1);
  ivec2 t0 = ivec2(tile) * extent;
  vec2 size = vec2(pc.layerWidth, pc.layerHeight);
  uint bits = 0u;
  for (uint c = 0u; c < COMPOSITE_OCCUPANCY_SPLIT * COMPOSITE_OCCUPANCY_SPLIT; ++c) {
    ivec2 c0 = t0 + ivec2(int(c % COMPOSITE_OCCUPANCY_SPLIT), int(c / COMPOSITE_OCCUPANCY_SPLIT)) * side;
    bool any = false;
    for (int y = -1; y <= side && !any; y += 2)
      for (int x = -1; x <= side; x += 2) {
        vec2 uv = vec2(c0 + ivec2(x + 1, y + 1)) / size;
        vec4 a = background ? (unite ? textureGather(nextBackgroundColor, uv, 3) : textureGather(backgroundColor, uv, 3))
                            : (unite ? textureGather(nextLayerColor, vec3(uv, float(layer)), 3)
                                     : textureGather(layerColor, vec3(uv, float(layer)), 3));
        float m = max(max(a.x, a.y), max(a.z, a.w));
        if (m > 0.0 && (background || m >= COMPOSITE_MIN_ALPHA)) { any = true; break; }
      }
    if (any) bits |= 1u << c;
  }
  occupancy[layer * tiles + id] = unite ? (occupancy[layer * tiles + id] | bits) : bits;
}
