// Depth-sliced layer rasterization (paper 3.2): the per-rebuild frame block, the per-draw push
// constants, the vertex record, and the rule that puts a leaf into a layer by its root's depth.
// The CPU (placement statistics, tests) and the vertex shaders use the same layerOfDepth().
#ifndef CANOPY_SHARED_LAYERS_H
#define CANOPY_SHARED_LAYERS_H
#include "interop.h"

#define CANOPY_MAX_LAYERS 32
#define LAYER_NO_LEAF 0xffffffffu

// How a draw routes triangles (LayerDrawPush.passKind).
#define LAYER_PASS_LAYERED 0u     // every layer at once: gl_Layer = layer of the leaf root
#define LAYER_PASS_ONE_LAYER 1u   // fallback: only triangles of targetLayer survive (clip distances)
#define LAYER_PASS_BACKGROUND 2u  // rigid parts, no slicing

// How a triangle's layer is decided (LayerFrame.sliceMode).
#define LAYER_SLICE_LEAF_ROOT 0u  // by its leaf's root vertex: leaves are never cut (paper 3.2)
#define LAYER_SLICE_GEOMETRY 1u   // the paper's "simple segmentation": near/far planes on the
                                  // triangle's own depth, so straddling leaves are cut

// Material alpha modes (glTF alphaMode).
#define LAYER_ALPHA_OPAQUE 0u
#define LAYER_ALPHA_MASK 1u
#define LAYER_ALPHA_BLEND 2u

CANOPY_NAMESPACE_BEGIN

struct LayerFrame {
  mat4 viewProj;        // world -> Vulkan clip space (y down, depth 0..1)
  vec4 depthRow;        // view depth of world point p: dot(depthRow, vec4(p, 1)), > 0 in front
  vec4 lightDirection;  // xyz: unit vector towards the light (world); w: ambient term 0..1
  vec4 lightColor;      // rgb; a unused
  uint layerCount;      // 1..CANOPY_MAX_LAYERS
  uint sliceMode;       // LAYER_SLICE_*
  uint pad0;
  uint pad1;
  // Layer i holds depths in (boundaries[i], boundaries[i+1]]; depths outside the range clamp to
  // the first or last layer, so every triangle lands in exactly one layer.
  float boundaries[CANOPY_MAX_LAYERS + 1];
  float pad2[3];
};
CANOPY_SIZE_CHECK(LayerFrame, 64 + 16 * 3 + 16 + 4 * (CANOPY_MAX_LAYERS + 4))

struct LayerDrawPush {
  vec4 baseColor;    // material base colour factor (linear RGBA)
  float alphaCutoff; // LAYER_ALPHA_MASK: fragments with alpha below are discarded
  uint alphaMode;    // LAYER_ALPHA_*
  uint targetLayer;  // LAYER_PASS_ONE_LAYER: the layer this draw renders
  uint passKind;     // LAYER_PASS_*
  uint triangleBase; // index of the draw's first triangle in the mesh (id output only)
  uint pad0;
  uint pad1;
  uint pad2;
};
CANOPY_SIZE_CHECK(LayerDrawPush, 48)

// One vertex of the GPU mesh (vertex attributes, not a buffer block; the C++ side static_asserts
// the offsets the pipeline declares).
struct LayerVertex {
  vec3 position;   // world space
  uint normal;     // unit normal as 4 x snorm8 (xyz, w = 0)
  vec2 uv;         // texcoord 0
  uint leaf;       // index into the leaf-root table, LAYER_NO_LEAF for rigid parts
};
CANOPY_SIZE_CHECK(LayerVertex, 28)

CANOPY_INLINE uint layerOfDepth(LayerFrame f, float depth) {
  uint layer = 0u;
  for (uint i = 1u; i < f.layerCount; ++i)
    if (depth > f.boundaries[i]) layer = i;
  return layer;
}

CANOPY_NAMESPACE_END
#endif
