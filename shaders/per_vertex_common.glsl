// The per-vertex wind baseline's inputs (render/per_vertex.cpp binds them after the six layer
// bindings of layers_common.glsl): the bend frame, the branch table, the per-vertex branch index
// and w, the motion table of tip bends and the species' fallback trunks (shared/bend.h); the walk
// from a vertex's branch up to its trunk and the gathering of its tips.
#include "shared/bend.h"

layout(binding = PER_VERTEX_BINDING_BASE, scalar) readonly buffer BendFrameBuf { BendFrame bendIn; };
layout(binding = PER_VERTEX_BINDING_BASE + 1, scalar) readonly buffer BranchBuf { BendBranch branches[]; };
layout(binding = PER_VERTEX_BINDING_BASE + 2, scalar) readonly buffer BendVertexBuf { BendVertex bendVertex[]; };
layout(binding = PER_VERTEX_BINDING_BASE + 3, scalar) readonly buffer TipBuf { vec3 tipTable[]; };
layout(binding = PER_VERTEX_BINDING_BASE + 4, scalar) readonly buffer TrunkBuf { BendTrunk trunks[]; };

// Vertex `index`'s branch and w (BEND_NO_BRANCH without a hierarchy), and the frame it bends in:
// without a branch, its species' trunk in place of the frame's (BendTrunk; w names the species).
BendVertex fetchBendVertex(inout BendFrame f, uint index) {
  BendVertex v = BendVertex(BEND_NO_BRANCH, 0u);
  if ((f.flags & BEND_FLAG_HIERARCHY) != 0u) {
    v.branch = bendVertex[index].branch;
    v.w = bendVertex[index].w;
  }
  if (v.branch == BEND_NO_BRANCH && v.w < f.trunkCount) f = bendFrameForTrunk(f, trunks[v.w]);
  return v;
}

// The chain of `branch`, trunk first (render/per_vertex.cpp's bendChainOf is the CPU twin).
BendChain fetchChain(uint branch) {
  BendChain c;
  c.count = 0u;
  if (branch >= BEND_LEAF_ONLY) return c;
  uint ids[BEND_LEVELS];
  uint n = 0u;
  for (uint b = branch; b != BEND_NO_PARENT && n < BEND_LEVELS; b = branches[b].parent) ids[n++] = b;
  for (uint i = 0u; i < n; ++i) {
    c.id[i] = ids[n - 1u - i];
    c.b[i] = branches[c.id[i]];
  }
  c.count = n;
  return c;
}

// The tips of a vertex's leaf and chain from copy `copy`'s motion table; `set` 0: this frame's, 1:
// the previous frame's (BEND_FLAG_PREVIOUS).
BendTips fetchTips(BendFrame f, BendChain c, bool hasLeaf, uint leaf, uint copy, uint set) {
  uint sets = (f.flags & BEND_FLAG_PREVIOUS) != 0u ? 2u : 1u;
  uint base = (copy * sets + set) * f.tipCount;
  BendTips t;
  t.leaf = hasLeaf ? tipTable[base + f.branchCount + leaf] : vec3(0.0);
  for (uint i = 0u; i < BEND_LEVELS; ++i) t.level[i] = i < c.count ? tipTable[base + c.id[i]] : vec3(0.0);
  return t;
}
