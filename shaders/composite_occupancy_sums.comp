#version 460
#extension GL_GOOGLE_include_directive : require
// The occupancy's summed-area table (run after composite_occupancy.comp, whenever it runs): per slot
// (a layer, or layerCount: the background), S[y][x] = occupied cells (COMPOSITE_OCCUPANCY_SPLIT a
// tile's side) in rows < y and columns < x, compositeSumsEntries entries per slot. The
// classification then asks whether any cell of a rectangle holds foliage with four reads, however
// wide the rectangle (a moving camera's depth search widens it; reaches(), composite_classify.comp).
#include "shared/composite.h"

layout(local_size_x = COMPOSITE_SUMS_GROUP) in;
layout(binding = 0, scalar) readonly buffer OccBuf { uint occupancy[]; };
layout(binding = 1, scalar) buffer SumBuf { uint sums[]; };
layout(push_constant, scalar) uniform Push { CompositePush pc; };

// One workgroup per slot: its rows summed (an invocation per row), then its columns; a cell is one
// of an occupancy tile's (COMPOSITE_OCCUPANCY_SPLIT a side).
void main() {
  uint slot = gl_WorkGroupID.y;
  if (slot > pc.layerCount) return;  // uniform over the workgroup
  uint tx = pc.layerTilesX, ty = pc.layerTilesY, cx = COMPOSITE_OCCUPANCY_SPLIT * tx, cy = COMPOSITE_OCCUPANCY_SPLIT * ty, stride = compositeSumsStride(pc);
  uint flags = slot * tx * ty, base = compositeSumsBase(pc, slot);
  const uint S = COMPOSITE_OCCUPANCY_SPLIT;
  for (uint y = gl_LocalInvocationID.x; y <= cy; y += COMPOSITE_SUMS_GROUP) {
    uint run = 0u, at = base + y * stride;
    sums[at] = 0u;
    // Row y - 1 of cells: each tile's entry read once, its S cells of that row from its bits.
    uint shift = y > 0u ? ((y - 1u) % S) * S : 0u, row = y > 0u ? flags + ((y - 1u) / S) * tx : 0u;
    for (uint t = 0u; t < tx; ++t) {
      uint cells = y > 0u ? occupancy[row + t] >> shift : 0u;
      for (uint k = 0u; k < S; ++k) {
        run += (cells >> k) & 1u;
        sums[at + t * S + k + 1u] = run;
      }
    }
  }
  memoryBarrierBuffer();
  barrier();
  for (uint x = gl_LocalInvocationID.x; x <= cx; x += COMPOSITE_SUMS_GROUP) {
    uint run = 0u;
    for (uint y = 1u; y <= cy; ++y) {
      run += sums[base + y * stride + x];
      sums[base + y * stride + x] = run;
    }
  }
}
