// canopy-bench: Canopy's benchmark (speed is measured here, never asserted in tests).
//   canopy-bench [sim] [layers] [anim] [--sizes 64,128,256] [--frames N] [--detail]
//                [--faces 80000,10000000] [--rebuilds N] [--layers 5(3-1-1)] [--device NAME]
//   canopy-bench soak [--frames N] [--rebuild-every N] [--check]
//   canopy-bench table1 [--faces 80000,10000000] [--scene shrub] [--frames N] [--size 1024x768]
//                [--orbit DEG] [--pair-frames N] [--series] [--series-faces LIST] [--csv-dir DIR] [--json FILE]
//   canopy-bench rebuild [--faces 80000,10000000] [--scene shrub] [--budget MS] [--rebuilds N] [--size WxH]
//                [--spread-max-faces N] [--device-budget MIB]
//   canopy-bench pervertex [--faces 80000,1000000,10000000] [--scene shrub] [--frames N] [--size WxH] [--csv FILE]
//   canopy-bench impostors [--faces 10000000] [--scene field] [--rebuilds N] [--size WxH] [--images DIR]
//   canopy-bench layercount [--faces 80000] [--scene shrub] [--gltf FILE] [--frames N] [--size WxH] [--csv FILE]
//   canopy-bench camera [--faces 80000] [--scene shrub] [--paths orbit,dolly,...] [--frames N] [--size WxH]
//                [--degrees-per-frame D] [--radii-per-frame R] [--swing D] [--budget MS] [--reslice-error PX]
//                [--csv FILE] [--no-cross-fade] [--half-res N] [--depth-search N]
//   canopy-bench species [--faces 8000] [--copies N] [--frames N] [--size WxH]
//   canopy-bench shadows [--faces 80000,1000000] [--frames N] [--size WxH] [--map N]
//   canopy-bench pushers [--faces 80000] [--frames N] [--size WxH]
//   canopy-bench counters [--faces 80000,1000000,10000000] [--size WxH] [--json FILE]
//   canopy-bench picture [--scenes LIST] [--paths LIST] [--picture-sizes LIST] [--winds LIST] [--methods LIST]
//                [--frames N] [--json FILE] [--table FILE] [--check]
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "engine/device.h"
#include "tools/own_device.h"
#include "demo/cli.h"

using namespace canopy;

