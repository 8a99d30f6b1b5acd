// The per-vertex wind baseline's inputs (render/per_vertex.cpp binds them after the six layer
// bindings of layers_common.glsl): the bend frame, the branch table and the per-vertex branch
// index and w (shared/bend.h), and the walk from a vertex's branch up to its trunk.
#include "shared/bend.h"

layout(binding = PER_VERTEX_BINDING_BASE, scalar) readonly buffer BendFrameBuf { BendFrame bendIn; };
layout(binding = PER_VERTEX_BINDING_BASE + 1, scalar) readonly buffer BranchBuf { BendBranch branches[]; };
layout(binding = PER_VERTEX_BINDING_BASE + 2, scalar) readonly buffer BendVertexBuf { BendVertex bendVertex[]; };

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
