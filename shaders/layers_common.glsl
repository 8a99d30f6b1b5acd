// Bindings shared by the layer and background shaders (render/layer_mesh.cpp drawMaterials binds the
// same six push-descriptor bindings for every pipeline, and the vertex and instance streams).
#include "shared/layers.h"

layout(binding = 0, scalar) readonly buffer FrameBuf { LayerFrame f; };
// The draw's chunk of the leaf-root table (bound at the chunk's offset): world position of each
// leaf's root vertex (paper 3.2's per-vertex root index, stored per leaf so the table stays small:
// vertices carry their leaf's chunk-local index) and the leaf's model-wide index.
layout(binding = 1, scalar) readonly buffer RootBuf { LayerLeafRoot leafRoot[]; };
layout(binding = 2) uniform sampler2D baseColorTex;
// Leaf shading's material textures (a white texel where the material has none): the tangent-space
// normal map (linear), the diffuse transmission factor (alpha) and colour (RGB) textures.
layout(binding = 3) uniform sampler2D normalTex;
layout(binding = 4) uniform sampler2D transmissionTex;
layout(binding = 5) uniform sampler2D transmissionColorTex;
layout(push_constant, scalar) uniform Push { LayerDrawPush pc; };

#ifdef CANOPY_VERTEX
#if defined(CANOPY_CLIP_DISTANCES)
// Near/far of the one-layer pass, then the half-resolution quarter (layers_half.glsl).
#define LAYER_HALF_CLIP_FIRST 2
out gl_PerVertex {
  vec4 gl_Position;
  float gl_ClipDistance[4];
};
#elif defined(CANOPY_HALF_RESOLUTION)
#define LAYER_HALF_CLIP_FIRST 0
out gl_PerVertex {
  vec4 gl_Position;
  float gl_ClipDistance[2];
};
#endif
// LayerVertex (shared/layers.h): quantised position and chunk-local leaf, octahedral normal, half UV.
layout(location = 0) in uvec4 inPositionLeaf;
layout(location = 1) in vec2 inNormalOct;
layout(location = 2) in vec2 inUv;
// The vegetation's placed copies (CanopyInstance): the draws are instanced and the instance table is
// their per-instance stream (gpu::LayerInstance's eight vec4 in order), not a storage buffer indexed
// by gl_InstanceIndex (docs/lab/performance-notebook.md "Instances as a vertex stream").
layout(location = LAYER_INSTANCE_LOCATION) in mat4 inInstanceModel;
layout(location = LAYER_INSTANCE_LOCATION + 4) in vec4 inInstanceNormal0;
layout(location = LAYER_INSTANCE_LOCATION + 5) in vec4 inInstanceNormal1;
layout(location = LAYER_INSTANCE_LOCATION + 6) in vec4 inInstanceNormal2;
layout(location = LAYER_INSTANCE_LOCATION + 7) in vec4 inInstanceTint;
layout(location = 0) out vec3 vNormal;
layout(location = 1) out vec2 vUv;
layout(location = 2) flat out uint vLeaf;
layout(location = 3) out vec3 vWorld;
layout(location = 5) flat out vec3 vTint;

float viewDepth(vec3 p) { return dot(f.depthRow, vec4(p, 1.0)); }

// The vertex in the model's coordinates, and placed by this draw instance's transform.
vec3 vertexPosition() { return pc.chunkOrigin.xyz + vec3(inPositionLeaf.xyz) * pc.chunkScale.xyz; }
LayerInstance thisInstance() {
  return LayerInstance(inInstanceModel, inInstanceNormal0, inInstanceNormal1, inInstanceNormal2, inInstanceTint);
}
vec3 placed(vec3 p) { return (inInstanceModel * vec4(p, 1.0)).xyz; }
vec3 worldPosition() { return placed(vertexPosition()); }
bool hasLeaf() { return layerFieldIsLeaf(inPositionLeaf.w); }

// The layer of this vertex's triangle. Every vertex of a leaf reads the same root (a leaf split
// over chunks has the same root in each chunk's table), so a leaf's triangles all agree and no leaf
// is cut (the near/far test is made on the root only).
// Wood carried into the layers (a rigid chunk drawn with the foliage, render/layer_mesh.h
// carriesWood) goes to the layer of its anchor, the one its corners would follow (rigidLayer): the
// anchors of one triangle's corners lie within a slab's thickness of each other, and the provoking
// vertex decides.
uint triangleLayer() {
  uint rigid = layerRigidEntry(inPositionLeaf.w);
  vec3 root = (f.sliceMode == LAYER_SLICE_LEAF_ROOT && hasLeaf()) ? leafRoot[inPositionLeaf.w].position
              : (f.sliceMode == LAYER_SLICE_LEAF_ROOT && rigid != LAYER_CHUNK_NO_LEAF) ? leafRoot[rigid].position
                                                                                        : vertexPosition();
  return layerOfDepth(f, viewDepth(placed(root)));
}

// A rigid vertex (docs/design.md "Rigid parts in wind"): how far it follows the foliage (its share)
// and the layer it follows, that of its anchor's depth (shared/layers.h LAYER_CHUNK_RIGID).
float rigidShare() {
  uint entry = layerRigidEntry(inPositionLeaf.w);
  return entry == LAYER_CHUNK_NO_LEAF ? 1.0 : layerRigidShare(leafRoot[entry].leaf);
}
uint rigidLayer(vec3 world) {
  uint entry = layerRigidEntry(inPositionLeaf.w);
  return layerOfDepth(f, viewDepth(entry == LAYER_CHUNK_NO_LEAF ? world : placed(leafRoot[entry].position)));
}

void emitVertex() {
  LayerInstance inst = thisInstance();
  vWorld = (inst.model * vec4(vertexPosition(), 1.0)).xyz;
  gl_Position = f.viewProj * vec4(vWorld, 1.0);
  vNormal = mat3(inst.normalColumn0.xyz, inst.normalColumn1.xyz, inst.normalColumn2.xyz) * layerDecodeNormal(inNormalOct);
  vUv = inUv;
  vLeaf = hasLeaf() ? leafRoot[inPositionLeaf.w].leaf : LAYER_NO_LEAF;
  vTint = inst.tint.rgb;
}
#ifdef LAYER_HALF_CLIP_FIRST
#include "layers_half.glsl"
#endif
#endif
