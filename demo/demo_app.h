#pragma once
// canopy-demo's pieces shared by the headless and the window mode: the options, the scene, and a
// small "host engine" that embeds Canopy through Canopy's render graph (path 1): its own clear,
// Canopy's passes, then a copy of the frame for the PNG files or a blit to the swapchain image,
// all ordered by one rg::RenderGraph (no hand-placed barriers).
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "demo/cache_cli.h"
#include "engine/device.h"
#include "tools/own_device.h"
#include "engine/memory.h"
#include "engine/render_graph.h"
#include "engine/timing.h"
#include "render/canopy.h"
#include "tools/camera_paths.h"
#include "tools/scene_generator.h"

namespace canopy::demo {

enum class PusherPath { None, Line, Circle };  // --pusher

// A scene file's species and copies (--scene-file; docs/scene-files.md), loaded by loadScene.
struct SceneCopies {
  std::vector<VegetationModel> models;  // per species
  std::vector<SpeciesModel> species;    // the models with their wind response (pointing into `models`)
  std::vector<CanopyInstance> instances;
};

struct Options {
  // Scene
  std::string gltf;                    // a glTF/GLB file instead of a generated scene
  std::string sceneFile;               // a scene file (species and copies) instead of one model
  std::shared_ptr<const SceneCopies> copies;  // what loadScene read from sceneFile (main sets it)
  MaterialSplitOptions split;          // --rigid / --foliage overrides of the default material rule
  bool attachRoots = LeafRootOptions{}.attachRoots;  // --paper-roots: false
  RigidMotion rigidMotion = LayerSettings{}.rigidMotion;  // --rigid-motion
  cli::CacheOptions cache;             // where the caches of a --gltf model go (demo/cache_cli.h)
  std::string cacheFolder;             // resolved by main(); empty: no cache
  SceneKind scene = SceneKind::Shrub;
  uint64_t faces = 80000;
  uint32_t seed = 1;
  // Method
  std::string layout = "5(3-1-1)";
  // The wind: the library's defaults (one set). The world wind (CanopyParams.wind) unless one of
  // --wind, --strength, --frequency, --modulation, --gust asks for the plane's sides (PlaneSides).
  Float3 windDirection = WorldWind{}.direction;  // --wind-dir: where it blows toward, world space
  float windSpeed = WorldWind{}.speed;           // --wind-speed, m/s
  float gustIntensity = WorldWind{}.gustIntensity;
  float gustFrequency = WorldWind{}.gustFrequency;
  float turbulence = WorldWind{}.turbulence;
  float sway = WorldWind{}.sway;                 // --sway: share of a plant's height per m/s
  bool planeSides = false;                       // WindMode::PlaneSides (the options below)
  uint32_t windSides = WindParams{}.sides;
  float windStrength = WindParams{}.strength;    // domain units/s
  float windFrequency = WindParams{}.frequency;  // Hz
  float windModulation = WindParams{}.modulation;  // b of strength * (a + b sin(2 pi f t)), a = 1
  float windGust = WindParams{}.gust;            // relative gust amplitude
  float yawDegrees = 0.0f;             // --yaw: the camera's start around the vegetation's vertical (0: the default view)
  float warmupSeconds = 2.0f;          // headless: simulation time run before the first written frame
  DelayMode delay = DelayMode::Exact;
  CompositeDebugView debug = CompositeDebugView::None;
  // The 2D method or the per-vertex baseline (Habel), on the same scene; the window can switch
  // (key M) when the context allows both, which it does in window mode and with per-vertex.
  AnimationMode method = AnimationMode::Layers2D;
  PerVertexWind perVertexWind = PerVertexWind::KaimalField;  // PerVertexParams.wind
  // Lluch et al.'s impostors for the far boxes (LayerSettings.impostors; docs/design.md
  // "Impostors"); the window cycles the mode (key I) and the debug view (key B).
  ImpostorMode impostors = ImpostorMode::Off;
  float impostorPixels = 64.0f;        // ImpostorSettings.switchPixels
  bool impostorDebug = false;          // colour leaves and impostors by their box's level
  ImpostorViews impostorViews = ImpostorViews::Diagonal6;            // ImpostorDesc.views
  ImpostorShape impostorShape = ImpostorShape::CrossedPolygons;      // ImpostorSettings.shape
  // Light and leaf shading (LayerSettings; docs/design.md "Layers: leaf shading")
  Float3 light = LayerSettings{}.lightDirection;     // towards the light, world space
  Float3 lightColor = LayerSettings{}.lightColor;
  float ambient = LayerSettings{}.ambient;
  float leafIor = LayerSettings{}.leafRefractiveIndex;
  float leafRoughness = LayerSettings{}.leafRoughness;
  bool overrideLeafRoughness = false;  // --leaf-roughness given: it overrides the materials' own
  float leafTransmission = LayerSettings{}.leafTransmission;
  bool translucency = true;
  bool bilinear = true;                // CompositeParams.bilinear (--nearest: false)
  float sharpness = CompositeParams{}.sharpness;  // CompositeParams.sharpness
  float maxStretch = DynamicsParams{}.maxStretch;  // DynamicsParams.maxStretch
  bool lightSheet = false;             // also write light_sheet.png: lit from the front, from behind, from behind without translucency
  // The vegetation's shadow (recordCanopyShadow; docs/design.md "Shadows"): a grey ground under the
  // scene lit by the sun (--light) through a shadow map Canopy draws every frame; with
  // debugShadowMap each written frame's map also goes to shadow_NNNN.png.
  bool shadows = false;
  bool debugShadowMap = false;
  // A sphere walking through the scene (setCanopyPushers; docs/design.md "Pushers"): along a line
  // across the view or around a circle, over the written frames; pusher_path.txt holds its screen
  // path (--compare-frames then measures the difference against a run without it).
  PusherPath pusher = PusherPath::None;
  // Output
  uint32_t width = 640, height = 480;
  uint32_t frames = 60;
  float fps = 30.0f;                   // simulation steps per second of animation (dt = 1 / fps)
  CameraMotion camera = CameraMotion::Still;  // tools/camera_paths.h
  float orbitDegrees = 60.0f;          // orbit path: total yaw over the sequence (unless --degrees-per-frame)
  float degreesPerFrame = 0.25f;       // orbit, turn, zoom, walk (tools/camera_paths.h CameraPath)
  bool degreesGiven = false;
  float radiiPerFrame = 0.005f;        // dolly, strafe, walk
  float swingDegrees = 5.0f;           // turn, zoom, walk: either side of the start
  ReslicePolicy reslice = ReslicePolicy::OnViewChange;  // --reslice auto | every-frame
  std::string compareA, compareB;      // --compare-frames: two output folders measured against each other
  std::string foliageWind, foliageStill;  // --measure-foliage: a run with wind and the same run without
  float resliceErrorPixels = LayerSettings{}.errorThresholdPixels;  // LayerSettings.errorThresholdPixels: the reprojection error that re-slices
  float rebuildBudgetMs = 4.0f;        // LayerSettings.rebuildBudgetMs: re-slices spread over frames (0: at once)
  float guardBand = 0.1f;              // CanopyDesc.guardBand: the layers reach this fraction beyond each edge
  float depthSearchSteps = float(CompositeParams{}.depthSearchSteps);  // CompositeParams.depthSearchSteps (0: the slabs' planes alone)
  float halfResolutionLayers = 0.0f;  // LayerSettings.halfResolutionLayers: the farthest this many layers at half resolution
  float deviceBudgetMiB = 1536.0f;     // CanopyDesc.deviceMemoryBudget (0: no limit)
  float ringMiB = 64.0f;               // CanopyDesc.meshStagingRingBytes
  std::string outDir = "demo_out";
  bool mp4 = true;
  // Window mode
  bool window = false;
  bool vsync = true;
  uint32_t resizeAt = 0;               // window: resize the window after this many frames (tests)
  std::string screenshot;              // window: write the last presented frame here (read back from the swapchain)
  // Both
  bool validate = false;
  std::string device;
  std::string injectFault;  // "oom:N" / "lost:N" (tools/fault_loader.h), empty: none
};

// --pusher: the sphere's world position, radius and velocity at written frame `i` of `frames`,
// over the bounds of the scene (a line across the view of frame 0's camera, or a circle), bending
// the grass twice as far as the wind of `windStrength` (domain units/s).
CanopyPusher pusherAt(PusherPath path, const glm::vec3& boundsMin, const glm::vec3& boundsMax, const glm::vec3& cameraRight,
                      uint32_t i, uint32_t frames, float fps, float windStrength);

// Whether the context is created with both methods (CanopyDesc.allowPerVertex; the scene then
// carries its branch hierarchy).
inline bool bothMethods(const Options& o) { return o.window || o.method == AnimationMode::PerVertex; }
// Whether the context bakes impostors (CanopyDesc.impostors; the scene then carries its boxes).
inline bool withImpostors(const Options& o) { return o.window || o.impostors != ImpostorMode::Off || o.impostorDebug; }

// Parses the command line. Returns 0 to run, 1 when --help was printed, 2 on an error (the
// one-line reason is in *error).
int parseOptions(int argc, char** argv, Options* out, std::string* error);
void printHelp();

// The scene the options name (generated or loaded), with a progress line for big ones. With a
// scene file, *copies gets its species and copies and *model only their world bounds (the camera's).
Status loadScene(const Options& o, VegetationModel* model, std::string* label, SceneCopies* copies);

// Camera: orbit around the model's bounds.
struct CameraRig {
  float yaw = 20.0f, pitch = 12.0f, distance = 1.0f, fov = 40.0f;
};
CameraRig defaultRig(const Options& o);
// The wind the options set, in words (the run's summary), and its speed in the simulation's domain
// units/s (the pusher's bend and the velocity view's scale).
std::string windText(const Options& o);
float domainWindSpeed(const Options& o);
LayerView cameraView(const CameraRig& rig, const VegetationModel& model, uint32_t width, uint32_t height);
// The headless run's camera path (--camera and its speeds), starting at `rig`.
CameraPath cameraPathOf(const Options& o, const CameraRig& rig);
// The host's clear colour as the sRGB frames store it (sky; water for the kelp scene).
glm::vec3 skySrgb(const Options& o);

CanopyParams paramsFrom(const Options& o, const CanopyParams& base);

// The host: targets, Canopy context, the frame graph and a GPU timer.
struct Host {
  Device* device = nullptr;
  CanopyContext* canopy = nullptr;
  uint32_t width = 0, height = 0;
  Image color, depth;
  // Frames in flight: frame i uses slot i % kFramesInFlight (its read-back buffer and timer), and
  // the loops wait only for that slot's previous frame, never for the device.
  static constexpr uint32_t kFramesInFlight = 2;
  Buffer readback[kFramesInFlight];        // width x height RGBA8, host-visible
  GpuTimer timer[kFramesInFlight];
  rg::ResourceId readbackId = rg::kInvalidResource;
  rg::RenderGraph graph;
  rg::ResourceId presentTarget = rg::kInvalidResource;  // imported swapchain image (window mode)
  uint64_t graphGeneration = ~0ull;
  bool wantsReadback = false;
  VkFormat presentFormat = VK_FORMAT_UNDEFINED;
  glm::vec4 clear{0.0f, 0.0f, 0.0f, 1.0f};  // linear
  glm::vec3 clearSrgb{0.0f};                 // the same colour as the sRGB target stores it
  // --shadows (docs/design.md "Shadows"): the sun's shadow map Canopy draws after each frame, the
  // ground the next frame draws with it (before Canopy's passes), and per slot the map read back.
  struct Shadow {
    static constexpr uint32_t kSize = 512;
    bool on = false, readback = false;
    Image map;                              // D32, kSize x kSize; rests sampled by the fragment stage
    VkSampler sampler = VK_NULL_HANDLE;
    GraphicsPipeline ground;                // demo/shaders/demo_ground.*
    Buffer groundFrame;                     // the quad, the light and the albedo (the shaders' GroundBuf)
    glm::mat4 light{1.0f};                  // world -> the light's clip space
    glm::vec3 groundCenter{0.0f};
    float groundHalf = 1.0f;
    glm::mat4 viewProj{1.0f};               // this frame's camera (the ground's draw)
    Buffer mapReadback[kFramesInFlight];    // kSize^2 floats
    rg::RenderGraph copy;                   // the map into a slot's buffer
    rg::ResourceId copyTarget = rg::kInvalidResource;
  } shadow;
};

// Creates targets + context at width x height. `presentFormat` != UNDEFINED adds a blit to an
// imported swapchain image (bound per frame); `readback` adds the copy for PNG output.
Status createHost(Device& device, const VegetationModel& model, const Options& o, uint32_t width, uint32_t height,
                  bool readback, VkFormat presentFormat, Host* out);
// A new size (window resize) or swapchain format: the host's targets are recreated and Canopy's
// context resized (resizeCanopy), so the scene is not prepared again.
Status resizeHost(Host& host, uint32_t width, uint32_t height, VkFormat presentFormat);
void destroyHost(Host& host);
// Records one frame (Canopy's frame prepared with `frame`) into `cmd`; `present` is the swapchain
// image for this frame in window mode.
// `slot` is the frame-in-flight slot (read-back buffer and timer) the frame uses.
Status recordHostFrame(Host& host, VkCommandBuffer cmd, const CanopyFrame& frame, const Image* present, uint32_t slot);
// The pixels of the frame recorded in `slot`, after its submission completed (RGBA8, rows top to
// bottom, alpha = 255).
void readPixels(const Host& host, uint32_t slot, std::vector<uint8_t>* rgba);
// With --shadows and a read-back: the shadow map of the frame recorded in `slot` (depth, 0 near the
// sun, kSize^2 floats, rows top to bottom of the light's view), after its submission completed.
void readShadowMap(const Host& host, uint32_t slot, std::vector<float>* depth);

// The demo's own frames in flight: a command buffer, a fence and an acquire semaphore per slot.
struct FrameRing {
  VkCommandPool pool = VK_NULL_HANDLE;
  VkCommandBuffer cmds[Host::kFramesInFlight] = {};
  VkFence fences[Host::kFramesInFlight] = {};
  VkSemaphore acquired[Host::kFramesInFlight] = {};
  bool pending[Host::kFramesInFlight] = {};  // submitted, not yet waited for
};
Status createFrameRing(Device& device, FrameRing* out);
// Destroys the ring; its submitted frames must have completed.
void destroyFrameRing(Device& device, FrameRing& ring);
// Waits for the frame submitted from `slot`, if any, and frees the slot (its fence reset);
// *waited (optional) says whether there was one. The headless and the windowed demo retire alike.
Status waitFrameSlot(Device& device, FrameRing& ring, uint32_t slot, bool* waited = nullptr);
// Records the host's frame `frame` into the slot's command buffer: reset, begin (one submit),
// recordHostFrame, end. The caller submits it (with its fence) and marks the slot pending.
Status recordFrameSlot(Host& host, FrameRing& ring, uint32_t slot, const CanopyFrame& frame, const Image* present);

// Per-pass timing: medians over the frames added.
struct TimingLog {
  std::map<std::string, std::vector<double>> passMs;
  std::vector<double> wallMs;
  std::vector<std::string> order;  // pass names in first-seen order
  void add(const std::vector<PassTiming>& passes, double wall);
  std::string summary(const std::string& title) const;
};

}  // namespace canopy::demo
