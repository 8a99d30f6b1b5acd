// Depth-sliced layer rasterization (paper 3.2): the per-rebuild frame block, the per-draw push
// constants, the vertex record, and the rule that puts a leaf into a layer by its root's depth.
// The CPU (placement statistics, tests) and the vertex shaders use the same layerOfDepth().
#ifndef CANOPY_SHARED_LAYERS_H
#define CANOPY_SHARED_LAYERS_H
#include "interop.h"
#include "leaf_shading.h"

#define CANOPY_MAX_LAYERS 32
// LayerFrame.leafShading.w: the unlit side's model (LayerSettings.translucencyModel).
#define LAYER_TRANSLUCENCY_DIFFUSE 0.0f  // the diffuse BTDF, (1 - a)(-n.l) t c_t
#define LAYER_TRANSLUCENCY_HABEL 1.0f    // Habel's (shared/leaf_shading.h leafTransmittedHabel)
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

// LayerDrawPush.shadingFlags. A texture the material lacks is not sampled (a sample costs more
// than the BRDF on a CPU driver).
#define LAYER_SHADE_TINT_FROM_BASE 1u           // transmission colour x leafTransmissionTint(base colour) (no file value)
#define LAYER_SHADE_TRANSMISSION_TEXTURE 2u     // sample transmissionTex (alpha)
#define LAYER_SHADE_TRANSMISSION_COLOR_TEXTURE 4u  // sample transmissionColorTex (RGB)

// The shading inputs a layer pipeline's fragment shader may meet: its specialization constant 0
// (layers_shade.glsl LAYER_FEATURES; render/layers.cpp shadingFeatures). A clear bit compiles that
// input's code out; unspecialised, a shader may meet all and tests each per draw.
#define LAYER_FEATURE_NORMAL_MAP 1u
#define LAYER_FEATURE_TRANSMISSION_TEXTURE 2u
#define LAYER_FEATURE_TRANSMISSION_COLOR_TEXTURE 4u
#define LAYER_FEATURE_HABEL 8u          // Habel's translucency (LayerFrame.leafShading.w)
#define LAYER_FEATURE_DIFFUSE_BTDF 16u  // the diffuse BTDF
#define LAYER_FEATURE_LEVEL_COLORS 32u  // the impostor debug view's colours by box level (LayerDrawPush.lod.y)
#define LAYER_FEATURE_ALL 0xffffffffu

CANOPY_NAMESPACE_BEGIN

struct LayerFrame {
  mat4 viewProj;        // world -> Vulkan clip space (y down, depth 0..1)
  vec4 depthRow;        // view depth of world point p: dot(depthRow, vec4(p, 1)), > 0 in front
  vec4 lightDirection;  // xyz: unit vector towards the light (world); w: ambient term 0..1
  vec4 lightColor;      // rgb; a unused
  // The viewer, for the view vector of the leaf shading: xyz the camera position (w = 1) or, for an
  // orthographic projection, the unit direction towards the viewer (w = 0).
  vec4 eye;
  // Leaf shading (shared/leaf_shading.h): x the effective refractive index n, y the Beckmann
  // roughness sigma, z 1 with translucency (0: unlit sides get the ambient term only), w the
  // translucency model (LAYER_TRANSLUCENCY_*).
  vec4 leafShading;
  uint layerCount;      // 1..CANOPY_MAX_LAYERS
  uint sliceMode;       // LAYER_SLICE_*
  // Bit i: layer i is drawn at half resolution, into the top-left quarter of its image (layer pixel
  // s at texel s / 2; LayerSettings.halfResolutionLayers, docs/design.md "Layers: half resolution").
  uint halfResolution;
  uint pad1;
  // Layer i holds depths in (boundaries[i], boundaries[i+1]]; depths outside the range clamp to
  // the first or last layer, so every triangle lands in exactly one layer.
  float boundaries[CANOPY_MAX_LAYERS + 1];
  float pad2[3];
};
CANOPY_SIZE_CHECK(LayerFrame, 64 + 16 * 5 + 16 + 4 * (CANOPY_MAX_LAYERS + 4))