static int usage(const char* why) {
  if (why) std::fprintf(stderr, "canopy-bench: %s\n", why);
  std::fprintf(why ? stderr : stdout,
               "usage: canopy-bench [sim] [layers] [options]\n"
               "  sim            simulation step per grid size, GPU vs CPU reference (default section)\n"
               "  layers         leaf-root preprocessing and layer rebuilds, one draw vs n draws\n"
               "  anim           per-frame delay + warp + composite and whole frame, 3 vs 5 layers, levers\n"
               "  soak           long run: random parameters every frame, re-slicing every --rebuild-every frames;\n"
               "                 NaN/Inf, RSS, device allocations, frame time (--frames default 100000)\n"
               "  rebuild        re-slicing: at once vs spread over frames (--budget MS, default 4), per face count;\n"
               "                 spread only up to --spread-max-faces (default 10000000)\n"
               "  pervertex      the 2D method against the per-vertex wind baseline (Habel) on the same scene and\n"
               "                 camera, per face count (default 80000,1000000,10000000), as ratios; --csv FILE\n"
               "  impostors      Lluch et al.'s impostors: re-slice time off / far region / by projected size and the\n"
               "                 far layers' image difference, per face count (default 10000000, --scene field,\n"
               "                 --rebuilds 5, --size 1024x768); --images DIR writes the far layers and the debug view\n"
               "  pacing         issue 79: per path (--paths, default orbit,dolly,strafe,turn,walk,species-walk,third-person;\n"
               "                 the last two: demo/scenes/six_species.json) and face count, --frames\n"
               "                 (300) of the default settings at --degrees-list (0.25,0.5): median, p95, p99, max, stutter\n"
               "                 frames, the still frame, counted work, world lock and the pop (--no-reference: without);\n"
               "                 --paced on|off: LayerSettings.pacedReslices; --predict N: predictFrames; --json FILE\n"
               "  camera         the moving camera: per path (--paths, default orbit,dolly,strafe,turn,zoom; also walk)\n"
               "                 the re-slicing policy (--budget MS spread, 0 at once) against re-slicing every frame,\n"
               "                 wind off: world-lock error frame by frame and frame times beside the still camera\n"
               "                 (--faces default 80000, --frames default 60, --size default 1024x768;\n"
               "                 --degrees-per-frame 0.25, --radii-per-frame 0.005, --swing 5: tools/camera_paths.h;\n"
               "                 --reslice-error PX: LayerSettings.errorThresholdPixels of the policy side, default 0.5;\n"
               "                 --csv FILE: a row per frame; then the cross-fade's coverage at one camera, a light and a\n"
               "                 layout change, unless --no-cross-fade; --half-res N: the farthest N layers at half\n"
               "                 resolution on every side, LayerSettings.halfResolutionLayers, default 0;\n"
               "                 --depth-search N: CompositeParams.depthSearchSteps of the policy side, 0: the\n"
               "                 slabs' planes alone, default 16)\n"
               "  layercount     the layer-count study: 1, 2, 3, 5, 7, 9 layers, 3(1-1-1), 5(3-1-1) against 16 layers, animated\n"
               "                 frames frame by frame at a still camera (--faces default 80000, --scene shrub, --gltf FILE\n"
               "                 too, --frames default 90, --size default 512x384, --csv FILE)\n"
               "  leafsheet      the translucency light sheet: a leaf's unlit side, light behind it from steep to grazing,\n"
               "                 Habel's translucency above the diffuse BTDF (--out FILE, default translucency_sheet.png)\n"
               "  species        six species in one vegetation against one at equal placed faces: still, reprojected\n"
               "                 and re-slice frames, mesh memory against copies, the first frame with recordCanopyLoad\n"
               "                 (--faces per species, default 8000; --copies per species, default 10; --frames 20;\n"
               "                 --size default 640x480)\n"
               "  shadows        the vegetation's shadow (recordCanopyShadow): the frame without a shadow and with an\n"
               "                 update every 1, 2 and 4 frames, and the update's own GPU time, for a shrub per face count\n"
               "                 (--faces, default 80000,1000000) and a six-species forest (--frames per variant, default\n"
               "                 20; --size default 640x480; --map N: the shadow map's side, default 1024)\n"
               "  counters       the work per frame kind, counted: vertex, primitive, fragment and compute invocations\n"
               "                 (pipeline statistics) and the bytes each pass declares, for still, reprojected, re-slice\n"
               "                 and spread-step frames, per pixel and per face (--faces, default 80000,1000000,10000000;\n"
               "                 --size, default 1024x768 and 1920x1080; --json, default bench_counters.json)\n"
               "  pushers        32 pushers (setCanopyPushers) against none on the field scene: the frame and the GPU\n"
               "                 time of the passes they touch (--faces, default 80000; --frames per variant, default\n"
               "                 40; --size default 640x480)\n"
               "  picture        the picture in wind: each frame with wind against the same frame without, the 2D method\n"
               "                 beside the per-vertex baseline: sharpness and coverage ratios per scene (--scenes, default\n"
               "                 field,shrub,tree:../shared/assets/quaternius_CommonTree_1/CommonTree_1.glb,\n"
               "                 file:demo/scenes/six_species.json), camera (--paths, default still,walk,orbit), size\n"
               "                 (--picture-sizes, default 640x480,1280x720), wind (--winds, default breeze,gale; gale = 3x\n"
               "                 the default speed), method (--methods, default 2d,per-vertex); --frames default 10; --json\n"
               "                 default bench_picture.json; --table FILE: the markdown table; --check: exit 1 when a 2D\n"
               "                 run is outside issue 67's bounds\n"
               "  plants         real plants in wind (issue 77): per plant (--plants, default the real trees and bushes\n"
               "                 of ../shared/assets and the generated tree) and wind (--winds, default breeze,gale), the\n"
               "                 2D method beside the per-vertex baseline: the attachment gap (a leaf's root against the\n"
               "                 rigid point it grows from, on screen), the sway, the trunk's base, bare rigid pixels in\n"
               "                 the crown (--size default 640x480, --frames default 90, --json default bench_plants.json,\n"
               "                 --table FILE, --check: exit 1 outside issue 77's bounds, --before: as before issue 77,\n"
               "                 --warmup S: seconds run before the first measured frame, default 2; --sway-frames N:\n"
               "                 the breeze's sway pass, frames at 320x240, default 1800 = 60 s, 0: none)\n"
               "  table1         the paper's Table 1: faces x 3(1-1-1)/5(3-1-1) x still/orbit beside the paper's FPS,\n"
               "                 baselines as ratios, a JSON file (--json, default bench_table1.json)\n"
               "  --size WxH     table1, layers: resolution (default 1024x768)\n"
               "  --orbit DEG    table1: camera turn per frame in the orbit rows, (0, 90] (default 0.25)\n"
               "  --guard-band F table1, camera: CanopyDesc.guardBand, [0, 0.5] (default 0.1; camera: the policy side,\n"
               "                 the every-frame side has none)\n"
               "  --series       table1: scaling series (faces, layers 1..9, resolution); --csv-dir DIR writes CSVs\n"
               "  --series-faces table1: the face-count series (default 80000,1000000,10000000)\n"
               "  --json FILE    table1: where the JSON goes ('' for none)\n"
               "  --pair-frames N  table1: still frames per context in the face-count comparison, frames of the two\n"
               "                 contexts alternated, 3..100000 (default 150)\n"
               "  --rebuild-every N  soak: frames between re-slicings, 1..100000 (default 100)\n"
               "  --check        soak: exit 1 on NaN/Inf, device-allocation growth or RSS growth over 64 MiB; picture: see above\n"
               "  --faces        layers, anim: leaf-cloud face counts, 2..100000000 (default 80000,10000000)\n"
               "  --scene NAME   anim: a generated scene (shrub, tree, grass, kelp, field) instead of leaf clouds\n"
               "  --rebuilds N   layers: rebuilds measured per configuration, 1..1000 (default 5)\n"
               "  --device-budget MIB  table1, rebuild: CanopyDesc.deviceMemoryBudget; a mesh over it is streamed\n"
               "                 through the staging ring; 0: no limit (default 1536)\n"
               "  --layers L     layers: layout (default 5(3-1-1))\n"
               "  --sizes        grid sizes, powers of two in [4, 1024] (default 64,128,256)\n"
               "  --frames N     sim: steps, anim: frames measured per configuration, 3..100000 (default 60; anim 30)\n"
               "  --detail       per-pass GPU timestamps\n"
               "  --validate     the validation layers with synchronization validation: any message fails the run (exit 1)\n"
               "  --device NAME  substring of the Vulkan device name\n");
  return why ? 2 : 0;
}

