#version 460
#extension GL_GOOGLE_include_directive : require
// The per-vertex baseline's motion table (shared/bend.h): once per frame, for every placed copy
// (CanopyInstance: its model-space wind and wind phase, bendFrameForCopy), the tip bend of every
// branch (the wind field at its base through its level's oscillator) and of every leaf (at its root), at this
// frame's time and, for motion vectors, at the previous frame's. The vertex shader then reads a
// branch's motion for each of its vertices instead of synthesising it again (Habel IV: the
// hierarchy's data in a table every vertex indexes).
#include "shared/bend.h"
#include "shared/layers.h"

layout(local_size_x = 64) in;
layout(binding = 0, scalar) readonly buffer BendFrameBuf { BendFrame bendIn; };
layout(binding = 1, scalar) readonly buffer BranchBuf { BendBranch branches[]; };
layout(binding = 2, scalar) writeonly buffer TipBuf { vec3 tipTable[]; };
layout(binding = 3, scalar) readonly buffer InstanceBuf { LayerInstance instances[]; };
layout(binding = 4, scalar) readonly buffer LeafBuf { vec4 leafRoots[]; };  // each leaf's root (model space)

// Grid-stride over (copy, tip): a table of millions of leaves stays within the dispatch's
// group-count limit.
void main() {
  BendFrame f0 = bendIn;
  uint stride = gl_NumWorkGroups.x * gl_WorkGroupSize.x;
  uint sets = (f0.flags & BEND_FLAG_PREVIOUS) != 0u ? 2u : 1u;
  for (uint k = gl_GlobalInvocationID.x; k < f0.tipCount * f0.copyCount; k += stride) {
    uint copy = k / f0.tipCount, i = k - copy * f0.tipCount;
    LayerInstance inst = instances[copy];
    BendFrame f = bendFrameForCopy(f0, inst.normalColumn0.xyz, inst.normalColumn1.xyz, inst.normalColumn2.xyz, inst.tint.w);
    uint base = copy * sets * f.tipCount;
    bool branch = i < f.branchCount;
    uint level = branch ? branches[i].level : 0u;
    vec3 origin = branch ? branches[i].origin : leafRoots[i - f.branchCount].xyz;
    tipTable[base + i] = branch ? bendBranchTip(f, f.time, level, i, origin) : bendLeafTip(f, f.time, i - f.branchCount, origin);
    if (sets == 2u)
      tipTable[base + f.tipCount + i] = branch ? bendBranchTip(f, f.previousTime, level, i, origin)
                                               : bendLeafTip(f, f.previousTime, i - f.branchCount, origin);
  }
}
