#pragma once
#include <algorithm>
#include <chrono>
#include <functional>
#include <cstdint>
#include <string>
#include <vector>

#include "render/canopy.h"
#include "render/model.h"
#include "tools/camera_paths.h"

namespace canopy {
struct Device;
namespace bench {
// The median of samples (the upper one of an even count; 0 for none): the benchmarks' figure of record.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Wall clock in milliseconds (steady), for the benchmarks' frame and step times.
inline double nowMs() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

int runSimBench(Device& dev, const std::vector<uint32_t>& sizes, int frames, bool detail);
// Leaf-root preprocessing and layer rebuilds for synthetic leaf clouds of the given face counts.
int runLayersBench(Device& dev, const std::vector<uint64_t>& faceCounts, int rebuilds, const std::string& layout,
                   uint32_t width, uint32_t height);
// Per-frame animation cost (delay + warp + composite, and the whole still-camera frame) for leaf
// clouds (scene empty) or generated scenes (render/scene_generator.h) of the given face counts and
// the given layouts, then the compositing levers side by side.
int runAnimBench(Device& dev, const std::vector<uint64_t>& faceCounts, const std::vector<std::string>& layouts,
                 int frames, uint32_t width, uint32_t height, const std::string& scene);
// Soak: `frames` frames with random parameters and periodic re-slicing; prints NaN/Inf counts,
// RSS, device-allocation and frame-time growth. With `check`, returns 1 when any of them is bad.
int runSoakBench(Device& dev, int frames, int rebuildEvery, bool check);

// Table 1 (issue 15): face counts x 3(1-1-1)/5(3-1-1) x still/orbiting camera beside the paper's
// FPS, baselines side by side, optional scaling series (CSV) and a JSON file of all of it.
struct Table1Options {
  std::vector<uint64_t> faces = {80000, 10000000};
  std::vector<uint64_t> seriesFaces = {80000, 1000000, 10000000};
  std::string scene = "shrub";
  int frames = 30;
  int pairFrames = 150;  // frames per context in the alternated face-count comparison
  uint32_t width = 1024, height = 768;
  float orbitDegrees = 0.25f;  // camera turn per frame in the orbit and every-frame rows (issue 34: 0.25)
  bool series = false;
  std::string csvDir;         // series CSV files (empty: none)
  std::string json = "bench_table1.json";
  uint64_t deviceMemoryBudget = CanopyDesc{}.deviceMemoryBudget;  // CanopyDesc.deviceMemoryBudget (0: none)
  float guardBand = CanopyDesc{}.guardBand;  // CanopyDesc.guardBand of every row
};
int runTable1Bench(Device& dev, const Table1Options& options);

// Re-slicing (issue 16): at once vs spread over frames with `budgetMs` (face counts up to
// `spreadMaxFaces`), per face count.
int runRebuildBench(Device& dev, const std::vector<uint64_t>& faceCounts, const std::string& scene, float budgetMs,
                    int rebuilds, uint32_t width, uint32_t height, uint64_t spreadMaxFaces, uint64_t deviceMemoryBudget);

// The 2D method against the per-vertex wind baseline (issue 17), same scene, context, resolution
// and camera, per face count; `csvPath` (empty: none) for scripts/plot_bench.py --pervertex.
int runPerVertexBench(Device& dev, const std::vector<uint64_t>& faceCounts, const std::string& scene, int frames,
                      uint32_t width, uint32_t height, uint64_t deviceMemoryBudget, const std::string& csvPath);
// Impostors (issue 18): re-slice time with and without Lluch et al.'s impostors (off, far region,
// by projected size, alternated) and the far layers' image difference, per face count; with
// `imageDir` (empty: none) the far layers and the debug view as PNG.
// The moving camera (docs/design.md "Moving camera: paths and the world-lock measure"): per camera
// path, the re-slicing policy against re-slicing every frame, frame by frame (world-lock error,
// frame times), beside the still camera of the same run.
struct CameraBenchOptions {
  std::vector<uint64_t> faces = {80000};
  std::string scene = "shrub";
  std::vector<CameraMotion> paths = {CameraMotion::Orbit, CameraMotion::Dolly, CameraMotion::Strafe, CameraMotion::Turn,
                                     CameraMotion::Zoom};
  int frames = 60;
  uint32_t width = 1024, height = 768;
  float degreesPerFrame = 0.25f, radiiPerFrame = 0.005f, swingDegrees = 5.0f;  // tools/camera_paths.h
  float budgetMs = 4.0f;  // the policy side's LayerSettings.rebuildBudgetMs (0: re-slice at once)
  float errorPixels = LayerSettings{}.errorThresholdPixels;  // the policy side's LayerSettings.errorThresholdPixels
  std::string csvPath;    // per-frame rows (faces, path, frame, both frame times, re-slice, world-lock error); "" none
  bool crossFade = true;  // the cross-fade's coverage at one camera (a light change, a layout change)
  float guardBand = CanopyDesc{}.guardBand;  // the policy side's CanopyDesc.guardBand (the every-frame side: 0)
  uint32_t halfResolutionLayers = LayerSettings{}.halfResolutionLayers;  // every side's (the still frame's too)
  uint32_t depthSearchSteps = CompositeParams{}.depthSearchSteps;  // the policy side's (0: the slabs' planes alone)
};
int runCameraBench(Device& dev, const CameraBenchOptions& options);

// Pacing (issue 79; bench/bench_pacing.cpp): per path and face count, a long run's frame times
// (median, p95, p99, max, stutter frames) beside the still frame, the work counted per frame, and
// the world lock and the pop against re-slicing every frame.
struct PacingOptions {
  std::vector<uint64_t> faces = {80000, 1000000};
  // walk: through the field; species-walk and third-person: the scene file `sceneFile`, walked, and
  // followed 2 m high behind a character walking and turning
  std::vector<std::string> paths = {"orbit", "dolly", "strafe", "turn", "walk", "species-walk", "third-person"};
  std::string sceneFile = "demo/scenes/six_species.json";
  std::vector<float> degreesPerFrame = {0.25f, 0.5f};  // dolly, strafe, walk: 0.005 radii a frame per 0.25 degrees
  int frames = 300;
  uint32_t width = 1024, height = 768;
  float budgetMs = -1.0f;  // LayerSettings.rebuildBudgetMs; < 0: the default
  uint32_t predictFrames = LayerSettings{}.predictFrames;  // LayerSettings.predictFrames of the policy side
  bool paced = LayerSettings{}.pacedReslices;  // LayerSettings.pacedReslices of the policy side (--paced on|off)
  bool reference = true;   // the every-frame side (world lock, the pop); off: timing and counts only
  std::string json;        // "" none
};
int runPacingBench(Device& dev, const PacingOptions& options);

// The layer-count study (issue 36): each layout's animated frames against the same wind drawn with
// `reference` layers, on a generated scene and optionally a glTF file (bench/bench_layer_count.cpp).
struct LayerCountOptions {
  std::string scene = "shrub";
  uint64_t faces = 80000;
  std::string gltf;  // "" none
  std::vector<std::string> layouts = {"1", "2", "3", "5", "7", "9", "3(1-1-1)", "5(3-1-1)"};
  std::string reference = "16";
  int frames = 90, skip = 15;  // frames drawn; the first `skip` (the wind rising from rest) not compared
  uint32_t width = 512, height = 384;
  float strength = 1.5f;  // SimulationParams.wind.strength, domain units/s
  std::string csvPath;    // a row per model and layout; "" none
};
int runLayerCountBench(Device& dev, const LayerCountOptions& options);

// The translucency light sheet (issue 36, seed 004 Figure 5's layout): a leaf's unlit side with the
// light behind it from steep to grazing, Habel's translucency above the diffuse BTDF, as one PNG.
int runLeafSheet(Device& dev, const std::string& outPath);

int runImpostorBench(Device& dev, const std::vector<uint64_t>& faceCounts, const std::string& scene, int rebuilds,
                     uint32_t width, uint32_t height, const std::string& imageDir);
// Species (issue 53): six species against one at equal placed faces, mesh memory against copies,
// the first frame with and without recordCanopyLoad.
int runSpeciesBench(Device& dev, uint64_t facesPerSpecies, uint32_t copiesPerSpecies, int frames, uint32_t width, uint32_t height);
// Shadows (issue 54): the frame without a shadow and with an update every 1, 2 and 4 frames, and the
// update's own cost, for a shrub of each face count and a six-species forest.
// canopy-bench counters: the work per frame kind, counted (bench/bench_counters.cpp).
int runCounterBench(Device& dev, const std::vector<uint64_t>& faceCounts, const std::vector<std::pair<uint32_t, uint32_t>>& sizes,
                    const std::string& jsonPath);
// canopy-bench pushers: 32 pushers against none on the field scene (bench/bench_pushers.cpp).
int runPusherBench(Device& dev, uint64_t faces, int frames, uint32_t width, uint32_t height);
// canopy-bench picture (issue 67): each frame with wind against the same frame without, 2D and
// per-vertex, per scene x camera path x size x wind (bench/bench_picture.cpp).
struct PictureOptions {
  // "field", "shrub", ... (generated), "tree:PATH" (a glTF plant), "file:PATH" (a scene file); a
  // missing file is skipped with a message.
  std::vector<std::string> scenes = {"field", "shrub", "tree:../shared/assets/quaternius_CommonTree_1/CommonTree_1.glb",
                                     "file:demo/scenes/six_species.json"};
  std::vector<CameraMotion> paths = {CameraMotion::Still, CameraMotion::Walk, CameraMotion::Orbit};
  std::vector<std::pair<uint32_t, uint32_t>> sizes = {{640, 480}, {1280, 720}};
  std::vector<std::string> winds = {"breeze", "gale"};  // WorldWind.speed's default, galeFactor x it
  std::vector<AnimationMode> methods = {AnimationMode::Layers2D, AnimationMode::PerVertex};
  uint32_t frames = 10;               // measured frames per run (after the demo's 2 s warm-up)
  float orbitDegreesPerFrame = 9.0f;  // the orbit path's turn
  float galeFactor = 3.0f;
  std::string json = "bench_picture.json", table;  // "" none
  bool check = false;                 // exit 1 when a 2D run is outside issue 67's bounds
};
int runPictureBench(Device& dev, const PictureOptions& options);
// canopy-bench plants (issue 77): real plants in a breeze and a gale, the 2D method beside the
// per-vertex baseline: the attachment gap, the sway, the trunk's base, bare rigid pixels in the
// crown (bench/bench_plants.cpp).
struct PlantsOptions {
  // "tree:PATH" (a glTF plant; a missing file is skipped with a message) or a generated scene's name.
  std::vector<std::string> plants = {
      "tree:../shared/assets/quaternius_megakit_common_tree_3/CommonTree_3.gltf",
      "tree:../shared/assets/quaternius_CommonTree_1/CommonTree_1.glb",
      "tree:../shared/assets/quaternius_PineTree_1/PineTree_1.glb",
      "tree:../shared/assets/sketchfab_pine_ps1_wersaus33/scene.gltf",
      "tree:../shared/assets/DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf",
      "tree:../shared/assets/fern_02/fern_02.glb",
      "tree:../shared/assets/kaykit_tree_1_c/Tree_1_C_Color1.gltf",
      "tree:../shared/assets/kenney_nature_palm_tall/tree_palmTall.glb",
      "tree:../shared/assets/polypizza_flower_bushes/flower_bushes.glb",
      "tree"};
  std::vector<std::string> winds = {"breeze", "gale"};  // WorldWind.speed's default, galeFactor x it
  uint32_t width = 640, height = 480;
  uint32_t frames = 90;  // measured frames per run (after the warm-up)
  float warmup = 2.0f;   // seconds of animation run before the first measured frame (the demo's default)
  float galeFactor = 3.0f;
  // The breeze's sway pass: both methods at this size over this many frames after the warm-up (0: none).
  uint32_t swayFrames = 1800, swayWidth = 320, swayHeight = 240;
  bool before = false;   // as before issue 77: RigidMotion::Still and the paper's leaf roots
  std::string json = "bench_plants.json", table;  // "" none
  bool check = false;    // exit 1 outside issue 77's bounds
};
int runPlantsBench(Device& dev, const PlantsOptions& options);
int runShadowBench(Device& dev, const std::vector<uint64_t>& faceCounts, int frames, uint32_t width, uint32_t height, uint32_t mapSize);
}
}  // namespace canopy
