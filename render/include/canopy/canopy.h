#pragma once
// Canopy: real-time animation of dense vegetation in wind with view-dependent 2D layers
// (docs/design.md). This header and the three it brings in (<canopy/canopy_core.h>,
// <canopy/canopy_params.h> and its <canopy/canopy_schema.h>) are the API a host calls: the entry
// points here, the plain types there. Two more public files are opt-in: <canopy/canopy_graph.h>
// (Canopy as one pass of the host's render graph) and <canopy/canopy_wind.glsl> (the wind for the
// host's own shaders). C++17, no header of Canopy's source tree, no third-party header but Vulkan's.
//
// A host
//   1. asks queryDeviceRequirements() what its VkDevice needs, enables it (enableDeviceFeatures()),
//   2. hands its instance, device and queue to adoptDevice() (one canopy::Device per VkDevice),
//   3. loads or builds a Model and creates one CanopyContext per plant or field (createCanopy),
//   4. every frame calls recordCanopy() into its own command buffer with its colour and depth.
// Errors are returned as a CanopyStatus (a Result code plus a message naming the parameter, file or
// Vulkan call); nothing throws across this API and nothing is global. Threading: the functions on
// one Device and its contexts must not run concurrently (the host serialises them); different
// Devices are independent.
#include <cstdint>
#include <functional>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

// The version, Result and CanopyStatus, Float3 / Float4x4 / CanopyCamera, and the host's device.
#include <canopy/canopy_core.h>
// The plain types: the model's input descriptions, every parameter struct, CanopyDesc, the statistics.
#include <canopy/canopy_params.h>

