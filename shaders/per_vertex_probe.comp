#version 460
#extension GL_GOOGLE_include_directive : require
// Test probe of the per-vertex baseline: bendPosition (shared/bend.h) for a list of rest vertices,
// with the vertex shader's chain walk, written back for the tests to read.
#define PER_VERTEX_BINDING_BASE 0
#include "per_vertex_common.glsl"

layout(local_size_x = 64) in;
layout(binding = 3, scalar) readonly buffer InBuf { BendProbeVertex probeIn[]; };
layout(binding = 4, scalar) writeonly buffer OutBuf { vec4 probeOut[]; };
layout(push_constant, scalar) uniform Push { uint count; };

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  BendProbeVertex v = probeIn[i];
  BendFrame bf = bendIn;
  BendVertex bv = BendVertex(BEND_NO_BRANCH, 0u);
  if ((bf.flags & BEND_FLAG_HIERARCHY) != 0u) {
    bv.branch = bendVertex[i].branch;
    bv.w = bendVertex[i].w;
  }
  vec3 n = v.normal;
  probeOut[i] = vec4(bendPosition(bf, fetchChain(bv.branch), bv, v.leaf != BEND_NO_LEAF, v.leafRoot, v.leaf,
                                  v.position, bf.time, n), 0.0);
}
