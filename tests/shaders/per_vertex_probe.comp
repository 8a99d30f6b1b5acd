#version 460
#extension GL_GOOGLE_include_directive : require
// Test probe of the per-vertex baseline: what the vertex shader computes (shared/bend.h's bendApply
// with the chain walk and the motion table) for a list of rest vertices, written back for the tests.
#define PER_VERTEX_BINDING_BASE 0
#include "per_vertex_common.glsl"

layout(local_size_x = 64) in;
layout(binding = 5, scalar) readonly buffer InBuf { BendProbeVertex probeIn[]; };
layout(binding = 6, scalar) writeonly buffer OutBuf { vec4 probeOut[]; };
layout(push_constant, scalar) uniform Push { uint count; };

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= count) return;
  BendProbeVertex v = probeIn[i];
  BendFrame bf = bendIn;
  BendVertex bv = fetchBendVertex(bf, i);
  // As the vertex shader does: the tips from the motion table the motion kernel wrote.
  vec3 n = v.normal;
  bool leaf = v.leaf != BEND_NO_LEAF;
  BendChain chain = fetchChain(bv.branch);
  probeOut[i] = vec4(bendApply(bf, chain, fetchTips(bf, chain, leaf, v.leaf, 0u, 0u), bv, leaf, v.leafRoot, v.position,
                               bf.time, n), 0.0);
}