namespace canopy {

// ---------------------------------------------------------------------------------------------
// Vegetation input (the descriptions: <canopy/canopy_params.h>)

struct Model;  // one vegetation model in host memory (opaque); may be destroyed after createCanopy

// Loads a .gltf or .glb (decided by the file's first bytes). Refusals name the file and element.
CanopyStatus loadModel(const std::string& path, const GltfLoadOptions& options, Model** out);

// Builds a model from the host's own arrays (MeshDesc; copied).
CanopyStatus createModel(const MeshDesc& desc, Model** out);
// Frees the model's host memory (null is ignored).
void destroyModel(Model* model);
// Triangles of the model (0 for null).
uint64_t modelTriangleCount(const Model* model);
// Axis-aligned bounds of the model, world units.
void modelBounds(const Model* model, Float3* min, Float3* max);

// Reads a scene file (JSON; docs/scene-files.md): species, explicit copies and seeded scatters
// (expanded here, the same copies on every machine). Every key, type, range and cap is checked and
// a refusal names the file and the JSON pointer ("/instances/3/scale: ..."); a species' glTF path
// must name a regular file (it is loaded by loadModel, not here). Never throws.
CanopyStatus readCanopyScene(const std::string& path, CanopyScene* out);
// Parses a scene file's text with readCanopyScene's checks but one: the species' glTF paths are
// resolved against `folder` (relative ones) and not checked to name a regular file (nothing is
// opened; loadModel reports a missing one when the host loads the species). `name` is used in
// messages. For the fuzz target and a host's embedded scenes.
CanopyStatus parseCanopyScene(const std::string& name, const std::string& text, const std::string& folder, CanopyScene* out);
// The scene's copies for createCanopy with the species' models loaded (`models[i]` for
// scene.species[i], in the CanopySpecies list given to createCanopy in the same order): each copy's
// species index set and its species' anchor applied.
CanopyStatus canopySceneInstances(const CanopyScene& scene, const std::vector<const Model*>& models, std::vector<CanopyInstance>* out);

// ---------------------------------------------------------------------------------------------
// Contexts

// The user's cache folder for Canopy: $XDG_CACHE_HOME/canopy (when that is an absolute path),
// else $HOME/.cache/canopy, created with mode 0700 when missing. An error when neither variable
// is an absolute path, or the folder is a link or another user's.
CanopyStatus userCacheFolder(std::string* folder);
// Removes Canopy's cache files from `folder` (leaf roots, impostor views, temporaries of
// interrupted writes; a link or FIFO planted at such a name, never what a link points to). Other
// files stay. The counts are optional.
CanopyStatus clearCacheFolder(const std::string& folder, uint64_t* removedFiles, uint64_t* removedBytes);

// Creates a context: splits materials, finds leaf roots, creates the GPU state and stages the mesh
// and textures. Submits nothing: the uploads are recorded at the start of the context's first
// recordCanopy(). Refuses models with nothing to animate.
CanopyStatus createCanopy(Device* device, const Model* model, const CanopyDesc& desc, CanopyContext** out);

// One species of a vegetation of several (docs/design.md "Species"): its model (may be destroyed
// after createCanopy) and its wind response, relative to the method's.
struct CanopySpecies {
  const Model* model = nullptr;
  float flexibility = 1.0f;    // [0, 4]: scales how far its plants bend for the same wind (eq. 6)
  float responseSpeed = 1.0f;  // [0.25, 4]: divides its layers' delay behind the nearest (eq. 4)
};
// A context animating copies of several species in one set of layers, one simulation and one
// composite (CanopyInstance.species picks each copy's): each species' mesh, leaf roots, materials
// and textures are stored once however many copies (with CanopyDesc.impostors, each species' views
// are baked once). 1..256 species (kMaxSceneSpecies). With allowPerVertex, each species bends
// through its own branch hierarchy, or about its own trunk when it has none.
CanopyStatus createCanopy(Device* device, const std::vector<CanopySpecies>& species, const CanopyDesc& desc, CanopyContext** out);
// Releases the context. Its GPU objects are freed framesInFlight host frames later (or at
// releaseDevice), so the host may destroy it while frames that used it still execute.
void destroyCanopy(CanopyContext* context);

// Replaces the species and their copies at run time (a new vegetation mesh from `species`, which the
// copies' CanopyInstance.species index): the next recorded frame re-slices at once; the simulation,
// compositor and parameters are kept, the old mesh freed once no frame in flight reads it. Refused
// (the context unchanged) for a context created with CanopyDesc.allowPerVertex.
CanopyStatus setCanopySpecies(CanopyContext* context, const std::vector<CanopySpecies>& species,
                        const std::vector<CanopyInstance>& instances);

// Validates and applies parameters from the next frame on. A new layer count recreates the layer
// images (the old ones are freed once no frame in flight uses them).
CanopyStatus setCanopyParams(CanopyContext* context, const CanopyParams& params);
// The parameters in force (the last accepted by setCanopyParams, or CanopyDesc.params).
const CanopyParams& canopyParams(const CanopyContext* context);

// The host's targets changed size: recreates the size-dependent parts (layer images, compositor,
// warp grid); mesh, leaf roots, simulation and parameters are kept. Waits for nothing: the old
// objects are freed once no frame in flight uses them. Width and height in [1, 16384]. After a
// failure (out of memory) frames are refused until a resizeCanopy succeeds; the same size retries.
CanopyStatus resizeCanopy(CanopyContext* context, uint32_t width, uint32_t height);

// Replaces the placed copies (CanopyDesc.instances; at least one; CanopyInstance.species must name
// one of the context's species): the next recorded frame re-slices
// at once, and the default simulation plane (no CanopyParams.customPlane) is taken again from its
// camera for the copies' bounds. A transform that is not a finite invertible affine matrix, or a
// tint outside [0, 16], is refused naming the instance. Waits for nothing.
CanopyStatus setCanopyInstances(CanopyContext* context, const std::vector<CanopyInstance>& instances);

// What changes every frame.
struct CanopyFrame {
  CanopyCamera camera;
  float dt = 1.0f / 30.0f;  // simulation step, s, [0, 10]; 0 holds the simulation (pause)
  // The host's frame counter: never decreases; several contexts recorded in one host frame give
  // the same number. Recording frame F promises that frames <= F - framesInFlight have completed.
  // 0: the device's last number plus one, for one context per frame (with several, each 0 would
  // count as a new frame: pass the host's counter to all of them).
  uint64_t frameNumber = 0;
  // A camera cut: no motion vectors across it and the layers are re-sliced at once.
  bool cameraCut = false;
};

// One of the host's images, how it arrives and how to leave it (ResourceState: canopy_core.h), and
// how it was created: Vulkan cannot be asked for an image's usage, so the host declares it and
// Canopy checks it the first time it sees the image, with an error naming the image, what is
// missing and the fix (docs/embedding.md, "Host images").
struct CanopyImage {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;  // 2D view; for depth, the depth aspect only
  ResourceState current;              // last stage/access/layout the host used it with
  ResourceState final;                // the state Canopy must leave it in
  // VkImageCreateInfo.usage, required: colour and motion need COLOR_ATTACHMENT; depth needs
  // DEPTH_STENCIL_ATTACHMENT and SAMPLED (Canopy reads the host's depth).
  VkImageUsageFlags usage = 0;
  VkFormat format = VK_FORMAT_UNDEFINED;            // required: the CanopyDesc format of this target
  VkSampleCountFlagBits samples = VK_SAMPLE_COUNT_1_BIT;  // single-sampled only
  VkImageAspectFlags viewAspects = 0;  // the view's aspects; 0: as Canopy expects (colour; depth only)
};
// The description of an image the host created with `usage` and `format`, used as `current` ->
// `final` (single-sampled, the view's aspects as Canopy expects).
inline CanopyImage canopyImage(VkImage image, VkImageView view, VkImageUsageFlags usage, VkFormat format,
                               const ResourceState& current, const ResourceState& final) {
  CanopyImage i;
  i.image = image;
  i.view = view;
  i.current = current;
  i.final = final;
  i.usage = usage;
  i.format = format;
  return i;
}
struct CanopyFrameInputs {
  CanopyFrame frame;
  CanopyImage color, depth;
  CanopyImage motion;                 // only with CanopyDesc.motionFormat
};
// Records one whole frame (uploads prepared since the last frame, simulation step, re-slicing when
// the view moved, dynamics, warp and composite, with every barrier) into the host's `cmd`, which
// the host submits. Nothing is submitted and nothing waits. The host's images are left in their
// `final` states.
CanopyStatus recordCanopy(CanopyContext* context, VkCommandBuffer cmd, const CanopyFrameInputs& inputs);

// The vegetation's shadow for one of the host's lights (docs/embedding.md "Shadows"; docs/design.md
// "Shadows"): the foliage (alpha-tested) and the trunks drawn, depth only, into the host's depth
// image from `lightViewProj`, each leaf displaced as the last recorded frame shows it on screen.
struct CanopyShadowInputs {
  // The host's shadow map (or one layer of its cascade array: a 2D view of that layer), a depth
  // format (D16_UNORM, D32_SFLOAT, D24_UNORM_S8_UINT, D32_SFLOAT_S8_UINT), declared with
  // VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT; its states as for recordCanopy's images.
  CanopyImage depth;
  uint32_t width = 0, height = 0;  // the image's size, pixels, [1, 16384]
  Float4x4 lightViewProj;          // world -> the light's Vulkan clip space: orthographic (a sun) or perspective (a spot)
  bool reverseZ = false;           // the map's convention: near is 1, the test GREATER_OR_EQUAL (else LESS_OR_EQUAL)
  bool clear = true;               // clear to the far value first; false: drawn over what the host drew
  uint32_t cascade = 0;            // [0, 7]: whose update counter
  // [1, 64]: the vegetation is drawn at every updateInterval-th call for this cascade (the first
  // included); the calls between only move the image from `current` to `final`, its contents kept.
  uint32_t updateInterval = 1;
};
// Records the shadow into `cmd` after this frame's recordCanopy (the same command buffer or a later
// one); *updated (optional): whether this call drew. Refused before the first recordCanopy.
CanopyStatus recordCanopyShadow(CanopyContext* context, VkCommandBuffer cmd, const CanopyShadowInputs& inputs, bool* updated = nullptr);

// ---------------------------------------------------------------------------------------------
// One wind for the scene (docs/embedding.md "The wind and pushers"; docs/design.md "The wind a host reads",
// "Pushers")

// What a host's shader needs to read the wind (<canopy/canopy_wind.glsl>: the same 64 bytes).
struct CanopyWindInfo {
  float origin[4] = {0, 0, 0, 1};  // xyz: world point at plane coordinate (0, 0); w: the tile's size, world units
  float right[4] = {1, 0, 0, 0};   // xyz: the plane's unit x axis; w: the image's size n, texels a side
  float up[4] = {0, 1, 0, 0};      // xyz: its unit y axis
  float normal[4] = {0, 0, 1, 0};  // xyz: right x up (the wind has no component along it)
};
// The simulation's wind as an image a host's shaders sample (canopyWindAt in <canopy/canopy_wind.glsl>).
struct CanopyWind {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;        // 2D, colour
  VkFormat format = VK_FORMAT_UNDEFINED;    // R32G32_SFLOAT: the plane's velocity, domain units/s
  uint32_t size = 0;                        // texels a side (SimulationDesc.gridSize)
  // The state every recordCanopy (and createCanopy's first uploads) leaves it in: SHADER_READ_ONLY
  // layout, its writes visible to sampled reads of the vertex, fragment and compute stages; the
  // host's reads need no barrier of their own.
  ResourceState state;
  CanopyWindInfo info;  // the plane's mapping now (changes when the plane does: copy it every frame)
};
// The wind image and its mapping. The image lives as long as the context (the simulation's, with
// CanopyDesc.shareSimulationWith); it is written by the recordCanopy that steps the simulation, and
// may be sampled from the first recordCanopy (or recordCanopyLoad) on, which records its first clear.
CanopyStatus canopyWind(const CanopyContext* context, CanopyWind* out);
// The wind at `count` world points (world units/s, as canopyWindAt) on the CPU, for gameplay code:
// from a copy read back without a stall, framesInFlight host frames late (the newest step whose
// frame has completed by CanopyFrame.frameNumber's promise), through the plane of the context that
// stepped it. *fieldFrame (optional): the host frame whose step it is; 0 and zero vectors before any
// has completed.
CanopyStatus sampleCanopyWind(const CanopyContext* context, const Float3* points, size_t count, Float3* out,
                        uint64_t* fieldFrame = nullptr);
// The spheres and capsules moving through the vegetation from the next recorded frame on (replacing
// the last call's; empty: none): each mapped onto the simulation plane every frame, a local bend
// of the foliage that springs back and a motor of the fluid (CanopyPusher). At most kMaxPushers;
// more, or a field outside its range, is refused naming it (the pushers in force are kept). With a
// shared simulation the context that steps it (the first recorded in a frame) maps its own.
CanopyStatus setCanopyPushers(CanopyContext* context, const std::vector<CanopyPusher>& pushers);

// Loading without a hitch (a loading screen): records into the host's `cmd` the uploads createCanopy
// staged (mesh, textures, the simulation's first clear) and the first re-slice of the layers for
// `camera`, so the first recordCanopy at that camera (bit for bit) costs what any frame costs. The
// host submits `cmd` before its first frame's. A mesh streamed under deviceMemoryBudget is sliced
// over the first frames as before (its uploads only are recorded here). Optional.
CanopyStatus recordCanopyLoad(CanopyContext* context, VkCommandBuffer cmd, const CanopyCamera& camera);

// Re-slices the layers at the next recorded frame whatever the camera did: `immediate` draws the
// new layers in that frame; otherwise the re-slice is spread over frames like a view change
// (LayerSettings.rebuildBudgetMs; at once when that is 0). A spread re-slice already running is
// restarted for the next frame's camera.
CanopyStatus requestCanopyRebuild(CanopyContext* context, bool immediate);

// Counters of the context (and of the device's release queue); CPU only, any time.
CanopyStats canopyStats(const CanopyContext* context);

}  // namespace canopy
