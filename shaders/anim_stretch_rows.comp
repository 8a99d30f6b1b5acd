#version 460
#extension GL_GOOGLE_include_directive : require
// The warp's stretch bound, second half (anim_stretch_cols.comp): the column envelopes swept along
// each row, right and back, give the bounded magnitude m; a corner's displacement keeps its
// direction and is shortened to m where it is longer (m <= |d| always: the corner itself is a
// candidate). Each invocation owns one row of one layer.
#include "shared/anim.h"

layout(local_size_x = ANIM_GROUP_SIZE) in;
layout(binding = 0, scalar) readonly buffer FrameBuf { AnimFrame f; };
layout(binding = 1, scalar) readonly buffer RawBuf { vec2 raw[]; };
layout(binding = 2, scalar) buffer EnvelopeBuf { float envelope[]; };
layout(binding = 3, scalar) writeonly buffer DispBuf { vec2 disp[]; };
layout(binding = 4, scalar) readonly buffer BendShareBuf { vec2 bendShare[]; };  // the pushers' share, added unbounded

void main() {
  uint gridX = f.gridX, gridY = f.gridY;
  uint gy = gl_GlobalInvocationID.x, layer = gl_GlobalInvocationID.y;
  if (gy >= gridY || layer >= f.layerCount) return;
  uint base = layer * gridX * gridY + gy * gridX;
  float step = f.maxStretch * f.cellSize;
  if (step <= 0.0) step = 3.0e38;  // 0: unbounded (m = |d|)
  float m = 3.0e38;
  for (uint x = 0u; x < gridX; ++x) {
    m = min(envelope[base + x], m + step);
    envelope[base + x] = m;
  }
  for (uint x = gridX; x > 0u; --x) {
    m = min(envelope[base + x - 1u], m + step);
    disp[base + x - 1u] = stretchBounded(raw[base + x - 1u], m) + bendShare[base + x - 1u];
  }
}
