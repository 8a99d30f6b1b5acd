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
  // The tile and one texel around it, 2x2 texels per gather: gather (i, j) at the corner shared by
  // texels (2i - 1, 2j - 1) and (2i, 2j) of the tile returns those four (the border sampler reads
  // outside texels as transparent; a clamped read would land on an edge texel of this tile, read
  // anyway) — a quarter of the texel reads of one fetch each, which is what this pass costs on CPU
  // devices. Each cell (COMPOSITE_OCCUPANCY_SPLIT a side, a bit each) is occupied when a gather
  // over its texels and one texel around it holds foliage, so a tile reads all its gathers (the
  // tile's flag used to stop at the first holding foliage), but for the shortcut below. The
  // classification asks the cells; the fragment path asks the tile (any bit). A layer at half
  // resolution (shared/layers.h layerTexelScale) holds the tile's pixels in half as many texels per
  // side (a cell then one texel); the margin stays one texel of its own (a bilinear footprint's).
  const float scale = background ? 1.0 : layerTexelScale(pc.halfResolution, layer);
  const int extent = int(float(COMPOSITE_TILE) * scale), side = max(extent / int(COMPOSITE_OCCUPANCY_SPLIT), 1);
  const int n = extent / 2 + 1;  // gathers per side
  ivec2 t0 = ivec2(tile) * extent;
  vec2 size = vec2(pc.layerWidth, pc.layerHeight);
  uint rows[COMPOSITE_TILE / 2u + 1u];  // bit i of rows[j]: gather (i, j) holds foliage
  for (int j = 0; j < n; ++j) rows[j] = 0u;
  // The gathers at odd (i, j) first: every cell's gathers include one of them, so when all hold
  // foliage every cell is occupied and the rest are not read (a tile inside the foliage).
  const int odd = n / 2, oddCount = odd * odd;
  const uint oddRow = 0xAAAAAAAAu & ((1u << uint(n)) - 1u);  // bits of the odd i
  for (int k = 0; k < n * n; ++k) {
    ivec2 g;
    if (k < oddCount) {
      g = ivec2(2 * (k % odd) + 1, 2 * (k / odd) + 1);
    } else {
      int e = k - oddCount;  // the others in row order, skipping the odd pairs
      int row = 0;
      for (row = 0; row < n; ++row) {
        int inRow = (row & 1) == 1 ? n - odd : n;
        if (e < inRow) break;
        e -= inRow;
      }
      g = ivec2((row & 1) == 1 ? 2 * e : e, row);
    }
    vec2 uv = vec2(t0 + 2 * g) / size;
    vec4 a = background ? (unite ? textureGather(nextBackgroundColor, uv, 3) : textureGather(backgroundColor, uv, 3))
                        : (unite ? textureGather(nextLayerColor, vec3(uv, float(layer)), 3)
                                 : textureGather(layerColor, vec3(uv, float(layer)), 3));
    float m = max(max(a.x, a.y), max(a.z, a.w));
    if (m > 0.0 && (background || m >= COMPOSITE_MIN_ALPHA)) rows[g.y] |= 1u << uint(g.x);
    if (k == oddCount - 1) {
      bool full = true;
      for (int j = 1; j < n; j += 2) full = full && (rows[j] & oddRow) == oddRow;
      if (full) break;
    }
  }
  // Cell c spans texels [c side - 1, (c + 1) side] with its margin: gathers c side / 2 to
  // ((c + 1) side + 1) / 2 along each axis.
  uint bits = 0u;
  for (uint cy = 0u; cy < COMPOSITE_OCCUPANCY_SPLIT; ++cy) {
    int y0 = int(cy) * side / 2, y1 = (int(cy + 1u) * side + 1) / 2;
    uint across = 0u;
    for (int j = y0; j <= y1; ++j) across |= rows[j];
    for (uint cx = 0u; cx < COMPOSITE_OCCUPANCY_SPLIT; ++cx) {
      int x0 = int(cx) * side / 2, x1 = (int(cx + 1u) * side + 1) / 2;
      uint span = ((2u << uint(x1)) - 1u) & ~((1u << uint(x0)) - 1u);
      if ((across & span) != 0u) bits |= 1u << (cy * COMPOSITE_OCCUPANCY_SPLIT + cx);
    }
  }
  occupancy[layer * tiles + id] = unite ? (occupancy[layer * tiles + id] | bits) : bits;
}
