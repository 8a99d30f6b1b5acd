#pragma once
// Canopy's plain types: the model's input descriptions, every parameter struct (declared by their
// field lists, <canopy/canopy_schema.h>), the context's description (CanopyDesc) and the statistics
// a context reports. No entry point: <canopy/canopy.h> includes this header and declares the
// functions; Canopy's own parts include only this one. C++17, Vulkan's headers only.
#include <cstdint>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

// The version, Result and CanopyStatus, Float3 / Float4x4 / CanopyCamera, and the host's device.
#include <canopy/canopy_core.h>
// The parameter schema the parameter structs are declared with.
#include <canopy/canopy_schema.h>

namespace canopy {

// ---------------------------------------------------------------------------------------------
// Vegetation input

enum class AlphaMode : uint32_t { Opaque = 0, Mask = 1, Blend = 2 };

// Limits a hostile file cannot get past: nothing is allocated from a number in the file before it
// is checked against the bytes behind it or against these.
struct GltfLoadOptions {
  uint64_t maxFileBytes = 2ull << 30;      // any single file (the model, a buffer, an image), <= 4 GiB
  uint32_t maxImageDimension = 16384;      // per side
  uint64_t maxImagePixels = 1ull << 28;    // all decoded images together (4 bytes each)
  uint64_t maxTriangles = 200'000'000;     // the whole model, after instancing by nodes
  uint64_t maxVertices = 150'000'000;      // the whole model, after instancing by nodes (32 bytes each)
  uint32_t maxJsonDepth = 64;              // nesting of JSON arrays and objects, checked before parsing
  bool decodeImages = true;
};

struct MeshMaterial {
  std::string name;                    // read by the rigid/foliage rule (MaterialSplitOptions)
  float baseColor[4] = {1, 1, 1, 1};   // linear RGBA factor
  int32_t image = -1;                  // index into MeshDesc::images, -1: none
  AlphaMode alphaMode = AlphaMode::Opaque;
  float alphaCutoff = 0.5f;            // [0, 1]
  bool doubleSided = false;
  // The leaf's gloss (docs/design.md "Layers: leaf shading"): glTF's perceptual roughness in [0, 1]
  // (the lobe's Beckmann sigma is its square); -1: LayerSettings.leafRoughness (Habel's range).
  float roughness = -1.0f;
  float specular = 1.0f;               // the lobe's weight, [0, 1] (KHR_materials_specular's specularFactor)
};
struct MeshImage {
  uint32_t width = 0, height = 0;      // 1..16384
  const uint8_t* rgba = nullptr;       // width * height sRGB-encoded RGBA8 texels, rows top to bottom
};
// One branch of a host's branch hierarchy for the per-vertex wind baseline (AnimationMode::PerVertex;
// docs/design.md "Per-vertex wind baseline"). Branches come parents first.
inline constexpr uint32_t kNoBranch = 0xffffffffu;  // MeshBranch.parent of a trunk
inline constexpr uint32_t kMaxBranchLevels = 4;     // trunk, branch, twig, finer
struct MeshBranch {
  Float3 origin;                 // rest position of the branch's base, world
  Float3 axis{0.0f, 1.0f, 0.0f}; // unit rest direction from the base to the tip
  uint32_t parent = kNoBranch;   // index of an earlier branch, or kNoBranch (level 0)
  uint32_t level = 0;            // the parent's + 1, below kMaxBranchLevels
};

// A triangle mesh in world space from the host's own arrays (copied).
struct MeshDesc {
  const float* positions = nullptr;    // 3 floats per vertex
  const float* normals = nullptr;      // 3 per vertex, or null (computed)
  const float* uvs = nullptr;          // 2 per vertex, or null (0, 0)
  uint32_t vertexCount = 0;
  const uint32_t* indices = nullptr;   // triangle list
  uint64_t indexCount = 0;             // a multiple of 3
  const uint32_t* triangleMaterials = nullptr;  // per triangle, or null (material 0)
  const MeshMaterial* materials = nullptr;
  uint32_t materialCount = 0;          // at least 1 when triangleMaterials is set
  const MeshImage* images = nullptr;
  uint32_t imageCount = 0;
  // Optional branch hierarchy (per-vertex baseline; without it a trunk and radial branches are
  // derived from the positions): per vertex the index of its innermost branch (kNoBranch: only the
  // leaf level moves it, e.g. ground) and Habel's w, 4 values in [0, 1] per vertex: its coordinate
  // along its level-L branch in w[L], and for each ancestor level the coordinate where the chain
  // leaves that ancestor. Checked at createCanopy with allowPerVertex.
  const uint32_t* vertexBranches = nullptr;
  const float* vertexW = nullptr;      // 4 per vertex
  const MeshBranch* branches = nullptr;
  uint32_t branchCount = 0;
  std::string name = "mesh";           // used in messages
};

// One placed copy of the model (CanopyDesc.instances, setCanopyInstances; docs/embedding.md).
struct CanopyInstance {
  Float4x4 transform;    // model -> world: any invertible affine matrix (rotation, non-uniform scale, a mirror)
  Float3 tint{1, 1, 1};  // multiplies the copy's base colour (linear), each channel in [0, 16]
  // s, [-3600, 3600]: the per-vertex baseline sways this copy as at its time + windPhase, so a hedge
  // of copies does not sway in lockstep. The 2D method's copies sway with the simulated field at
  // their place, which already differs between them (docs/design.md "Instances").
  float windPhase = 0.0f;
  // The copy's species: an index into the species the context was created with (createCanopy with
  // a CanopySpecies list; 0 with one model).
  uint32_t species = 0;
};

// A scene file (docs/scene-files.md; readCanopyScene in <canopy/canopy.h>): species and their
// placed copies. Caps on what a file may ask for (each a refusal naming the JSON pointer).
constexpr uint32_t kMaxSceneSpecies = 256;
constexpr uint32_t kMaxSceneInstances = 100000;     // explicit and scattered together
constexpr uint64_t kMaxSceneFileBytes = 16ull << 20;

// One species: its model — a glTF file, or one of the generated plants (the demo's generator:
// "shrub", "tree", "grass", "kelp", "field") — and its wind response.
struct CanopySceneSpecies {
  std::string name;            // unique in the file, 1..64 characters
  std::string gltf;            // the model's path, resolved against the scene file's folder; empty: generated
  std::string generated;       // a generated plant's kind; empty: gltf
  uint64_t faces = 0;          // generated: triangles, 2000..200M (0: the generator's default)
  uint32_t seed = 1;           // generated: the generator's seed
  float flexibility = 1.0f;    // [0, 4]: how far it bends for the same wind, relative to the method's
  float responseSpeed = 1.0f;  // [0.25, 4]: how fast it follows the wind, relative to the method's
  // "anchor": "base": a copy's position is where the centre of the model's base (its bounds' lowest
  // face) stands, for a file modelled away from its origin; "file" (false, the default): the model's
  // own origin. The reader of the file applies it (canopySceneAnchor).
  bool anchorBase = false;
};

// One placed copy of a species (CanopyInstance: its world transform, tint and wind phase).
struct CanopySceneInstance {
  uint32_t species = 0;  // index into CanopyScene::species
  CanopyInstance placement;
};

struct CanopyScene {
  std::string path;  // the file read
  std::vector<CanopySceneSpecies> species;
  std::vector<CanopySceneInstance> instances;  // the explicit ones in file order, then each scatter's
};

// Rigid vs foliage: explicit material names ("#N" for materials[N]) win over the default rule
// (names with bark/trunk/branch/... are rigid, leaf/grass/... and MASK/BLEND are foliage).
struct MaterialSplitOptions {
  std::vector<std::string> rigid;
  std::vector<std::string> foliage;
};
struct LeafRootOptions {
  bool weldPositions = true;  // also join vertices with bit-identical positions into one leaf
  // A leaf that meets the rigid parts (a vertex within 1 % of the model's size of a trunk or branch
  // triangle) is rooted where it meets them, not at its smallest (u, v): it goes into the layer of
  // the depth where it grows from its branch (docs/design.md "Rigid parts in wind"; false: the paper's).
  bool attachRoots = true;
};

// ---------------------------------------------------------------------------------------------
// Parameters (all changeable every frame through setCanopyParams unless said otherwise). Each
// struct is declared by its field list (<canopy/canopy_schema.h>): one line per field with its
// type, name, default, check, range, unit and what it does; docs/parameters.md is the same table.

inline constexpr uint32_t kMaxLayers = 32;
inline constexpr uint32_t kMaxMotors = 8;
inline constexpr uint32_t kMaxPushers = 32;  // setCanopyPushers: more are refused

enum class FluidScheme : uint32_t {
  MacMultigrid = 0,  // staggered grid + multigrid projection (default)
  Stam = 1,          // Stam's collocated games-paper solver, closed walls
};
enum class FluidBoundary : uint32_t {
  WindTunnel = 0,  // inflow on source sides, open outflow elsewhere (default)
  Walls = 1,       // closed box
};
// Wind source sides (combinable): a source on the left blows toward +x, on the top toward -y.
enum WindSide : uint32_t { kWindFromLeft = 1, kWindFromRight = 2, kWindFromBottom = 4, kWindFromTop = 8 };

// Injected wind: speed through a source side = strength * (baseline + modulation sin(2 pi f t))
// * (1 + gust * noise), the noise travelling along the side.
#define CANOPY_WIND_PARAMS(X)                                                                                           \
  X(uint32_t, sides, kWindFromLeft, Closed, 0, 15, "WindSide mask", "the source sides (0: no boundary wind)")          \
  X(float, strength, 0.5f, Closed, 0, 1000, "domain units/s", "wind speed through a source side")                     \
  X(float, frequency, 0.25f, Closed, 0, 1000, "Hz", "f of the speed profile a + b sin(2 pi f t)")                      \
  X(float, baseline, 1.0f, Closed, -10, 10, "", "a of the speed profile")                                              \
  X(float, modulation, 0.3f, Closed, -10, 10, "", "b of the speed profile")                                            \
  X(float, gust, 0.3f, Closed, 0, 1, "", "relative gust amplitude")                                                    \
  X(float, gustScale, 0.25f, AboveMin, 0, 100, "domain units", "gust wavelength along a side")                         \
  X(float, gustSpeed, 0.3f, Closed, -1000, 1000, "domain units/s", "gust travel speed along a side")                   \
  X(uint32_t, seed, 1, Unchecked, 0, 0, "", "gust noise seed")
CANOPY_PARAM_STRUCT(WindParams, CANOPY_WIND_PARAMS)

// A point "motor" (a character, an explosion): a mass source in the fluid, so air flows outward
// around it (negative strength: inward). The source density falls linearly to zero at the radius.
#define CANOPY_MOTOR_PARAMS(X)                                                                                          \
  X(float, x, 0.5f, Closed, -100, 100, "domain units", "centre x (may lie outside [0, 1])")                            \
  X(float, y, 0.5f, Closed, -100, 100, "domain units", "centre y (may lie outside [0, 1])")                            \
  X(float, radius, 0.1f, AboveMin, 0, 100, "domain units", "where the source density reaches zero")                    \
  X(float, strength, 1.0f, Closed, -1000, 1000, "domain units/s", "outward flow speed at the radius")
CANOPY_PARAM_STRUCT(Motor, CANOPY_MOTOR_PARAMS)

#define CANOPY_FLUID_PARAMS(X)                                                                                          \
  X(FluidScheme, scheme, FluidScheme::MacMultigrid, Enum, 0, 1, "MacMultigrid | Stam", "the stable-fluids solver")      \
  X(FluidBoundary, boundary, FluidBoundary::WindTunnel, Enum, 0, 1, "WindTunnel | Walls",                                \
    "the domain's edges (MAC scheme only; Stam's has walls)")                                                          \
  X(float, viscosity, 1e-4f, Closed, 0, 10, "domain units^2/s", "kinematic viscosity")                                 \
  X(uint32_t, iterations, 20, Closed, 1, 10000, "", "relaxation sweeps")                                               \
  X(uint32_t, multigridCycles, 2, Closed, 1, 64, "", "V-cycles per MAC projection")
CANOPY_PARAM_STRUCT(FluidParams, CANOPY_FLUID_PARAMS)

// The oscillator V'' = c^2 lap V - k (V - g V_wind) - zeta V' (docs/design.md).
#define CANOPY_WAVE_PARAMS(X)                                                                                           \
  X(float, stiffness, 40.0f, Closed, 0, 1e6, "1/s^2", "k: pull towards the driven rest state")                         \
  X(float, speed, 0.5f, Closed, 0, 100, "domain units/s", "c: wave propagation speed (eq. 5's s; before 0.7: 0.05)")    \
  X(float, damping, 2.0f, Closed, 0, 1000, "1/s", "zeta")                                                              \
  X(float, gain, 1.0f, Closed, -100, 100, "", "g: how strongly the wind drives the wave")                              \
  X(uint32_t, maxSubsteps, 64, Closed, 1, 4096, "", "stable substeps per step; a longer step is clamped (stats.clampedSeconds)")
CANOPY_PARAM_STRUCT(WaveParams, CANOPY_WAVE_PARAMS)

// How grass pushed by a CanopyPusher springs back (docs/design.md "Pushers"): each cell of the
// pushers' bend field is a damped spring B'' = -stiffness (B - target) - damping B'. The defaults
// (omega 3 /s, damping ratio 0.7) settle to 10 % of a bend in about a second.
#define CANOPY_PUSH_PARAMS(X)                                                                                           \
  X(float, stiffness, 9.0f, Closed, 0, 400, "1/s^2", "pull of the pushed grass back to its rest (and toward a pusher's target)") \
  X(float, damping, 4.2f, Closed, 0, 100, "1/s", "damping of the spring back")
CANOPY_PARAM_STRUCT(PushParams, CANOPY_PUSH_PARAMS)

#define CANOPY_SIMULATION_PARAMS(X)                                                                                     \
  X(WindParams, wind, {}, Nested, 0, 0, "", "injected wind")                                                            \
  X(FluidParams, fluid, {}, Nested, 0, 0, "", "the fluid solver")                                                       \
  X(WaveParams, wave, {}, Nested, 0, 0, "", "the wave oscillator")                                                      \
  X(std::vector<Motor>, motors, {}, Each, 0, kMaxMotors, "", "point motors, at most kMaxMotors")                       \
  X(PushParams, push, {}, Nested, 0, 0, "", "how grass pushed by a CanopyPusher springs back")
CANOPY_PARAM_STRUCT(SimulationParams, CANOPY_SIMULATION_PARAMS)

// Fixed at creation. The simulation domain is the unit square of the simulation plane.
// groupSize: invocations of the single-workgroup solver kernels; 0: chosen by device class
// (docs/performance.md): on CPU devices such as lavapipe, grids of 16..128 run the diffusion,
// projection and oscillator as one subgroup with the fields in registers (other steps at 64),
// GPUs take 1024. A non-zero value forces the workgroup kernels at that width.
#define CANOPY_SIMULATION_DESC(X)                                                                                       \
  X(uint32_t, gridSize, 64, PowerOfTwo, 4, 1024, "cells", "N: the grid is N x N (the multigrid and red-black kernels need a power of two)") \
  X(uint32_t, historySize, 0, Closed, 0, 4096, "fields", "H tiled fields kept; 0: enough for historySeconds at nominalDt") \
  X(float, historySeconds, 1.0f, AboveMin, 0, 3600, "s", "the delayed fields' reach")                                  \
  X(float, nominalDt, 1.0f / 30.0f, AboveMin, 0, 10, "s", "the step the history is sized for")                        \
  X(uint32_t, groupSize, 0, PowerOfTwoOrZero, 32, 1024, "invocations", "single-workgroup kernels' width; 0: by device class")
CANOPY_PARAM_STRUCT(SimulationDesc, CANOPY_SIMULATION_DESC)

// Layers per depth region, written like the paper: {3, 1, 1} is "5(3-1-1)".
struct LayerLayout {
  uint32_t region[3] = {3, 1, 1};  // near, mid, far
  uint32_t count() const { return region[0] + region[1] + region[2]; }
};
inline bool operator==(const LayerLayout& a, const LayerLayout& b) {
  return a.region[0] == b.region[0] && a.region[1] == b.region[1] && a.region[2] == b.region[2];
}
inline bool operator!=(const LayerLayout& a, const LayerLayout& b) { return !(a == b); }
// Where the near region ends and the far region begins: fractions of the foliage's depth range
// (0 <= nearEnd <= farStart <= 1), or with `absolute` view distances in world units (checked
// together: "region split").
#define CANOPY_REGION_SPLIT(X)                                                                                          \
  X(float, nearEnd, 1.0f / 3.0f, Unchecked, 0, 1, "fraction (or world units)", "end of the near region")                    \
  X(float, farStart, 2.0f / 3.0f, Unchecked, 0, 1, "fraction (or world units)", "start of the far region")                  \
  X(bool, absolute, false, Unchecked, 0, 0, "", "the two are view distances in world units")
CANOPY_PARAM_STRUCT(RegionSplit, CANOPY_REGION_SPLIT)
enum class SliceMode {
  LeafRoots,  // a leaf goes whole into the layer of its root (default)
  Geometry,   // near/far planes on each fragment's depth (leaves crossing a boundary are cut)
};
enum class LayerDrawMode { Auto, SinglePass, PerLayer };  // Auto: single pass when the device can
enum class ReslicePolicy { OnViewChange, EveryFrame };

// Image-based levels of detail for the foliage (Lluch et al.'s image-based multiresolution foliage; docs/design.md
// "Impostors"): at a re-slice, boxes of the foliage's box hierarchy are drawn as textured polygons
// (their baked views, CanopyDesc.impostors) instead of their leaves.
enum class ImpostorMode {
  Off,              // every leaf drawn (default)
  FarRegion,        // boxes whose root lies in the far region (LayerSettings.regions) and whose
                    // projected size is below switchPixels; the share ramps in over band x (the
                    // foliage's depth range / the layer count) before the far region's start
  ByProjectedSize,  // any box whose projected size is below switchPixels, whatever its depth
};
// How a box's stored views are drawn: the paper's crossed polygons (each view on its own plane
// through the box, alpha-blended by how squarely it faces the viewer: parallax inside the box) or,
// before 0.7, one polygon facing the viewer blending the two views nearest its direction.
enum class ImpostorShape { CrossedPolygons, FacingPolygon };
// A mode other than Off needs CanopyDesc.impostors.enable and a resident mesh; the cut is made for
// each re-slice's view, at once or, spread over frames (rebuildBudgetMs > 0), when its placement is done.
// A box is an impostor where its projected size (bounding-sphere diameter, pixels of the layer
// images) is at most switchPixels; its leaves fade out and its impostor in while the size falls
// from switchPixels x (1 + band) to switchPixels (a distance band: size ~ 1 / distance). At
// switchPixels = CanopyDesc.impostors.tilePixels the views are shown 1:1 (Lluch et al. 4.1).
#define CANOPY_IMPOSTOR_SETTINGS(X)                                                                                     \
  X(ImpostorMode, mode, ImpostorMode::Off, Enum, 0, 2, "Off | FarRegion | ByProjectedSize", "which boxes are drawn as impostors") \
  X(float, switchPixels, 64.0f, Closed, 1, 4096, "pixels", "projected size at and below which a box is an impostor")   \
  X(float, band, 0.2f, Closed, 0, 4, "", "the fade's width above switchPixels, relative; 0: a hard switch")            \
  X(bool, debugView, false, Unchecked, 0, 0, "", "colour leaves and impostors by their box's level (also with mode Off)") \
  X(ImpostorShape, shape, ImpostorShape::CrossedPolygons, Enum, 0, 1, "CrossedPolygons | FacingPolygon", "how a box's views are drawn (FacingPolygon: before 0.7)")
CANOPY_PARAM_STRUCT(ImpostorSettings, CANOPY_IMPOSTOR_SETTINGS)

// Which views a box stores: Lluch et al.'s six diagonally aligned planes (Figure 6; each contains two
// opposite edges of the box), or (before 0.7) those and the six box faces, twice the storage.
enum class ImpostorViews { Diagonal6, FacesAndDiagonals12 };
// Fixed at creation: the foliage's box hierarchy and its baked views. Boxes of hierarchy levels
// 0..maxLevel get views (6 or 12 each, `views`; tilePixels^2 x 8 bytes each: RGBA8 colour, 32-bit
// depth), level by level from the top while memoryBudget allows; a box over maxBoxTriangles (its
// subtree's leaves) gets none (its children do): baking costs a draw of a box's leaves per view,
// and a box this large is rarely small on screen. Levels count boxes with other leaves than their only child's (an L-system's bracketed
// axiom is not a level of its own). When not even the top level fits memoryBudget (RGBA8 colour
// and 32-bit depth), the tiles are halved (down to 8 pixels) before the creation is refused.
#define CANOPY_IMPOSTOR_DESC(X)                                                                                         \
  X(bool, enable, false, Unchecked, 0, 0, "", "build the hierarchy and bake the views (ImpostorSettings.mode may then be on)") \
  X(uint32_t, tilePixels, 64, PowerOfTwo, 8, 512, "pixels", "side of each view's image")                               \
  X(uint32_t, maxLevel, 2, Closed, 0, 64, "", "the deepest hierarchy level baked")                                     \
  X(uint64_t, maxBoxTriangles, 1'000'000, Closed, 1, 1099511627776.0, "triangles", "a larger box gets no views")      \
  X(uint64_t, memoryBudget, 256ull << 20, Closed, 1048576, 17179869184.0, "bytes", "the views' colour and depth")      \
  X(uint32_t, maxLeavesPerBox, 256, Closed, 1, 1073741824, "leaves", "models without a box hierarchy (glTF): k-d split of the leaf roots") \
  X(float, minVolumeRatio, 0.0f, Closed, 0, 1, "", "a box under this share of its parent box's volume gets no views (Lluch et al.'s level limit; 0: none)") \
  X(ImpostorViews, views, ImpostorViews::Diagonal6, Enum, 0, 1, "Diagonal6 | FacesAndDiagonals12", "the views stored per box (FacesAndDiagonals12: before 0.7)")
CANOPY_PARAM_STRUCT(ImpostorDesc, CANOPY_IMPOSTOR_DESC)

// Leaf shading (Habel et al.'s leaf model, section III; docs/design.md "Layers: leaf shading"): on
// the side the light falls on, Lambert plus a Cook-Torrance lobe on the leaf's front; on the unlit
// side, diffuse transmission. Rigid parts are Lambert only. A change re-slices, like a light change.
// Spread re-slicing (docs/design.md "Layers: spread re-slicing"): rebuildBudgetMs > 0: a re-slice
// caused by the camera (the reprojection's estimated error: errorThresholdPixels, turnThresholdDegrees;
// docs/design.md "Layers: reprojection"), a light change or
// requestCanopyRebuild(spread) is done over several frames, each adding about this much work: the
// placement on the CPU (timed), then triangles drawn into a second layer set (as many as the
// measured drawing rate fits); the old layers keep animating meanwhile, and the new ones replace
// them over crossFadeFrames frames (in one copy when drawn from another camera). 0: every re-slice is drawn at once in the frame that asks for
// it. The first view, a camera cut, a new layer count or size, ReslicePolicy::EveryFrame and the
// id output always re-slice at once.
// The unlit side of a leaf (docs/design.md "Layers: leaf shading"): Habel's translucency (Habel et al.,
// III.C: the light-facing side's relief, its self-shadowing, Fresnel entry, Beer-Lambert through the
// leaf's thickness), or the diffuse BTDF he contrasts it with.
enum class TranslucencyModel { Habel, DiffuseBtdf };
// How the rigid parts (trunks, branches) move (docs/design.md "Rigid parts in wind"): drawn every
// frame, each vertex displaced as the foliage layer of its depth is, by a share that is 0 at the
// plant's foot and 1 from its crown's base up, so the leaves stay on their branches and the trunk's
// base stands (FollowFoliage); or drawn once per re-slice as the still background the paper
// composites the layers over (Still; before 0.8, and for a streamed mesh).
enum class RigidMotion { FollowFoliage, Still };
#define CANOPY_LAYER_SETTINGS(X)                                                                                        \
  X(LayerLayout, layout, {}, Unchecked, 1, kMaxLayers, "layers", "default 5(3-1-1), at most CanopyDesc.maxLayers layers (checked as a whole)") \
  X(RegionSplit, regions, {}, Nested, 0, 0, "", "where the depth regions meet")                                        \
  X(SliceMode, slice, SliceMode::LeafRoots, Enum, 0, 1, "LeafRoots | Geometry", "how leaves go into layers")          \
  X(LayerDrawMode, draw, LayerDrawMode::Auto, Enum, 0, 2, "Auto | SinglePass | PerLayer", "how the layers are drawn") \
  X(bool, shadeOnce, false, Unchecked, 0, 0, "", "a depth pre-pass first, so leaf shading runs once per layer texel (slower on lavapipe: docs/design.md)") \
  X(uint32_t, halfResolutionLayers, 0, Closed, 0, kMaxLayers, "layers", "the farthest this many layers are drawn at half resolution (a quarter of their fill); at most the layout's count") \
  X(ReslicePolicy, policy, ReslicePolicy::OnViewChange, Enum, 0, 1, "OnViewChange | EveryFrame", "when layers are re-sliced") \
  X(float, errorThresholdPixels, 0.5f, Closed, 0, 1000, "pixels", "estimated reprojection error that re-slices (parallax, content beyond the layers; 0.5: the world-lock bar of docs/performance.md)") \
  X(float, turnThresholdDegrees, 2.0f, Closed, 0, 180, "degrees", "change of the view direction to the vegetation that re-slices (baked shading)") \
  X(uint32_t, predictFrames, 0, Closed, 0, 16, "frames", "a moving camera's re-slice at once slices for its view this many frames ahead (its last frame's motion repeated; 0: the current view)") \
  X(bool, pacedReslices, false, Unchecked, 0, 0, "", "a moving camera's re-slices drawn in even slices over the frames until its error would pass the thresholds, each sliced for the view it is shown at (docs/design.md: spread re-slicing)") \
  X(Float3, lightDirection, (Float3{0.35f, 0.8f, 0.5f}), Finite, 0, 0, "world space", "towards the light (normalised; zero: straight up)") \
  X(Float3, lightColor, (Float3{1.0f, 1.0f, 1.0f}), Closed, 0, 1000, "linear RGB", "the light's colour")              \
  X(float, ambient, 0.35f, Closed, 0, 1, "", "ambient share of the light")                                             \
  X(float, leafRefractiveIndex, 1.45f, Closed, 1.2, 1.7, "", "effective refractive index n of the lobe (Bousquet et al.'s measured range)") \
  X(float, leafRoughness, 0.25f, Closed, 0.078, 0.5, "", "Beckmann roughness sigma of the lobe (measured range) where the material gives none (a generated scene), or for every material with overrideLeafRoughness (canopy-demo: when given)") \
  X(bool, overrideLeafRoughness, false, Unchecked, 0, 0, "", "leafRoughness for every material, the file's roughness ignored")    \
  X(float, leafTransmission, 0.35f, Closed, 0, 1, "", "diffuse transmission of foliage materials whose file gives none") \
  X(bool, translucency, true, Unchecked, 0, 0, "", "false: unlit sides get the ambient term only")                          \
  X(TranslucencyModel, translucencyModel, TranslucencyModel::Habel, Enum, 0, 1, "Habel | DiffuseBtdf", "the unlit side's light (DiffuseBtdf: before 0.7)") \
  X(float, leafOpticalDepth, 0.3f, Closed, 0, 100, "", "Habel: optical depth through a leaf whose file gives no KHR_materials_volume")       \
  X(RigidMotion, rigidMotion, RigidMotion::FollowFoliage, Enum, 0, 1, "FollowFoliage | Still", "trunks and branches move with the leaves they carry, drawn every frame (Still: a background drawn per re-slice, before 0.8)") \
  X(float, rebuildBudgetMs, 0.0f, Closed, 0, 1000, "ms", "work a frame of a spread re-slice; 0: re-slices at once")   \
  X(uint32_t, crossFadeFrames, 8, Closed, 1, 240, "frames", "a spread re-slice fades in over this many frames")       \
  X(ImpostorSettings, impostors, {}, Nested, 0, 0, "", "Lluch et al.'s impostors (a change re-slices)")
CANOPY_PARAM_STRUCT(LayerSettings, CANOPY_LAYER_SETTINGS)

enum class DelayMode { Exact, Approximate };  // paper eq. 3-4, or eq. 5
// Units of L_i in eq. 4 (docs/design.md "Departures from the papers"): the simulation's domain units
// (the world distance over SimulationPlane.tileSize, so a plant authored in centimetres sways as the
// same plant in metres), or world units as before 0.7 (delays then grow with the model's scale).
enum class DelayDistanceUnits { Domain, World };
// Units of lambda in eq. 6: warp-grid cells per domain unit (the paper: "set with respect to the grid
// cell's size"; scaled by cellSize into pixels), or pixels per domain unit as before 0.7.
enum class LambdaUnits { Cells, Pixels };
// Eq. 5's offset: gamma s V/|V| (the paper: "the distance the movement travels during gamma", V
// taken as the direction and s the wave's propagation speed), or gamma s V as before 0.7.
enum class ApproximateOffset { Direction, Velocity };
using Eq5Offset [[deprecated("renamed ApproximateOffset in 0.7; removed in 0.9")]] = ApproximateOffset;
// Eq. 7's root: the bottom of each plant's bounding box (every generated plant, glTF scene root,
// or copy; beyond the paper: docs/design.md "Per-plant roots"), or of the whole vegetation's as the
// paper says (before 0.7: every plant of a field bends about the field's lowest point).
enum class RootMode { PerPlant, Vegetation };
// Eq. 6's Delta t is the simulation's nominal step (SimulationDesc.nominalDt, the paper's "simulation
// time step") unless dt > 0 overrides it; never the frame's measured time, so the sway does not
// depend on the frame rate. V_D of eq. 4: vd, plus per layer a seeded uniform number in
// [-vdJitter, vdJitter] (the paper: "a small random number"; 0: the constant).
#define CANOPY_DYNAMICS_PARAMS(X)                                                                                       \
  X(DelayMode, delay, DelayMode::Exact, Enum, 0, 1, "Exact | Approximate", "eq. 3-4, or eq. 5")                         \
  X(float, vd, 4.0f, Closed, -1000, 1000, "domain units/s", "V_D of eq. 4 (before 0.8: 1; before 0.7: 2, with L_i in world units)")                                             \
  X(float, propagationSpeed, 0.0f, Closed, 0, 1000, "domain units/s", "s of eq. 5; 0: the wave oscillator's speed c (WaveParams.speed)") \
  X(Float3, lambda, (Float3{18.75f, 18.75f, 9.375f}), Closed, 0, 1e6, "cells (lambdaUnits) per domain unit", "lambda_x,y,z of eq. 6") \
  X(float, rigidity, 1.0f, Closed, 0, 10, "", "r of eq. 7")                                                            \
  X(bool, everyPartMoves, false, Unchecked, 0, 0, "", "eq. 7: R = 1 everywhere")                                            \
  X(float, depthAttenuation, 0.3f, Closed, 0, 1, "", "m of eq. 6")                                                     \
  X(float, dt, 0.0f, Closed, 0, 10, "s", "Delta t of eq. 6; 0: the simulation's nominal step (SimulationDesc.nominalDt)") \
  X(uint32_t, cellSize, 16, Closed, 2, 256, "pixels", "warp-grid cell (at least CanopyDesc.minCellSize)")             \
  X(float, maxDelay, 10.0f, AboveMin, 0, 3600, "s", "|gamma| bound for a vanishing eq. 4 denominator")                 \
  X(DelayDistanceUnits, delayUnits, DelayDistanceUnits::Domain, Enum, 0, 1, "Domain | World", "units of L_i in eq. 4 (World: before 0.7)") \
  X(LambdaUnits, lambdaUnits, LambdaUnits::Cells, Enum, 0, 1, "Cells | Pixels", "units of lambda (Pixels: before 0.7)")  \
  X(float, vdJitter, 0.0f, Closed, 0, 1000, "domain units/s", "per-layer random part of V_D, uniform in [-vdJitter, vdJitter]") \
  X(uint32_t, vdSeed, 1, Unchecked, 0, 0, "", "seed of the per-layer V_D")                                              \
  X(ApproximateOffset, approximateOffset, ApproximateOffset::Direction, Enum, 0, 1, "Direction | Velocity", "eq. 5: gamma s V/|V|, or gamma s V (before 0.7)") \
  X(RootMode, roots, RootMode::PerPlant, Enum, 0, 1, "PerPlant | Vegetation", "eq. 7's root: each plant's, or the whole vegetation's (before 0.7)") \
  X(float, maxShrink, 0.05f, Closed, 0, 1e6, "of the height above the root", "eq. 6's lambda_z |V_z| shrink at most this share of a corner's height above its root (1e6: unbounded, before 0.8)")  \
  X(float, maxStretch, 0.4f, Closed, 0, 4, "cells per cell", "the displacement's largest change across one warp cell (the warp draws a texel at most 1 / (1 - maxStretch) wide; 0: unbounded, before 0.8)")
CANOPY_PARAM_STRUCT(DynamicsParams, CANOPY_DYNAMICS_PARAMS)

enum class CompositeDebugView : uint32_t {
  Off = 0,
#ifndef None
  None = Off,  // 0.8's name of Off (X11 defines None)
#endif
  Layers = 1,    // each layer in its own false colour (paper Figure 3c)
  Velocity = 2,  // the tiled simulation field over the simulation plane
  Grid = 3,      // the nearest layer's warp grid, displaced
};
// How the inverse warp + compositing runs (docs/performance.md compares them).
enum class CompositePath : uint32_t {
  Compute = 0,   // tile-classified compute kernel + a resolve draw over the listed tiles (default)
  Fragment = 1,  // one fused full-screen fragment pass (also used for the debug views)
};
// skipEmptyTiles: per 8x8 screen tile in the compute path (a layer is listed when its occupancy
// meets the tile moved by the displacement's range), per pixel in the fragment path. exposure:
// the vegetation's linear colour is multiplied by it before it is blended over the host's target
// (HDR hosts: scene-referred intensity).
#define CANOPY_COMPOSITE_PARAMS(X)                                                                                      \
  X(CompositePath, path, CompositePath::Compute, Enum, 0, 1, "Compute | Fragment", "how the warp and composite run")   \
  X(bool, earlyExit, true, Unchecked, 0, 0, "", "front to back, stop at accumulated alpha >= 1 - 1/1024")                   \
  X(bool, skipEmptyTiles, true, Unchecked, 0, 0, "", "skip layers that cannot reach a pixel")                              \
  X(bool, bilinear, true, Unchecked, 0, 0, "", "bilinear layer colour (false: nearest texel)")                              \
  X(float, sharpness, 3.0f, Closed, 1, 8, "", "the warp's filter: the bilinear ramp between texel centres steepened k times (1: bilinear; design.md, sharp resampling)") \
  X(uint32_t, depthSearchSteps, 16, Closed, 0, 64, "samples", "reprojection: at most this many samples of a layer's depth along a pixel's ray (two layer pixels apart; 0: the slab's plane alone)") \
  X(float, depthAlpha, 0.5f, AboveMin, 0, 1, "", "alpha at which a layer writes the depth output")                    \
  X(float, exposure, 1.0f, Closed, 0, 65504, "", "multiplies the vegetation's linear colour")                          \
  X(CompositeDebugView, debugView, CompositeDebugView::Off, Enum, 0, 3, "Off | Layers | Velocity | Grid", "debug views") \
  X(float, debugVelocityScale, 1.0f, AboveMin, 0, 1e30, "domain units/s", "velocity view: speed at full brightness")
CANOPY_PARAM_STRUCT(CompositeParams, CANOPY_COMPOSITE_PARAMS)

// The simulation plane in world space: the 2D field is the same on every parallel plane (right
// and up checked together: orthogonal unit vectors).
#define CANOPY_SIMULATION_PLANE(X)                                                                                      \
  X(Float3, origin, (Float3{0.0f, 0.0f, 0.0f}), Finite, 0, 0, "world space", "world point at simulation coordinate (0, 0)") \
  X(Float3, right, (Float3{1.0f, 0.0f, 0.0f}), Finite, 0, 0, "world space", "unit x axis")                             \
  X(Float3, up, (Float3{0.0f, 1.0f, 0.0f}), Finite, 0, 0, "world space", "unit y axis, orthogonal to right")           \
  X(float, tileSize, 1.0f, AboveMin, 0, 1e30, "world units", "covered by one tile")
CANOPY_PARAM_STRUCT(SimulationPlane, CANOPY_SIMULATION_PLANE)

// Something moving through the vegetation (a character, a vehicle, a blast), in world space:
// setCanopyPushers. A capsule from `a` to `b` (a sphere when they are equal). Canopy maps it onto
// the simulation plane every frame (docs/design.md "Pushers"): a local bend of the foliage near it
// that springs back (SimulationParams.push), and a motor of the fluid (the air it displaces as it
// moves, and an optional outward blow), which the wind a host reads carries too.
#define CANOPY_PUSHER_PARAMS(X)                                                                                         \
  X(Float3, a, (Float3{0.0f, 0.0f, 0.0f}), Finite, 0, 0, "world space", "the capsule's first end (a sphere's centre)") \
  X(Float3, b, (Float3{0.0f, 0.0f, 0.0f}), Finite, 0, 0, "world space", "its other end (equal to a: a sphere)")         \
  X(float, radius, 0.5f, AboveMin, 0, 1e6, "world units", "the capsule's radius: what it touches")                    \
  X(Float3, velocity, (Float3{0.0f, 0.0f, 0.0f}), Finite, 0, 0, "world units/s", "how it moves (the air it displaces)") \
  X(float, bend, 1.0f, Closed, 0, 16, "x the default wind", "how far it bends the foliage it touches: 1 as far as a wind of WindParams.strength's default (0.5 domain units/s)") \
  X(float, air, 0.25f, Closed, 0, 16, "", "scales the air its motion displaces (1: its cross-section's; 0.25: the plane's column counts a quarter)") \
  X(float, blow, 0.0f, Closed, -1000, 1000, "world units/s", "an outward push of air at its radius (a blast, a rotor's downwash; negative: inward)")
CANOPY_PARAM_STRUCT(CanopyPusher, CANOPY_PUSHER_PARAMS)

// How the vegetation is animated (docs/design.md "Per-vertex wind baseline"). A host switches
// between the two on the same context and scene (CanopyDesc.allowPerVertex) to compare them.
enum class AnimationMode : uint32_t {
  Layers2D = 0,   // the paper's method: depth layers, 2D wind simulation, inverse warp, composite (default)
  PerVertex = 1,  // the "3D" baseline (Habel et al.'s hierarchical bending, IV-VI): the whole mesh drawn every frame into
                  // the host's targets, every vertex bent through its branch hierarchy in the vertex
                  // shader; no simulation, layers or composite run
};
// The per-vertex baseline's wind (docs/design.md "Per-vertex wind baseline").
enum class PerVertexWind {
  KaimalField,   // a stochastic wind field over the plant (Kaimal's spectrum, random-phase components
                 // carried by the mean wind), each level a damped oscillator responding to it (default)
  UniformNoise,  // one wind speed for the whole plant, spectral noise per branch (before 0.7)
};
// The per-vertex baseline's hierarchical bending. The wind is SimulationParams.wind's: its speed
// profile strength * (baseline + modulation sin(2 pi frequency t)) as the mean wind, its direction
// from the source sides on the simulation plane, its gust as the turbulence intensity (the
// fluctuation's standard deviation over the mean speed). Levels: 0 trunk, 1 branch, 2 twig,
// 3 finer; then each leaf about its root. Tip bends are given at referenceSpeed (WindMode::World:
// worldReferenceSpeed; drag makes them grow with the speed squared); with KaimalField each level
// responds as a damped oscillator of natural frequency `frequency` and damping ratio `damping`. The
// defaults sway the default shrub within a factor 1.5 of the 2D method in the default world wind
// (docs/performance.md "The wind from every side"), and as much in 0.7's demo wind (PlaneSides:
// "The 2D method against the per-vertex baseline").
#define CANOPY_PER_VERTEX_PARAMS(X)                                                                                     \
  X(Float4, flexibility, (Float4{{0.045f, 0.079f, 0.1125f, 0.135f}}), Closed, 0, 100, "rad", "tip bend per level (0.036, 0.063, 0.09, 0.108 before 0.7)") \
  X(float, leafFlexibility, 0.3375f, Closed, 0, 100, "rad", "a leaf's bend about its root (0.27 before 0.7)")        \
  X(Float4, frequency, (Float4{{0.35f, 0.8f, 1.6f, 2.6f}}), Closed, 0, 100, "Hz", "natural (sway) frequency per level") \
  X(float, leafFrequency, 4.0f, Closed, 0, 100, "Hz", "a leaf's natural frequency")                                    \
  X(float, referenceSpeed, 2.0f, AboveMin, 0, 1000, "domain units/s", "WindMode::PlaneSides: the mean wind speed the two above are given at") \
  X(float, worldReferenceSpeed, 6.0f, AboveMin, 0, 1000, "m/s", "WindMode::World: the mean wind speed the two above are given at") \
  X(float, lateral, 0.4f, Closed, 0, 1, "", "sway across the wind relative to the sway along it")                      \
  X(float, maxAngle, 0.5f, AboveMin, 0, 1.5, "rad", "saturation of any one bend")                                      \
  X(float, taper, 1.5f, Closed, 0.5, 4, "", "the rotation at coordinate x along a branch is tip * x^taper")            \
  X(uint32_t, seed, 1, Unchecked, 0, 0, "", "noise phases")                                                                   \
  X(PerVertexWind, wind, PerVertexWind::KaimalField, Enum, 0, 1, "KaimalField | UniformNoise", "the wind model (UniformNoise: before 0.7)") \
  X(Float4, damping, (Float4{{0.15f, 0.2f, 0.25f, 0.3f}}), Closed, 0.01, 10, "", "KaimalField: damping ratio per level") \
  X(float, leafDamping, 0.4f, Closed, 0.01, 10, "", "KaimalField: a leaf's damping ratio")                            \
  X(float, integralScale, 1.0f, AboveMin, 0, 1000, "domain units", "KaimalField: the turbulence's length scale L")
CANOPY_PARAM_STRUCT(PerVertexParams, CANOPY_PER_VERTEX_PARAMS)

// How a host sets the wind (docs/design.md "World wind").
enum class WindMode : uint32_t {
  World = 0,       // CanopyParams.wind: a world direction and a speed in m/s (default); the simulation
                   // plane is horizontal through the vegetation, its x axis along the wind, fixed in the
                   // world (no camera chooses it); SimulationParams.wind's sides, strength, frequency,
                   // baseline, modulation and gust are derived from it each frame
  PlaneSides = 1,  // advanced (before 0.8): SimulationParams.wind's source sides and strength on the plane
                   // fixed by the first frame's camera, or on CanopyParams.plane with customPlane
};
// The wind in the world, as a game sets it (Unity's WindZone, SpeedTree's wind): a direction and a
// mean speed, the speed swelling in gusts, noise along the gust front. A change eases in over
// easeSeconds (the direction turns along the shortest arc, both with a smoothstep in time), so a
// host may set it every frame. The simulation's domain speed is speed / tileMetres (one tile is one
// domain unit: docs/design.md "World wind").
#define CANOPY_WORLD_WIND(X)                                                                                            \
  X(Float3, direction, (Float3{1.0f, 0.0f, 0.0f}), Finite, 0, 0, "world space", "where the wind blows toward (any length > 0; y is up)") \
  X(float, speed, 3.0f, Closed, 0, 100, "m/s", "mean wind speed (3: a light breeze, Beaufort 2)")                      \
  X(float, unitsPerMetre, 1.0f, AboveMin, 0, 1e6, "world units per m", "the model's scale (100: authored in centimetres)") \
  X(float, gustIntensity, 0.4f, Closed, 0, 4, "", "gust swell: the speed is speed * (1 + gustIntensity sin(2 pi gustFrequency t))") \
  X(float, gustFrequency, 0.3f, Closed, 0, 100, "Hz", "how often the gusts come")                                      \
  X(float, turbulence, 0.3f, Closed, 0, 1, "", "noise travelling along the gust front, relative to the speed")         \
  X(float, easeSeconds, 2.0f, Closed, 0, 600, "s", "a change of direction or speed eases in over this time (0: at once)") \
  X(float, tileMetres, 4.0f, Closed, 0.01, 1e4, "m", "the simulation tile's least side in the world (it spans the vegetation seen from above: a plant smaller than it sways as one)") \
  X(float, sway, 0.03f, Closed, 0, 10, "of its height per m/s", "how far a plant's top moves in the wind: eq. 6 in shares of the plant's on-screen height")
CANOPY_PARAM_STRUCT(WorldWind, CANOPY_WORLD_WIND)

// windMode World: `wind` sets the wind and the plane (customPlane and plane are not read).
// windMode PlaneSides: customPlane unset, the plane is fixed from the first frame's camera, one tile
// over the visible region at the vegetation's centre depth (plane is then not read).
#define CANOPY_PARAMS(X)                                                                                                \
  X(AnimationMode, animation, AnimationMode::Layers2D, Enum, 0, 1, "Layers2D | PerVertex", "PerVertex needs CanopyDesc.allowPerVertex") \
  X(PerVertexParams, perVertex, {}, Nested, 0, 0, "", "the per-vertex baseline")                                       \
  X(LayerSettings, layers, {}, Nested, 0, 0, "", "depth layers, light and leaf shading, re-slicing, impostors")       \
  X(SimulationParams, simulation, {}, Nested, 0, 0, "", "ignored by a context that shares another's simulation")      \
  X(DynamicsParams, dynamics, {}, Nested, 0, 0, "", "the paper's eq. 1-7")                                              \
  X(CompositeParams, composite, {}, Nested, 0, 0, "", "inverse warp and compositing")                                 \
  X(WindMode, windMode, WindMode::World, Enum, 0, 1, "World | PlaneSides", "how the wind is set (PlaneSides: before 0.8)") \
  X(WorldWind, wind, {}, Nested, 0, 0, "", "the wind in the world (windMode World)")                                   \
  X(bool, customPlane, false, Unchecked, 0, 0, "", "PlaneSides: use `plane` instead of the one fixed from the first camera") \
  X(SimulationPlane, plane, {}, Unchecked, 0, 0, "", "checked (as a SimulationPlane) with customPlane only")
CANOPY_PARAM_STRUCT(CanopyParams, CANOPY_PARAMS)

// ---------------------------------------------------------------------------------------------
// Contexts: the description a context is created from

struct CanopyContext;  // one animated plant or field (opaque)

// How the host's depth target is read and written.
enum class DepthConvention : uint32_t {
  Standard = 0,  // near = 0, far = 1, compared LESS
  Reverse = 1,   // near = 1, far = 0, compared GREATER (reverse-Z, also with an infinite far plane)
};

// Host colour target: any blendable colour-attachment format (UNORM, SRGB, R16G16B16A16_SFLOAT,
// B10G11R11_UFLOAT_PACK32, ...); Canopy blends linear colour, SRGB formats encode on write. Host
// depth: D32_SFLOAT, D16_UNORM, D24_UNORM_S8_UINT or D32_SFLOAT_S8_UINT with SAMPLED usage, single
// sampled (a multisampled host names its resolved depth); the stencil aspect is never written.
// shareSimulationWith: another context on the same Device whose simulation this one follows (one
// wind over a whole scene), stepped once per host frame number, whichever context records first.
// rootCacheDir: Canopy's cache files (the leaf roots, seconds saved on big models, and the
// impostor views) are read and written only in this folder (userCacheFolder() gives the user's);
// empty: no file is read or written. A cache is checked before use (version, key, size, checksum)
// and rebuilt when it does not match; a link, FIFO or folder at a cache's name is never followed
// or waited on (docs/design.md "Files"). Every write is a new file renamed into place.
// cacheMaxBytes: after a write the least recently used cache files beyond it are removed (a single
// cache over it is not written); 0: no cap.
// deviceMemoryBudget: device memory this context may allocate (buffers and images; Canopy's own
// allocator rounds up to 64 MiB blocks); the default fits lavapipe's 2 GiB heap. When the compact
// foliage mesh does not fit beside the other resources (two layer sets included), it stays in host
// memory and every re-slice streams it through a staging ring of about meshStagingRingBytes, a
// slice a frame (a re-slice asked at once then takes several frames; docs/design.md "Layers: mesh
// budget and staging ring"). 0: no limit, the mesh is always resident. Planned for the layer count
// and size at creation.
// instances: the copies of the model the context draws as one vegetation (one set of layers, one
// simulation; the mesh and its leaf roots stored once, the draws instanced): each a model -> world
// transform, a tint and a wind phase. Empty: one copy at the model's origin. Copies outside the view
// are not drawn. With impostors each model's views are baked once and far copies drawn as its
// impostors through their transform and tint. docs/design.md "Instances".
// guardBand: the layer images extend beyond each edge of the targets by this fraction of their
// width and height (rounded to a multiple of 16 pixels; docs/design.md "Layers: guard band"), so a
// camera that turns or strafes between re-slices shows the layers' content from there instead of an
// empty edge, and the error-driven policy does not re-slice while the view stays within them. It
// costs layer memory and fill in proportion: 0.1 draws 1.2 x 1.2 = 1.44 times the pixels.
// allowPerVertex: keeps the model's branch hierarchy (8 bytes a vertex, host and device) and the
// per-vertex pipeline; the mesh must then be resident (createCanopy refuses a model whose mesh
// would be streamed, naming the budget).
#define CANOPY_DESC(X)                                                                                                  \
  X(uint32_t, headerVersion, CANOPY_HEADER_VERSION, Unchecked, 0, 0, "", "leave as is: checked against the library")        \
  X(uint32_t, width, 1024, Closed, 1, 16384, "pixels", "host targets' width")                                          \
  X(uint32_t, height, 768, Closed, 1, 16384, "pixels", "host targets' height")                                         \
  X(VkFormat, colorFormat, VK_FORMAT_R8G8B8A8_UNORM, Unchecked, 0, 0, "", "host colour target (any blendable colour format)") \
  X(VkFormat, depthFormat, VK_FORMAT_D32_SFLOAT, Unchecked, 0, 0, "", "host depth (D32_SFLOAT, D16_UNORM, D24_UNORM_S8_UINT, D32_SFLOAT_S8_UINT)") \
  X(DepthConvention, depthConvention, DepthConvention::Standard, Enum, 0, 1, "Standard | Reverse", "how the host's depth is read and written") \
  X(VkFormat, motionFormat, VK_FORMAT_UNDEFINED, Unchecked, 0, 0, "", "R16G16_SFLOAT / R32G32_SFLOAT; UNDEFINED: no motion output") \
  X(VkFormat, layerFormat, VK_FORMAT_R16G16B16A16_SFLOAT, Unchecked, 0, 0, "", "Canopy's layer images (or R8G8B8A8_UNORM)") \
  X(uint32_t, maxLayers, 8, Closed, 1, 32, "layers", "the most layers CanopyParams may ask for")                      \
  X(uint32_t, minCellSize, 4, Closed, 2, 256, "pixels", "the smallest warp-grid cell CanopyParams may ask for")       \
  X(std::vector<CanopyInstance>, instances, {}, Unchecked, 0, 0, "", "copies of the model placed in the world; empty: one at its origin") \
  X(float, guardBand, 0.1f, Closed, 0, 0.5, "of width, height", "the layers reach this far beyond each edge of the targets (rounded to 16 px; 0: none)") \
  X(SimulationDesc, simulation, {}, Nested, 0, 0, "", "the simulation's grid and history")                             \
  X(CanopyContext*, shareSimulationWith, nullptr, Unchecked, 0, 0, "", "follow this context's simulation")                  \
  X(MaterialSplitOptions, split, {}, Unchecked, 0, 0, "", "rigid vs foliage materials")                                     \
  X(LeafRootOptions, roots, {}, Unchecked, 0, 0, "", "how leaves are found")                                                \
  X(std::string, rootCacheDir, {}, Unchecked, 0, 0, "", "the cache files' folder; empty: none read or written")             \
  X(uint64_t, cacheMaxBytes, 2048ull << 20, Unchecked, 0, 0, "bytes", "cap on the cache files in rootCacheDir; 0: none")   \
  X(Progress, progress, {}, Unchecked, 0, 0, "", "optional: called during createCanopy (\"leaf roots\", \"vertices\")")  \
  X(CanopyParams, params, {}, Unchecked, 0, 0, "", "the initial parameters (checked as setCanopyParams checks them)")       \
  X(uint64_t, deviceMemoryBudget, 1536ull << 20, Unchecked, 0, 0, "bytes", "device memory this context may allocate; 0: no limit") \
  X(uint64_t, meshStagingRingBytes, 64ull << 20, Closed, 1048576, 4294967296.0, "bytes", "a streamed mesh's staging ring (at least the largest chunk per frame in flight)") \
  X(bool, allowPerVertex, false, Unchecked, 0, 0, "", "lets CanopyParams.animation be PerVertex")                           \
  X(ImpostorDesc, impostors, {}, Unchecked, 0, 0, "", "the box hierarchy and its baked views (checked when enable is set)")
struct CanopyDesc {
  CANOPY_DESC(CANOPY_PARAM_FIELD)
};

// Checks each field of a parameter struct against its line of the schema (the check over [min,
// max], finiteness, enumerators); the message names the field as `prefix` + its path, with its
// range and unit. Only what one line states: fields checked together (a layout against
// CanopyDesc.maxLayers, the region split's order, the simulation plane's axes, a warp cell against
// minCellSize, PerVertex against allowPerVertex) are checked by createCanopy and setCanopyParams,
// which run this on the values they are given.
CanopyStatus checkParams(const WindParams& params, const std::string& prefix = "WindParams.");
CanopyStatus checkParams(const Motor& params, const std::string& prefix = "Motor.");
CanopyStatus checkParams(const FluidParams& params, const std::string& prefix = "FluidParams.");
CanopyStatus checkParams(const WaveParams& params, const std::string& prefix = "WaveParams.");
CanopyStatus checkParams(const PushParams& params, const std::string& prefix = "PushParams.");
CanopyStatus checkParams(const SimulationParams& params, const std::string& prefix = "SimulationParams.");
CanopyStatus checkParams(const SimulationDesc& params, const std::string& prefix = "SimulationDesc.");
CanopyStatus checkParams(const RegionSplit& params, const std::string& prefix = "RegionSplit.");
CanopyStatus checkParams(const ImpostorSettings& params, const std::string& prefix = "ImpostorSettings.");
CanopyStatus checkParams(const ImpostorDesc& params, const std::string& prefix = "ImpostorDesc.");
CanopyStatus checkParams(const LayerSettings& params, const std::string& prefix = "LayerSettings.");
CanopyStatus checkParams(const DynamicsParams& params, const std::string& prefix = "DynamicsParams.");
CanopyStatus checkParams(const CompositeParams& params, const std::string& prefix = "CompositeParams.");
CanopyStatus checkParams(const SimulationPlane& params, const std::string& prefix = "SimulationPlane.");
CanopyStatus checkParams(const CanopyPusher& params, const std::string& prefix = "CanopyPusher.");
CanopyStatus checkParams(const PerVertexParams& params, const std::string& prefix = "PerVertexParams.");
CanopyStatus checkParams(const WorldWind& params, const std::string& prefix = "WorldWind.");
CanopyStatus checkParams(const CanopyParams& params, const std::string& prefix = "CanopyParams.");
CanopyStatus checkParams(const CanopyDesc& params, const std::string& prefix = "CanopyDesc.");

// ---------------------------------------------------------------------------------------------
// Statistics (canopyStats)

struct LayerStats {
  double preprocessMs = 0;    // material split + leaf roots (or cache read)
  bool rootCacheHit = false;
  std::string rootCacheNote;  // why the cache was not used, or where it was written
  uint32_t leafCount = 0;
  uint32_t plants = 1;        // plants of the model (eq. 7 per plant: DynamicsParams.roots; each copy is one more)
  uint32_t species = 1;       // models in the vegetation (CanopySpecies), each stored once
  uint64_t foliageTriangles = 0, rigidTriangles = 0;
  bool singlePass = false;    // the draw mode in use
  // The layer images' size, pixels: the targets' plus the guard band on each side (CanopyDesc.guardBand).
  uint32_t layerWidth = 0, layerHeight = 0, guardX = 0, guardY = 0;
  uint64_t viewUpdates = 0;   // frames seen
  uint64_t rebuilds = 0;      // of which re-sliced the layers
  std::string lastRebuildReason;
  double lastPlacementMs = 0; // CPU time of the last placement
  uint32_t meshChunks = 0;    // draws per layer rebuild (compact mesh chunks, foliage + rigid)
  uint64_t meshBytes = 0;     // the compact mesh: vertices, 16-bit indices, root tables
  // Whether the compact mesh is on the device (CanopyDesc.deviceMemoryBudget); when not, it stays in
  // host memory and every re-slice streams it through a staging ring of meshRingBytes.
  bool meshResident = true;
  uint64_t meshRingBytes = 0;
  // Spread re-slicing (LayerSettings.rebuildBudgetMs):
  uint32_t spreadPhase = 0;          // 0 idle, 1 placing (CPU), 2 drawing the new set, 3 cross-fading
  uint64_t spreadRebuilds = 0;       // spread re-slices completed
  uint64_t outrunSpreads = 0;        // spread re-slices a moving camera outran, replaced by one at once
  uint64_t pacedRebuilds = 0;        // re-slices of a moving camera drawn in even slices (LayerSettings.pacedReslices)
  uint32_t lastSpreadFrames = 0;     // frames the last completed one took, placement to last fade step
  uint64_t lastSliceTriangles = 0;   // triangles drawn by the last drawing frame
  uint64_t maxSliceTriangles = 0;    // the most one drawing frame of the last (or running) one drew
  double trianglesPerMs = 0;         // the drawing-rate estimate that sizes the slices (measured)
  float crossFade = 1.0f;            // the newest set's share of the visible layers, [0, 1]
  // Impostors (CanopyDesc.impostors): the box hierarchy, what was baked, and the last re-slice.
  uint32_t impostorBoxes = 0;        // boxes in the hierarchy
  uint32_t impostorBakedBoxes = 0;   // of which have views
  uint32_t impostorTilePixels = 0;   // the views' side after the budget
  uint64_t impostorBytes = 0;        // the views' colour and depth (the atlas as allocated)
  uint32_t impostorViewsPerBox = 0;  // 6 or 12 (ImpostorDesc.views)
  uint64_t impostorBytesPerBox = 0;  // a box's views: impostorViewsPerBox x tile^2 x 8 bytes
  double impostorBakeMs = 0;         // wall clock of the bake (creation), or of reading its cache
  // The views' file cache (CanopyDesc.rootCacheDir, beside the leaf roots', for a model with a
  // path): whether it was read, else why not and whether it was written.
  bool impostorCacheHit = false;
  std::string impostorCacheNote;
  uint32_t lastImpostors = 0;        // boxes drawn as impostors by the last re-slice
  uint32_t lastFadingBoxes = 0;      // of which inside the transition band
  uint64_t lastDrawnTriangles = 0;   // foliage triangles the last re-slice drew
  uint32_t lastImpostorCopies = 0;   // copies with a box drawn as an impostor (or leaves left out) by the last re-slice
  // Instances (CanopyDesc.instances): how many, and how many the last placement found in view.
  uint32_t instances = 0, lastVisibleInstances = 0;
  uint32_t lastVisibleSpecies = 0;  // species with a copy in the last placement's view
};
struct SimulationStats {
  uint64_t steps = 0;
  uint32_t lastWaveSubsteps = 0;
  uint32_t lastDiffuseSweeps = 0;
  uint32_t dispatchesPerStep = 0;
  double clampedSeconds = 0.0;  // oscillator time dropped by the maxSubsteps clamp (frame hitches)
};
struct CanopyStats {
  uint64_t frames = 0;
  bool layersRebuilt = false;        // the last frame re-sliced the layers
  uint64_t resourceGeneration = 0;   // bumps when Canopy's resources were recreated
  uint64_t internalGraphBuilds = 0;  // recordCanopy() graph (re)compilations
  uint64_t pendingReleases = 0;      // objects waiting for their frames to complete (device-wide)
  // Device memory of Canopy's device object, bytes (a shared device counts every context on it):
  // live buffers and images, their highest total so far, and the memory blocks Canopy allocated
  // (0 when the host's DeviceMemoryAllocator provides the memory).
  uint64_t deviceBytes = 0, peakDeviceBytes = 0, deviceBlockBytes = 0;
  // recordCanopyShadow: calls that drew the vegetation's shadow, and calls between updates
  // (CanopyShadowInputs.updateInterval) that only moved the map's state.
  uint64_t shadowUpdates = 0, shadowSkips = 0;
  // setCanopyPushers: of the last frame's pushers, those mapped onto the plane, those outside its
  // domain and those behind the camera (these two do nothing).
  uint32_t pushersMapped = 0, pushersOutside = 0, pushersBehind = 0;
  // The composite of the last frame ran on the tiled compute path (the fast one). False: the
  // full-screen fragment path (about 10x dearer on lavapipe) because CompositeParams.path is
  // Fragment, a debug view is on, or the device lacks what the compute path needs
  // (compositeComputeAvailable: VK_FORMAT_R32G32B32A32_SFLOAT as a linearly filtered storage image).
  bool compositeCompute = false, compositeComputeAvailable = false;
  LayerStats layers;
  SimulationStats simulation;
};

}  // namespace canopy