// The command line, parsed into each section's options (main: parse, then run).
struct Args {
  std::vector<uint32_t> sizes = {64, 128, 256};
  int frames = 0;  // 0: the section's default
  bool detail = false;
  bool runLayerCount = false, sizeGiven = false, runLeafSheetSection = false;
  std::string sheetPath = "translucency_sheet.png";
  bench::LayerCountOptions layerCount;
  bool runSim = false, runLayers = false, runAnim = false, runSoak = false, check = false, runTable1 = false;
  bench::Table1Options t1;
  bool facesGiven = false;
  // A comma-separated list of counts in [2, 10^8].
  static bool parseList(const char* v, std::vector<uint64_t>* out) {
    if (!v) return false;
    out->clear();
    std::stringstream ss(v);
    std::string item;
    while (std::getline(ss, item, ',')) {
      uint32_t n;
      if (!cli::parseUint(item.c_str(), 2, 100000000, &n)) return false;
      out->push_back(n);
    }
    return !out->empty();
  }
  uint32_t rebuildEvery = 100;
  bool runRebuild = false, runPerVertex = false, runImpostors = false, runCamera = false;
  bench::CameraBenchOptions cam;
  bool budgetGiven = false;
  // A float in [lo, hi] from the next argument.
  static bool parseNumber(const char* v, float lo, float hi, float* out) {
    char* end = nullptr;
    const float f = v ? std::strtof(v, &end) : 0.0f;
    if (!v || *end || !(f >= lo && f <= hi)) return false;
    *out = f;
    return true;
  }
  std::string csvPath, imagesDir;
  float budgetMs = 4.0f;
  uint64_t spreadMaxFaces = 10000000;
  std::vector<uint64_t> faces = {80000, 10000000};
  uint32_t rebuilds = 5;
  std::string layout = "5(3-1-1)";
  std::string scene;
  bool runSpecies = false, runShadows = false, runPushers = false, runCounters = false, jsonGiven = false;
  bool runPicture = false, pathsGiven = false, runPlants = false, runPacing = false;
  bench::PacingOptions pacing;
  std::vector<std::string> pacingPaths;  // --paths as given (pacing also takes species-walk, third-person)
  bench::PictureOptions picture;
  bench::PlantsOptions plants;
  // A comma-separated list, each item through `each` (false: refused).
  static bool forEachItem(const char* v, const std::function<bool(const std::string&)>& each) {
    if (!v || !*v) return false;
    std::stringstream ss(v);
    std::string item;
    while (std::getline(ss, item, ','))
      if (!each(item)) return false;
    return true;
  }
  uint32_t mapSize = 1024;
  uint32_t copiesPerSpecies = 10;
  DeviceDesc desc;
  bool validate = false;  // the validation layers and synchronization validation; a message fails the run
  int validationMessages = 0;