struct LayerDrawPush {
  vec4 baseColor;    // material base colour factor (linear RGBA)
  // The draw's mesh chunk (render/mesh_chunks.h): world position = chunkOrigin + q * chunkScale for
  // the vertex's quantised q (0..65535 per axis); w unused.
  vec4 chunkOrigin;
  vec4 chunkScale;
  float alphaCutoff; // LAYER_ALPHA_MASK: fragments with alpha below are discarded
  uint alphaMode;    // LAYER_ALPHA_*
  uint targetLayer;  // LAYER_PASS_ONE_LAYER: the layer this draw renders
  uint passKind;     // LAYER_PASS_*
  uint triangleBase; // index of the draw's first triangle in the mesh (id output only)
  float specular;    // the front side's Cook-Torrance lobe weight: the material's (foliage); 0: none (rigid parts)
  uint shadingFlags;  // LAYER_SHADE_*: which material inputs this draw has
  float normalScale; // the material's normal map scale (glTF normalTexture.scale); 0: no normal map
  // Diffuse transmission (KHR_materials_diffuse_transmission): rgb its colour, a its factor 0..1
  // (0: an opaque leaf; rigid parts).
  vec4 transmission;
  // Levels of detail (issue 18; docs/design.md "Impostors"): x the draw's weight, multiplying its
  // premultiplied output (1: as drawn; below 1: a box fading out towards its impostor); y the debug
  // view: 0 material colours, else the hierarchy level + 1 of the draw's box (colour by level).
  vec4 lod;
  // Habel's translucency: rgb the leaf's optical depth through its thickness (KHR_materials_volume:
  // thicknessFactor x -ln(attenuationColor) / attenuationDistance; else LayerSettings.leafOpticalDepth);
  // a: the lobe's Beckmann sigma from the material's roughness (0: the frame's, leafShading.y).
  vec4 volume;
};
CANOPY_SIZE_CHECK(LayerDrawPush, 128)

// One step of a spread re-slice's cross-fade (docs/design.md "Layers: spread re-slicing"): the
// visible layer's (or background's) colour becomes visible * (1 - weight) + new * weight, with
// weight 1 / (F - k + 1) at step k of F, so after step k the new set's share is exactly k / F; the
// last step (weight 1) is a copy of the new set, depth included.
struct LayerFadePush {
  uint layer;    // array layer of the new set read and of the visible set written (0: background)
  float weight;  // this step's weight of the new set, (0, 1]
  uint pad0;
  uint pad1;
};
CANOPY_SIZE_CHECK(LayerFadePush, 16)

// A chunk-local leaf index that means "no leaf" (rigid parts).
#define LAYER_CHUNK_NO_LEAF 0xffffu
// The chunk-local leaf field of a rigid vertex (docs/design.md "Rigid parts in wind"): this bit and,
// in the 15 bits below it, the vertex's entry in the rigid chunk's root table (LayerLeafRoot): its
// anchor (`position`: where the wood around it is centred, whose depth picks the foliage layer it
// follows, so the front and back of a trunk follow the same one) and its share (`leaf`: 0, the
// trunk's base, still, to LAYER_RIGID_FULL, a branch in the crown, follows in full). A chunk holds
// at most 65535 vertices and a leaf at least one triangle, so leaf indices stay below the bit; a
// rigid chunk holds at most LAYER_RIGID_FULL + 1 vertices. LAYER_CHUNK_NO_LEAF: a rigid vertex
// without an entry (no wind data: the layers' background).
#define LAYER_CHUNK_RIGID 0x8000u
#define LAYER_RIGID_FULL 0x7fffu

// One vertex of the compact GPU mesh (issue 16; vertex attributes, not a buffer block; the C++ side
// static_asserts the offsets the pipeline declares). 16 bytes, against 28 for float positions,
// snorm8 normals, float UVs and a 32-bit leaf index plus a global 16-byte root per leaf.
struct LayerVertex {
  uint positionXY;   // x | y << 16: position quantised to the chunk's bounds (R16G16B16A16_UINT)
  uint positionZLeaf;// z | leaf << 16: leaf = index into the chunk's root table, or LAYER_CHUNK_RIGID | its flexibility
  uint normal;       // octahedral unit normal as 2 x snorm16 (R16G16_SNORM)
  uint uv;           // texcoord 0 as 2 x half (R16G16_SFLOAT)
};
CANOPY_SIZE_CHECK(LayerVertex, 16)

