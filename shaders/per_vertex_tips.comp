#version 460
#extension GL_GOOGLE_include_directive : require
// The per-vertex baseline's motion table (shared/bend.h): once per frame, the tip bend of every
// branch (spectral noise at its level's flexibility and frequency) and of every leaf, at this
// frame's time and, for motion vectors, at the previous frame's. The vertex shader then reads a
// branch's motion for each of its vertices instead of synthesising it again (Habel IV: the
// hierarchy's data in a table every vertex indexes).
#include "shared/bend.h"

layout(local_size_x = 64) in;
layout(binding = 0, scalar) readonly buffer BendFrameBuf { BendFrame bendIn; };
layout(binding = 1, scalar) readonly buffer BranchBuf { BendBranch branches[]; };
layout(binding = 2, scalar) writeonly buffer TipBuf { vec3 tipTable[]; };

// Grid-stride: a table of millions of leaves stays within the dispatch's group-count limit.
void main() {
  BendFrame f = bendIn;
  uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
  for (uint i = gl_GlobalInvocationID.x; i < f.tipCount; i += stride) {
    bool branch = i < f.branchCount;
    uint level = branch ? branches[i].level : 0u;
    tipTable[i] = branch ? bendBranchTip(f, f.time, level, i) : bendLeafTip(f, f.time, i - f.branchCount);
    if ((f.flags & BEND_FLAG_PREVIOUS) != 0u)
      tipTable[f.tipCount + i] = branch ? bendBranchTip(f, f.previousTime, level, i)
                                        : bendLeafTip(f, f.previousTime, i - f.branchCount);
  }
}