  // The section words and canopy-bench picture's options; -1: not one of them, else the exit code (0: go on).
  int sectionOrPictureOption(const std::string& a, const std::function<const char*()>& next) {
    if (a == "sim") runSim = true;
    else if (a == "layers") runLayers = true;
    else if (a == "anim") runAnim = true;
    else if (a == "soak") runSoak = true;
    else if (a == "table1") runTable1 = true;
    else if (a == "rebuild") runRebuild = true;
    else if (a == "pervertex") runPerVertex = true;
    else if (a == "picture") runPicture = true;
    else if (a == "plants") runPlants = true;
    else if (a == "--plants") {
      plants.plants.clear();
      if (!forEachItem(next(), [&](const std::string& it) { plants.plants.push_back(it); return true; }))
        return usage("--plants needs a list: tree:FILE.glb, ..., or generated scene names (tree, shrub, ...)");
    } else if (a == "--before") plants.before = true;
    else if (a == "--sway-frames") {
      float v = 0;
      if (!parseNumber(next(), 0.0f, 1e6f, &v)) return usage("--sway-frames needs a frame count in [0, 1000000]");
      plants.swayFrames = uint32_t(v);
    } else if (a == "--warmup") {
      if (!parseNumber(next(), 0.0f, 600.0f, &plants.warmup)) return usage("--warmup needs seconds in [0, 600]");
    }
    else if (a == "--scenes") {
      picture.scenes.clear();
      if (!forEachItem(next(), [&](const std::string& it) { picture.scenes.push_back(it); return true; }))
        return usage("--scenes needs a list: field, shrub, ..., tree:FILE.glb, file:SCENE.json");
    } else if (a == "--picture-sizes") {
      picture.sizes.clear();
      if (!forEachItem(next(), [&](const std::string& it) {
            unsigned w = 0, h = 0;
            char tail = 0;
            if (std::sscanf(it.c_str(), "%ux%u%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 8192 || h > 8192) return false;
            picture.sizes.push_back({w, h});
            return true;
          }))
        return usage("--picture-sizes needs a list of WxH, each in [16, 8192]");
    } else if (a == "--winds") {
      picture.winds.clear();
      if (!forEachItem(next(), [&](const std::string& it) {
            picture.winds.push_back(it);
            return it == "breeze" || it == "gale";
          }))
        return usage("--winds needs a list of breeze, gale");
      plants.winds = picture.winds;
    } else if (a == "--methods") {
      picture.methods.clear();
      if (!forEachItem(next(), [&](const std::string& it) {
            if (it != "2d" && it != "per-vertex") return false;
            picture.methods.push_back(it == "2d" ? AnimationMode::Layers2D : AnimationMode::PerVertex);
            return true;
          }))
        return usage("--methods needs a list of 2d, per-vertex");
    } else if (a == "--table") {
      const char* v = next();
      if (!v) return usage("--table needs a file");
      picture.table = plants.table = v;
    }
    else if (a == "impostors") runImpostors = true;
    else if (a == "camera") runCamera = true;
    else if (a == "layercount") runLayerCount = true;
    else if (a == "leafsheet") runLeafSheetSection = true;
    else if (a == "species") runSpecies = true;
    else if (a == "shadows") runShadows = true;
    else if (a == "pushers") runPushers = true;
    else if (a == "counters") runCounters = true;
    else if (a == "pacing") runPacing = true;
    else if (a == "--no-reference") pacing.reference = false;
    else if (a == "--paced") {
      const char* v = next();
      if (!v || (std::string(v) != "on" && std::string(v) != "off")) return usage("--paced needs on or off");
      pacing.paced = std::string(v) == "on";
    }
    else if (a == "--predict") {
      if (!cli::parseUint(next(), 0, 16, &pacing.predictFrames)) return usage("--predict needs frames in [0, 16]");
    }
    else if (a == "--degrees-list") {
      pacing.degreesPerFrame.clear();
      if (!forEachItem(next(), [&](const std::string& it) {
            float v = 0;
            if (!parseNumber(it.c_str(), 0.0f, 90.0f, &v)) return false;
            pacing.degreesPerFrame.push_back(v);
            return true;
          }))
        return usage("--degrees-list needs degrees a frame, each in [0, 90]");
    }
    else return -1;
    return 0;
  }

  // The shadow, species, layer-count and camera sections' options; -1: not one of them, else the exit code (0: go on).
  int cameraOption(const std::string& a, const std::function<const char*()>& next) {
    if (a == "--map") {
      if (!cli::parseUint(next(), 16, 16384, &mapSize)) return usage("--map needs the shadow map's side in [16, 16384]");
    }
    else if (a == "--copies") {
      if (!cli::parseUint(next(), 1, 10000, &copiesPerSpecies)) return usage("--copies needs copies per species in [1, 10000]");
    }
    else if (a == "--out") {
      const char* v = next();
      if (!v) return usage("--out needs a file");
      sheetPath = v;
    }
    else if (a == "--gltf") {
      const char* v = next();
      if (!v) return usage("--gltf needs a file");
      layerCount.gltf = v;
    }
    else if (a == "--paths") {
      const char* v = next();
      if (!v) return usage("--paths needs a list: orbit,dolly,strafe,turn,zoom,walk");
      cam.paths.clear();
      pacingPaths.clear();
      std::stringstream ss(v);
      std::string item;
      while (std::getline(ss, item, ',')) {
        pacingPaths.push_back(item);
        if (item == "species-walk" || item == "third-person") continue;  // pacing's scene-file paths
        CameraMotion m;
        const Status ps = parseCameraMotion(item, &m);
        if (!ps.ok()) return usage(("--paths: " + ps.message()).c_str());
        cam.paths.push_back(m);
      }
      pathsGiven = true;
    } else if (a == "--reslice-error") {
      if (!parseNumber(next(), 0, 1000, &cam.errorPixels)) return usage("--reslice-error needs pixels in [0, 1000]");
    } else if (a == "--degrees-per-frame") {
      if (!parseNumber(next(), -90, 90, &cam.degreesPerFrame)) return usage("--degrees-per-frame needs degrees in [-90, 90]");
    } else if (a == "--radii-per-frame") {
      if (!parseNumber(next(), 0, 10, &cam.radiiPerFrame)) return usage("--radii-per-frame needs radii in [0, 10]");
    } else if (a == "--depth-search") {
      if (!cli::parseUint(next(), 0, 64, &cam.depthSearchSteps)) return usage("--depth-search needs a sample count in [0, 64]");
    } else if (a == "--half-res") {
      if (!cli::parseUint(next(), 0, 32, &cam.halfResolutionLayers)) return usage("--half-res needs a layer count in [0, 32]");
    } else if (a == "--no-cross-fade") {
      cam.crossFade = false;
    } else if (a == "--swing") {
      if (!parseNumber(next(), 0, 80, &cam.swingDegrees)) return usage("--swing needs degrees in [0, 80]");
    }
    else if (a == "--images") {
      const char* v = next();
      if (!v) return usage("--images needs a folder");
      imagesDir = v;
    }
    else if (a == "--csv") {
      const char* v = next();
      if (!v) return usage("--csv needs a file name");
      csvPath = v;
    }
    else return -1;
    return 0;
  }

  // Re-slicing, budgets and table1's options; -1: not one of them, else the exit code (0: go on).
  int budgetOption(const std::string& a, const std::function<const char*()>& next) {
    if (a == "--spread-max-faces") {
      uint32_t n = 0;
      if (!cli::parseUint(next(), 0, 100000000, &n)) return usage("--spread-max-faces needs an integer in [0, 100000000]");
      spreadMaxFaces = n;
    }
    else if (a == "--device-budget") {
      uint32_t mib = 0;
      if (!cli::parseUint(next(), 0, 1u << 20, &mib)) return usage("--device-budget needs MiB in [0, 1048576]");
      t1.deviceMemoryBudget = uint64_t(mib) << 20;
    } else if (a == "--budget") {
      const char* v = next();
      char* end = nullptr;
      budgetMs = v ? std::strtof(v, &end) : 0.0f;
      if (!v || *end || !(budgetMs >= 0.0f && budgetMs <= 1000.0f)) return usage("--budget needs ms in [0, 1000]");
      budgetGiven = true;
    }
    else if (a == "--series") t1.series = true;
    else if (a == "--series-faces") {
      if (!parseList(next(), &t1.seriesFaces)) return usage("--series-faces: each must be an integer in [2, 100000000]");
    } else if (a == "--pair-frames") {
      uint32_t n = 0;
      if (!cli::parseUint(next(), 3, 100000, &n)) return usage("--pair-frames needs an integer in [3, 100000]");
      t1.pairFrames = int(n);
    } else if (a == "--csv-dir") {
      const char* v = next();
      if (!v) return usage("--csv-dir needs a folder");
      t1.csvDir = v;
    } else if (a == "--json") {
      const char* v = next();
      if (!v) return usage("--json needs a file name ('' for none)");
      t1.json = v;
      jsonGiven = true;
    } else if (a == "--size") {
      const char* v = next();
      unsigned w = 0, h = 0;
      char tail = 0;
      if (!v || std::sscanf(v, "%ux%u%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 8192 || h > 8192)
        return usage("--size needs WxH, each in [16, 8192]");
      t1.width = w;
      t1.height = h;
      sizeGiven = true;
    } else if (a == "--guard-band") {
      float g = 0.0f;
      if (!parseNumber(next(), 0, 0.5, &g)) return usage("--guard-band needs a fraction in [0, 0.5]");
      t1.guardBand = cam.guardBand = g;
    } else if (a == "--orbit") {
      const char* v = next();
      char* end = nullptr;
      const float deg = v ? std::strtof(v, &end) : 0.0f;
      if (!v || *end || !(deg > 0.0f && deg <= 90.0f)) return usage("--orbit needs degrees in (0, 90]");
      t1.orbitDegrees = deg;
    }
    else return -1;
    return 0;
  }

  // The options several sections read; -1: not one of them, else the exit code (0: go on).
  int commonOption(const std::string& a, const std::function<const char*()>& next) {
    if (a == "--check") check = true;
    else if (a == "--rebuild-every") {
      if (!cli::parseUint(next(), 1, 100000, &rebuildEvery)) return usage("--rebuild-every needs an integer in [1, 100000]");
    }
    else if (a == "--detail") detail = true;
    else if (a == "--validate") validate = true;
    else if (a == "--faces") {
      const char* v = next();
      if (!v) return usage("--faces needs a list");
      faces.clear();
      std::stringstream ss(v);
      std::string item;
      while (std::getline(ss, item, ',')) {
        uint32_t n;
        if (!cli::parseUint(item.c_str(), 2, 100000000, &n)) return usage("--faces: each must be an integer in [2, 100000000]");
        faces.push_back(n);
      }
      facesGiven = true;
    } else if (a == "--scene") {
      const char* v = next();
      if (!v) return usage("--scene needs a name: shrub, tree, grass, kelp, field");
      scene = v;
    } else if (a == "--rebuilds") {
      if (!cli::parseUint(next(), 1, 1000, &rebuilds)) return usage("--rebuilds needs an integer in [1, 1000]");
    } else if (a == "--layers") {
      const char* v = next();
      if (!v) return usage("--layers needs a layout");
      layout = v;
    }
    else if (a == "--sizes") {
      const char* v = next();
      if (!v) return usage("--sizes needs a list");
      sizes.clear();
      std::stringstream ss(v);
      std::string item;
      while (std::getline(ss, item, ',')) {
        uint32_t n;
        if (!cli::parseUint(item.c_str(), 4, 1024, &n) || (n & (n - 1))) return usage("--sizes: each must be a power of two in [4, 1024]");
        sizes.push_back(n);
      }
    } else if (a == "--frames") {
      uint32_t n;
      if (!cli::parseUint(next(), 3, 10000000, &n)) return usage("--frames needs an integer in [3, 10000000]");
      frames = int(n);
    } else if (a == "--device") {
      const char* v = next();
      if (!v) return usage("--device needs a name");
      desc.preferredDevice = v;
    }
    else return -1;
    return 0;
  }

  // 0: run; 1: --help printed; else the exit code of a refusal.
  int parse(int argc, char** argv) {
    desc.applicationName = "canopy-bench";
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
      if (a == "--help" || a == "-h") return usage(nullptr), 1;
      int rc = -1;
      for (auto group : {&Args::sectionOrPictureOption, &Args::cameraOption, &Args::budgetOption, &Args::commonOption})
        if ((rc = (this->*group)(a, next)) >= 0) break;
      if (rc < 0) return usage(("unknown argument '" + a + "'").c_str());
      if (rc > 0) return rc;
    }
    return 0;
  }

  // The sections asked for (sim when none), on the device `desc` names.
  int run() {
    if (validate) {
      desc.enableValidation = desc.requireValidation = true;
      desc.validationSink = [this](VkDebugUtilsMessageSeverityFlagBitsEXT, const char* id, const char* text) {
        ++validationMessages;
        std::fprintf(stderr, "validation: %s: %s\n", id ? id : "", text);
      };
    }
  if (runRebuild && !(budgetMs > 0.0f)) return usage("rebuild: --budget needs ms in (0, 1000]");
  Device dev;
  Status s = createDevice(desc, &dev);
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
    return 1;
  }
  std::printf("Device: %s\n", dev.properties.deviceName);
  if (!runSim && !runLayers && !runAnim && !runSoak && !runTable1 && !runRebuild && !runPerVertex && !runImpostors && !runCamera &&
      !runLayerCount && !runLeafSheetSection && !runSpecies && !runShadows && !runPushers && !runCounters && !runPicture &&
      !runPlants && !runPacing)
    runSim = true;
  int rc = 0;
  if (runSim) rc = bench::runSimBench(dev, sizes, frames ? frames : 60, detail);
  if (rc == 0 && runLayers) rc = bench::runLayersBench(dev, faces, int(rebuilds), layout, sizeGiven ? t1.width : 1024u, sizeGiven ? t1.height : 768u);
  if (rc == 0 && runAnim) rc = bench::runAnimBench(dev, faces, {"3(1-1-1)", "5(3-1-1)"}, frames ? frames : 30, 1024, 768,
                                             scene);
  if (rc == 0 && runTable1) {
    if (facesGiven) t1.faces.assign(faces.begin(), faces.end());
    if (!scene.empty()) t1.scene = scene;
    if (frames) t1.frames = frames;
    rc = bench::runTable1Bench(dev, t1);
  }
  if (rc == 0 && runRebuild)
    rc = bench::runRebuildBench(dev, faces, scene.empty() ? "shrub" : scene, budgetMs, int(rebuilds),
                                t1.width, t1.height, spreadMaxFaces, t1.deviceMemoryBudget);
  if (rc == 0 && runPerVertex)
    rc = bench::runPerVertexBench(dev, facesGiven ? faces : std::vector<uint64_t>{80000, 1000000, 10000000},
                                  scene.empty() ? "shrub" : scene, frames ? frames : 24, t1.width, t1.height,
                                  t1.deviceMemoryBudget, csvPath);
  if (rc == 0 && runImpostors)
    rc = bench::runImpostorBench(dev, facesGiven ? faces : std::vector<uint64_t>{10000000}, scene, int(rebuilds),
                                 t1.width, t1.height, imagesDir);
  if (rc == 0 && runCamera) {
    if (facesGiven) cam.faces.assign(faces.begin(), faces.end());
    if (!scene.empty()) cam.scene = scene;
    if (frames) cam.frames = frames;
    cam.width = t1.width;
    cam.height = t1.height;
    if (budgetGiven) cam.budgetMs = budgetMs;
    cam.csvPath = csvPath;
    rc = bench::runCameraBench(dev, cam);
  }
  if (rc == 0 && runPacing) {
    if (facesGiven) pacing.faces.assign(faces.begin(), faces.end());
    if (pathsGiven) pacing.paths = pacingPaths;
    if (frames) pacing.frames = frames;
    if (sizeGiven) {
      pacing.width = t1.width;
      pacing.height = t1.height;
    }
    if (budgetGiven) pacing.budgetMs = budgetMs;
    if (jsonGiven) pacing.json = t1.json;
    rc = bench::runPacingBench(dev, pacing);
  }
  if (rc == 0 && runLayerCount) {
    if (facesGiven) layerCount.faces = faces.front();
    if (!scene.empty()) layerCount.scene = scene;
    if (frames) layerCount.frames = std::max<int>(frames, layerCount.skip + 1);
    if (sizeGiven) layerCount.width = t1.width, layerCount.height = t1.height;
    layerCount.csvPath = csvPath;
    rc = bench::runLayerCountBench(dev, layerCount);
  }
  if (rc == 0 && runLeafSheetSection) rc = bench::runLeafSheet(dev, sheetPath);
  if (rc == 0 && runSpecies)
    rc = bench::runSpeciesBench(dev, facesGiven ? faces.front() : 8000, copiesPerSpecies, frames ? frames : 20,
                                sizeGiven ? t1.width : 640u, sizeGiven ? t1.height : 480u);
  if (rc == 0 && runShadows)
    rc = bench::runShadowBench(dev, facesGiven ? faces : std::vector<uint64_t>{80000, 1000000}, frames ? frames : 20,
                               sizeGiven ? t1.width : 640u, sizeGiven ? t1.height : 480u, mapSize);
  if (rc == 0 && runCounters)
    rc = bench::runCounterBench(dev, facesGiven ? faces : std::vector<uint64_t>{80000, 1000000, 10000000},
                                sizeGiven ? std::vector<std::pair<uint32_t, uint32_t>>{{t1.width, t1.height}}
                                          : std::vector<std::pair<uint32_t, uint32_t>>{{1024, 768}, {1920, 1080}},
                                jsonGiven ? t1.json : std::string("bench_counters.json"));
  if (rc == 0 && runPushers)
    rc = bench::runPusherBench(dev, facesGiven ? faces.front() : 80000, frames ? frames : 40, sizeGiven ? t1.width : 640u,
                               sizeGiven ? t1.height : 480u);
  if (rc == 0 && runPicture) {
    if (pathsGiven) picture.paths = cam.paths;
    if (frames) picture.frames = uint32_t(frames);
    if (jsonGiven) picture.json = t1.json;
    picture.check = check;
    rc = bench::runPictureBench(dev, picture);
  }
  if (rc == 0 && runPlants) {
    if (frames) plants.frames = uint32_t(frames);
    if (sizeGiven) {
      plants.width = t1.width;
      plants.height = t1.height;
    }
    if (jsonGiven) plants.json = t1.json;
    plants.check = check;
    rc = bench::runPlantsBench(dev, plants);
  }
  if (rc == 0 && runSoak) rc = bench::runSoakBench(dev, frames ? frames : 100000, int(rebuildEvery), check);
  destroyDevice(dev);
  if (validationMessages > 0) {
    std::fprintf(stderr, "canopy-bench: %d validation messages\n", validationMessages);
    return 1;
  }
  return rc;
  }
};

int main(int argc, char** argv) {
  Args args;
  const int rc = args.parse(argc, argv);
  if (rc == 1) return 0;
  if (rc != 0) return rc;
  return args.run();
}