// A chunk's leaf-root table entry (bound per draw at the chunk's offset): the root's world position
// at full precision, so a leaf's layer is decided exactly as the CPU placement decides it, and the
// model-wide leaf index for the id output. The root is the leaf's root vertex, or for a leaf that
// grows from a rigid triangle that triangle's corner it grows nearest (docs/design.md "Rigid parts in
// wind"): the leaf and the branch it hangs on are then in one layer and move as one.
struct LayerLeafRoot {
  vec3 position;
  uint leaf;
};
CANOPY_SIZE_CHECK(LayerLeafRoot, 16)

// One placed copy of the model (CanopyInstance; docs/embedding.md "Several views, several plants, files"): the
// layer draws are instanced, gl_InstanceIndex indexing this table. World position = model * p,
// world normal = normalMatrix * n (the inverse transpose of model's linear part, so a non-uniform
// scale or a mirror keeps normals perpendicular and the leaf's front side where it was).
struct LayerInstance {
  mat4 model;          // model -> world
  vec4 normalColumn0;  // xyz: columns of the normal matrix; w unused
  vec4 normalColumn1;
  vec4 normalColumn2;
  vec4 tint;           // rgb multiplies the base colour (linear); a: the wind phase, s (the per-vertex baseline)
};
CANOPY_SIZE_CHECK(LayerInstance, 128)
// The first of the eight vertex input locations (one per vec4 of LayerInstance, in order) of the
// draws' per-instance stream (render/layer_mesh.cpp layerMeshPipelineDesc).
#define LAYER_INSTANCE_LOCATION 8

// Octahedral unit-vector decoding (Meyer et al. 2010): LayerVertex.normal unpacked to [-1, 1]^2 ->
// unit normal; render/mesh_chunks.cpp encodes, the layer vertex shaders and the tests decode.
CANOPY_INLINE vec3 layerDecodeNormal(vec2 e) {
  vec3 n = vec3(e.x, e.y, 1.0f - abs(e.x) - abs(e.y));
  if (n.z < 0.0f)
    n = vec3((1.0f - abs(e.y)) * (e.x >= 0.0f ? 1.0f : -1.0f), (1.0f - abs(e.x)) * (e.y >= 0.0f ? 1.0f : -1.0f), n.z);
  return normalize(n);
}

// The debug view's colour of hierarchy level `level` (geometry and impostors alike): red, yellow,
// green, cyan, blue for levels 0..4, magenta for 5 and deeper.
CANOPY_INLINE vec3 lodLevelColor(uint level) {
  uint k = min(level, 5u);
  if (k == 0u) return vec3(0.9f, 0.2f, 0.2f);
  if (k == 1u) return vec3(0.95f, 0.75f, 0.1f);
  if (k == 2u) return vec3(0.2f, 0.8f, 0.25f);
  if (k == 3u) return vec3(0.15f, 0.75f, 0.9f);
  if (k == 4u) return vec3(0.3f, 0.35f, 0.95f);
  return vec3(0.85f, 0.3f, 0.9f);
}

// Texels of layer i's image per layer pixel: 1/2 for a layer drawn at half resolution (bit i of
// `halfResolution`, LayerFrame.halfResolution), else 1. Every reader of a layer image samples at
// s x layerTexelScale (the composite's two paths, its occupancy, the CPU reference).
CANOPY_INLINE float layerTexelScale(uint halfResolution, uint layer) {
  return ((halfResolution >> layer) & 1u) != 0u ? 0.5f : 1.0f;
}

// Whether a vertex's chunk-local leaf field names a leaf, and a rigid vertex's flexibility in [0, 1].
CANOPY_INLINE bool layerFieldIsLeaf(uint field) { return field < LAYER_CHUNK_RIGID; }
// A rigid vertex's entry in its chunk's root table, or LAYER_CHUNK_NO_LEAF.
CANOPY_INLINE uint layerRigidEntry(uint field) {
  return field >= LAYER_CHUNK_RIGID && field != LAYER_CHUNK_NO_LEAF ? field & LAYER_RIGID_FULL : LAYER_CHUNK_NO_LEAF;
}
// The share of an entry's `leaf` word, [0, 1].
CANOPY_INLINE float layerRigidShare(uint entryLeaf) { return float(min(entryLeaf, LAYER_RIGID_FULL)) / float(LAYER_RIGID_FULL); }

CANOPY_INLINE uint layerOfDepth(LayerFrame f, float depth) {
  uint layer = 0u;
  for (uint i = 1u; i < f.layerCount; ++i)
    if (depth > f.boundaries[i]) layer = i;
  return layer;
}

CANOPY_NAMESPACE_END
#endif
