#version 460
#extension GL_GOOGLE_include_directive : require
// The warp's stretch bound, first half (docs/design.md "Layers: the warp's stretch"): the inverse
// warp q = p - d(p) draws a texel 1 / (1 - |grad d|) times its width, so a displacement that
// changes by most of a cell across one cell smears a leaf into a streak. The bounded magnitude is
// the largest L-Lipschitz function under |d| in the grid's L1 metric, min over corners n of
// |d(n)| + L cellSize |c - n|_1, which separates into a pass along each column (this one) and a
// pass along each row (anim_stretch_rows.comp); along a line the minimum is two sweeps, down and
// back (a distance transform), so each invocation owns one column of one layer. L = AnimFrame.maxStretch.
#include "shared/anim.h"

layout(local_size_x = ANIM_GROUP_SIZE) in;
layout(binding = 0, scalar) readonly buffer FrameBuf { AnimFrame f; };
layout(binding = 1, scalar) readonly buffer RawBuf { vec2 raw[]; };  // anim_displace.comp's eq. 6-7
layout(binding = 2, scalar) writeonly buffer EnvelopeBuf { float envelope[]; };

void main() {
  uint gridX = f.gridX, gridY = f.gridY;
  uint gx = gl_GlobalInvocationID.x, layer = gl_GlobalInvocationID.y;
  if (gx >= gridX || layer >= f.layerCount) return;
  uint base = layer * gridX * gridY + gx;
  float step = f.maxStretch * f.cellSize;
  if (step <= 0.0) step = 3.0e38;  // 0: unbounded (m = |d|)
  // Down the column, then back up: m(y) = min(|d(y)|, m(y - 1) + step), then min(m(y), m(y + 1) + step).
  float m = 3.0e38;
  for (uint y = 0u; y < gridY; ++y) {
    m = min(length(raw[base + y * gridX]), m + step);
    envelope[base + y * gridX] = m;
  }
  for (uint y = gridY - 1u; y > 0u; --y) {
    m = min(envelope[base + (y - 1u) * gridX], m + step);
    envelope[base + (y - 1u) * gridX] = m;
  }
}
