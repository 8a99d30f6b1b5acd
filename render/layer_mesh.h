#pragma once
// The compact mesh of the layered vegetation (docs/design.md "Layers: mesh budget and staging
// ring"): its chunks in host memory (the placement reads them), on the device or streamed through a
// staging ring, the materials' textures, and every draw of it (the layers, the background, the
// impostor bake, the per-vertex baseline).
#include <cstdint>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include <canopy/canopy_params.h>

#include "engine/graphics_pipeline.h"
#include "engine/memory.h"
#include "engine/render_graph.h"
#include "engine/transfer.h"
#include "engine/status.h"
#include "render/impostors.h"
#include "render/leaf_roots.h"
#include "render/material_split.h"
#include "render/layer_instances.h"
#include "render/mesh_chunks.h"
#include "render/model.h"
#include "render/plants.h"
#include "render/species.h"

namespace canopy {
struct Device;

// What the mesh is built from besides the model (the vegetation's description derives from it,
// so these are its fields too).
struct LayerMeshDesc {
  MaterialSplitOptions split;
  LeafRootOptions roots;
  // The leaf-root cache folder: leafRootCachePath(model.path, rootCacheDir) is read and written
  // there. Empty (the default), or a model without a path: no file is touched.
  std::string rootCacheDir;
  uint64_t cacheMaxBytes = 0;  // CanopyDesc.cacheMaxBytes (0: no cap)
  bool writeIds = false;      // also an R32G32_UINT array per layer: (leaf + 1, triangle + 1), 0 = none
  uint32_t maxChunkVertices = kMaxChunkVertices;  // distinct vertices per mesh chunk, 3..65535 (tests cut small chunks)
  // Device memory (issue 16; docs/design.md "Layers: mesh budget and staging ring"): the bytes of
  // buffers and images the vegetation may allocate; 0: no limit (the mesh is resident). When the
  // compact mesh does not fit beside the textures and both layer sets, it stays in host memory and
  // every re-slice streams it through a host-visible ring of about `stagingRingBytes` (one segment
  // per frame in flight), a slice per frame.
  uint64_t deviceMemoryBudget = 0;
  uint64_t stagingRingBytes = 64ull << 20;
  // Keep the model's branch hierarchy with the compact mesh (CompactMesh::bend) for the per-vertex
  // wind baseline; the mesh must then be resident (refused, naming the budget, otherwise).
  bool keepBend = false;
  // The foliage's box hierarchy and its baked views (render/impostors.h; needs a resident mesh).
  ImpostorDesc impostors;
  Progress progress;          // optional: "leaf roots" and "vertices" while creating (big meshes)
};

// The staging ring of a streamed mesh (docs/design.md "Layers: mesh budget and staging ring"):
// LayerMesh's vertices, indexBuffer and leafRoots are host-visible rings of `segments` segments of
// these capacities (elements); frame F writes segment F mod segments, which the embedding contract
// (frames <= F - framesInFlight completed) leaves free.
struct MeshRing {
  uint32_t segments = 0;
  uint64_t vertexCapacity = 0, indexCapacity = 0, rootCapacity = 0;  // per segment
  uint32_t rootAlignment = 1;            // root blocks start at multiples of this many entries
  uint64_t counter = 0;                  // segment choice when no host frame numbers are seen (tools)
  uint64_t bytes = 0;                    // the three rings together
};

struct LayerMesh {
  MaterialSplit split;
  std::vector<ModelMaterial> materials;
  glm::vec3 boundsMin{0}, boundsMax{0};
  Plants plants;  // each leaf's plant and each plant's bounds (eq. 7 per plant)
  // The species laid end to end (render/species.h): each one's materials, leaves and plants as
  // ranges, its bounds and wind response; one entry for a vegetation of one model.
  std::vector<MeshSpecies> species;
  // The compact mesh in host memory (its chunks: `chunks`): the placement reads its decoded
  // positions and leaves (so the CPU places what the GPU draws, and no per-vertex copy of the
  // model is kept), and a streamed mesh's re-slices copy from it into the ring.
  CompactMesh hostMesh;
  uint32_t leafCount = 0;                 // model leaves (LayerLeafRoot.leaf < leafCount)
  // With desc.keepBend: each leaf's root position (xyz), for the per-vertex baseline's wind field
  // (render/per_vertex.cpp uploads it at creation; releaseLeafRootPositions then drops it).
  std::vector<glm::vec4> leafRootPositions;
  // With desc.keepBend: the branch table the per-vertex hierarchy indexes (the species' tables laid
  // end to end, render/species.h mergeBendHierarchies); released with leafRootPositions.
  std::vector<gpu::BendBranch> branches;
  std::vector<uint32_t> gpuToModelTriangle;  // with desc.writeIds only
  bool hasRigid = false;                  // the model has rigid triangles (a background to draw)
  // The wood is never carried into the layers (carriesWood): the composite's Layers debug view shows
  // each layer in false colour and the rigid parts apart in their own (paper Figure 3c), so the
  // context keeps them out while it is on (render/canopy.cpp).
  bool woodApart = false;
  std::vector<MeshChunk> chunks;          // the compact mesh's chunks, one draw each
  Buffer vertices, indexBuffer, leafRoots;
  Buffer bendVertices;                    // hostMesh.bend on the device (desc.keepBend and a hierarchy)
  std::vector<Image> textures;            // per model image (sRGB), plus a white one last
  VkSampler sampler = VK_NULL_HANDLE;
  bool streamed = false;                  // not resident: re-slices stream it through `ring`
  MeshRing ring;
  PreparedList pendingUploads;            // textures and buffers not yet recorded (host devices)
};

// A part of a mesh chunk drawn by one spread slice; a streamed mesh has the chunk's vertices,
// the part's indices and the chunk's roots copied into this frame's ring segment at these element
// offsets (vertexOffset, firstIndex, root-table binding).
struct ChunkPart {
  uint32_t chunk = 0, firstTriangle = 0, triangleCount = 0;
  uint64_t ringVertex = 0, ringIndex = 0, ringRoot = 0;
  float weight = 1.0f;  // LayerDrawPush.lod.x: below 1 for a box fading towards its impostor
  uint32_t level = 0;   // the part's foliage box level (the debug view)
  InstanceRun copies;   // the copies it is drawn for (an impostor cut's copy); count 0: the draw's
};

// What a draw of the mesh binds besides the mesh (meshDraw() of the vegetation, layers.cpp, fills
// it): the placed copies' instance table (the second vertex stream), the frame block
// (layers_common.glsl FrameBuf) unless the options or the per-vertex bindings name another, the
// viewport unless the options keep the caller's, and the settings' leaf optics for materials
// without their own.
struct MeshDraw {
  Device* device = nullptr;
  const LayerMesh* mesh = nullptr;
  VkBuffer instances = VK_NULL_HANDLE;
  // Per species, its copies in the instance table (LayerInstances::speciesCopies): a chunk draws
  // only the runs inside its species'. Null: every chunk draws every run (one species).
  const std::vector<InstanceRun>* speciesCopies = nullptr;
  VkBuffer frame = VK_NULL_HANDLE;
  uint32_t width = 0, height = 0;
  float leafTransmission = 0.0f, leafOpticalDepth = 0.0f;  // LayerSettings'
  bool overrideLeafRoughness = false;                       // LayerSettings': the frame's sigma for every material
};

// How drawMaterials differs from a layer draw (the impostor bake, the debug view).
struct MeshDrawOptions {
  VkBuffer frame = VK_NULL_HANDLE;  // another frame block (layers_common.glsl FrameBuf) at frameOffset; null: the layers'
  VkDeviceSize frameOffset = 0;
  bool keepViewport = false;        // the caller has set viewport and scissor
  bool debugLevels = false;         // colour each part by its level (LayerDrawPush.lod.y)
  // Shading once (docs/design.md "Layers: shading once"): the draws a depth pre-pass can hold
  // (opaque and alpha-masked materials at full weight), the others (blended materials, parts
  // fading towards their impostors), or every draw.
  enum class Subset : uint8_t { All, DepthPrepassed, Rest } subset = Subset::All;
  // The copies drawn (instanced draws, one per chunk and run; render/layer_instances.h); null: the
  // first copy only (the impostor bake, the per-vertex baseline).
  const std::vector<InstanceRun>* runs = nullptr;
  // Bound after layers_common.glsl's six (the shadow caster's: render/shadow.cpp); empty: none.
  std::vector<Binding> extra;
  // The carried rigid chunks (MeshChunk::carried) drawn with the foliage (true: a draw of foliage
  // draws them, one of rigid chunks skips them; carriesWood) or with the rigid chunks (false).
  bool carryWood = false;
};

// Splits the materials, computes (or reads from the cache) the leaf roots, builds the compact mesh
// into *out (with impostors, the box hierarchy and atlas plan into `impostors`) and uploads the
// textures into `mesh`; *rootKey: the leaf roots' cache key (0: no cache). Statistics: `stats`'
// mesh and leaf-root fields.
Status prepareLayerMesh(Device& device, const LayerMeshDesc& desc, const VegetationModel& model, LayerMesh& mesh,
                        Impostors& impostors, LayerStats& stats, CompactMesh* out, uint64_t* rootKey);
// The same for several species (render/species.h): each prepared on its own (its split, its leaf
// roots' cache file), then laid end to end into one mesh; *rootKey: the first species'.
Status prepareLayerMesh(Device& device, const LayerMeshDesc& desc, const std::vector<SpeciesModel>& species, LayerMesh& mesh,
                        Impostors& impostors, LayerStats& stats, CompactMesh* out, uint64_t* rootKey);
// After the layer images exist: sets mesh.streamed when the compact mesh (`meshBytes`) does not
// fit the memory budget beside them (`liveAtStart`: the allocator's bytes before the vegetation) and
// the second layer set still to be made (`nextSetBytes`), refusing what needs it resident; a
// streamed mesh then needs the second set before placeLayerMesh. placeLayerMesh creates and fills
// the resident buffers, or the staging ring (the mesh stays in host memory).
Status chooseLayerMeshResidency(const Device& device, const LayerMeshDesc& desc, LayerMesh& mesh, uint64_t liveAtStart,
                                uint64_t meshBytes, uint64_t nextSetBytes);
Status placeLayerMesh(Device& device, const LayerMeshDesc& desc, LayerMesh& mesh, LayerStats& stats, CompactMesh&& compact,
                      uint64_t liveAtStart);
void destroyLayerMesh(Device& device, LayerMesh& mesh);
// Frees the leaves' root positions once the per-vertex baseline has uploaded them (or when it is
// not created): host memory of 16 bytes a leaf that nothing reads after creation.
void releaseLeafRootPositions(LayerMesh& mesh);

// The pipeline description every draw of the compact mesh starts from (the layers, the background,
// the impostor bake, the per-vertex baseline): shaders/layers_common.glsl's six bindings, the
// LayerDrawPush constants, the LayerVertex attributes, premultiplied "over", layers.frag.
GraphicsPipelineDesc layerMeshPipelineDesc(VkFormat colorFormat, VkFormat depthFormat);

// What the per-vertex baseline binds besides the layers' mesh and textures (render/per_vertex.cpp).
struct PerVertexBindings {
// Bound in the order shaders/per_vertex_common.glsl declares them, after layers_common.glsl's.
  VkBuffer frame = VK_NULL_HANDLE;         // its gpu::LayerFrame (FrameBuf, in place of the layers')
  VkBuffer bendFrame = VK_NULL_HANDLE;     // gpu::BendFrame (BendFrameBuf)
  VkBuffer branches = VK_NULL_HANDLE;      // gpu::BendBranch table (BranchBuf)
  VkBuffer bendVertices = VK_NULL_HANDLE;  // gpu::BendVertex per compact-mesh vertex (BendVertexBuf)
  VkBuffer tips = VK_NULL_HANDLE;          // the motion table (TipBuf)
  VkBuffer trunks = VK_NULL_HANDLE;        // gpu::BendTrunk per species (TrunkBuf)
};
// Draws every chunk of the (resident) mesh, foliage then rigid, for the placed copies in `runs`,
// with `pipe` inside the caller's rendering: the per-vertex baseline's frame.
Status drawWholeMesh(const MeshDraw& draw, VkCommandBuffer cmd, const GraphicsPipeline& pipe,
                     const PerVertexBindings& bindings, const std::vector<InstanceRun>& runs);

// The mesh draw with chunk parts (the layer passes' slices and cut, the impostor bake); a
// GPU-order foliage triangle run cut at chunk borders into parts.
Status drawMeshParts(const MeshDraw& draw, VkCommandBuffer cmd, const GraphicsPipeline& pipe, uint32_t passKind,
                     uint32_t target, const std::vector<ChunkPart>& parts, const MeshDrawOptions& options);
void appendRunParts(const std::vector<MeshChunk>& chunks, uint64_t first, uint64_t count, float weight, uint32_t level,
                    std::vector<ChunkPart>* out, InstanceRun copies = {});

// Draws one material group of the chunk parts (`foliage`: the foliage's parts, else the rigid
// chunks) with `pipe` inside the caller's rendering; `perVertex`/`options` as drawWholeMesh and
// drawMeshParts.
Status drawMaterials(const MeshDraw& draw, VkCommandBuffer cmd, const GraphicsPipeline& pipe, bool foliage,
                     uint32_t passKind, uint32_t target, const std::vector<ChunkPart>* parts,
                     const PerVertexBindings* perVertex = nullptr, const MeshDrawOptions* options = nullptr);

// The compact mesh in a render graph (issue 16's buffers, read-only after their upload): imported in
// its rest states and bound; readsMesh() declares a draw's reads. One place for the layer passes,
// the per-vertex baseline and the impostor bake.
// Whether the rigid parts are drawn into the layers' background at each re-slice (RigidMotion::Still,
// or a streamed mesh, which is not resident to be drawn every frame), or every frame displaced with
// the foliage (render/rigid_follow.h; docs/design.md "Rigid parts in wind").
inline bool drawsBackground(const LayerMesh& mesh, const LayerSettings& s) {
  return mesh.hasRigid && (mesh.streamed || s.rigidMotion == RigidMotion::Still);
}
// Whether the rigid chunks that follow the foliage fully (MeshChunk::carried) are drawn into the
// layers with it, each triangle in the layer of its anchor, rather than every frame: when the rigid
// parts follow the foliage, the leaves are sliced by their roots (a triangle goes to one layer) and
// the layer set has no impostor cut (`cutActive`: its parts are the foliage's). Decided per layer
// set: the set's draws and the frames that show it ask with the set's cut.
inline bool carriesWood(const LayerMesh& mesh, const LayerSettings& s, bool cutActive) {
  return mesh.hasRigid && !mesh.woodApart && !drawsBackground(mesh, s) && s.slice == SliceMode::LeafRoots && !cutActive;
}
// Whether chunk `c` is drawn with the foliage (MeshDrawOptions::carryWood).
inline bool drawnWithFoliage(const MeshChunk& c, bool carryWood) { return c.foliage || (carryWood && c.carried); }

struct MeshResources {
  rg::ResourceId vertices = rg::kInvalidResource, indices = rg::kInvalidResource, roots = rg::kInvalidResource;
};
Status importMesh(const LayerMesh& mesh, rg::RenderGraph& graph, MeshResources* out);
rg::RenderGraph::PassBuilder& readsMesh(rg::RenderGraph::PassBuilder& pass, const MeshResources& mesh);

}  // namespace canopy
