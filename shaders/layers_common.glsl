// Bindings shared by the layer and background shaders (render/layers.cpp declares the same three
// push-descriptor bindings for every pipeline).
#include "shared/layers.h"

layout(binding = 0, scalar) readonly buffer FrameBuf { LayerFrame f; };
// Leaf-root table: world position of each leaf's root vertex (paper 3.2's per-vertex root index,
// stored per leaf so the table stays small: vertices carry their leaf's index).
layout(binding = 1, scalar) readonly buffer RootBuf { vec4 leafRoot[]; };
layout(binding = 2) uniform sampler2D baseColorTex;
layout(push_constant, scalar) uniform Push { LayerDrawPush pc; };

#ifdef CANOPY_VERTEX
#ifdef CANOPY_CLIP_DISTANCES
out gl_PerVertex {
  vec4 gl_Position;
  float gl_ClipDistance[2];
};
#endif
layout(location = 0) in vec3 inPosition;
layout(location = 1) in vec4 inNormal;
layout(location = 2) in vec2 inUv;
layout(location = 3) in uint inLeaf;
layout(location = 0) out vec3 vNormal;
layout(location = 1) out vec2 vUv;
layout(location = 2) flat out uint vLeaf;

float viewDepth(vec3 p) { return dot(f.depthRow, vec4(p, 1.0)); }

// The layer of this vertex's triangle. Every vertex of a leaf reads the same root, so a leaf's
// triangles all agree and no leaf is cut (the near/far test is made on the root only).
uint triangleLayer() {
  vec3 root = (f.sliceMode == LAYER_SLICE_LEAF_ROOT && inLeaf != LAYER_NO_LEAF) ? leafRoot[inLeaf].xyz : inPosition;
  return layerOfDepth(f, viewDepth(root));
}

void emitVertex() {
  gl_Position = f.viewProj * vec4(inPosition, 1.0);
  vNormal = inNormal.xyz;
  vUv = inUv;
  vLeaf = inLeaf;
}
#endif
