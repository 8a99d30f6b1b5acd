// The per-vertex wind baseline (seed 004, Habel IV-VI; docs/design.md "Per-vertex wind baseline"):
// the whole mesh drawn every frame into the host's targets, each vertex bent through its branch
// hierarchy (shared/bend.h), shaded by the layers' fragment shader.
#define CANOPY_VERTEX
#define PER_VERTEX_BINDING_BASE 6
#include "layers_common.glsl"
#include "per_vertex_common.glsl"

#ifdef PER_VERTEX_MOTION
// Screen-space motion in pixels: this frame's position under this frame's camera minus last frame's
// position under last frame's camera (the bend's motion and the camera's; a TAA host needs both).
layout(location = 4) out vec2 vMotion;
#endif

void main() {
  // This copy's frame (its model-space wind, its phase) and placement (CanopyInstance).
  LayerInstance inst = thisInstance();
  BendFrame bf = bendFrameForCopy(bendIn, inst.normalColumn0.xyz, inst.normalColumn1.xyz, inst.normalColumn2.xyz, inst.tint.w);
  uint copy = uint(gl_InstanceIndex);
  vec3 rest = vertexPosition();
  BendVertex bv = fetchBendVertex(bf, uint(gl_VertexIndex));
  BendChain chain = fetchChain(bv.branch);
  bool leaf = hasLeaf();
  // Field by field: a buffer struct and a constructed one are different SPIR-V types.
  LayerLeafRoot lr = LayerLeafRoot(rest, 0u);
  if (leaf) {
    lr.position = leafRoot[inPositionLeaf.w].position;
    lr.leaf = leafRoot[inPositionLeaf.w].leaf;
  }
  vec3 n = layerDecodeNormal(inNormalOct);
  mat3 normalMatrix = mat3(inst.normalColumn0.xyz, inst.normalColumn1.xyz, inst.normalColumn2.xyz);
  vWorld = (inst.model * vec4(bendApply(bf, chain, fetchTips(bf, chain, leaf, lr.leaf, copy, 0u), bv, leaf, lr.position, rest,
                                        bf.time, n), 1.0)).xyz;
  vNormal = normalMatrix * n;
  vUv = inUv;
  vLeaf = leaf ? lr.leaf : LAYER_NO_LEAF;
  vTint = inst.tint.rgb;
  gl_Position = f.viewProj * vec4(vWorld, 1.0);
#ifdef PER_VERTEX_MOTION
  vec3 n0 = n;
  vec3 before = bendApply(bf, chain, fetchTips(bf, chain, leaf, lr.leaf, copy, 1u), bv, leaf, lr.position, rest,
                          bf.previousTime, n0);
  vec4 c0 = bf.previousViewProj * (inst.model * vec4(before, 1.0));
  vMotion = (gl_Position.xy / gl_Position.w - c0.xy / c0.w) * 0.5 * bf.targetSize;
#endif
}
