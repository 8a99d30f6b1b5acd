#version 460
#extension GL_GOOGLE_include_directive : require
// Which COMPOSITE_TILE-sized tiles of each layer hold any foliage (run after a layer rebuild), and,
// in slot layerCount, which tiles the rigid background covers (the compute path's classification).
// A tile counts texels one pixel around it too, so any bilinear footprint whose sample point lies
// in an empty tile reads only empty texels: skipping it changes nothing.
#include "shared/composite.h"

layout(local_size_x = COMPOSITE_OCCUPANCY_GROUP) in;
layout(binding = 0) uniform sampler2DArray layerColor;
layout(binding = 1, scalar) writeonly buffer OccBuf { uint occupancy[]; };
layout(binding = 2) uniform sampler2D backgroundColor;
layout(push_constant, scalar) uniform Push { CompositePush pc; };

void main() {
  uint tiles = pc.tilesX * pc.tilesY;
  uint id = gl_GlobalInvocationID.x;
  uint layer = gl_GlobalInvocationID.y;
  if (id >= tiles || layer > pc.layerCount) return;
  bool background = layer == pc.layerCount;
  if (background && (pc.flags & COMPOSITE_BACKGROUND) == 0u) {
    occupancy[layer * tiles + id] = 0u;
    return;
  }
  ivec2 t0 = ivec2(id % pc.tilesX, id / pc.tilesX) * int(COMPOSITE_TILE);
  ivec2 hi = ivec2(pc.width, pc.height) - 1;
  uint any = 0u;
  for (int y = -1; y <= int(COMPOSITE_TILE) && any == 0u; ++y)
    for (int x = -1; x <= int(COMPOSITE_TILE); ++x) {
      ivec2 q = clamp(t0 + ivec2(x, y), ivec2(0), hi);
      float a = background ? texelFetch(backgroundColor, q, 0).a : texelFetch(layerColor, ivec3(q, layer), 0).a;
      if (a > 0.0 && (background || a >= COMPOSITE_MIN_ALPHA)) { any = 1u; break; }
    }
  occupancy[layer * tiles + id] = any;
}
