#include "demo/demo_app.h"

#include "tools/fault_loader.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>

#include "demo/cli.h"
#include "demo/progress.h"
#include "render/gltf_loader.h"
#include "tools/param_table.h"
#include "engine/graphics_pipeline.h"
#include "engine/shader_registry.h"
#include <glm/gtc/matrix_transform.hpp>

// canopy-demo's own shaders (demo/shaders; CMakeLists.txt canopy_demo_shaders).
namespace canopy_demo {
const canopy::EmbeddedShader* findEmbeddedShader(const char* name);
}

namespace canopy::demo {

// ---- options ------------------------------------------------------------------------------------

namespace {
// The --help line of an option that mirrors a parameter: its text, unit and range from the schema
// (<canopy/canopy_schema.h>), the demo's own default.
std::string mirrored(const char* option, const char* param, double demoDefault) {
  const ParamInfo* p = findParam(param);
  if (!p) return std::string("  ") + option + " (no schema line " + param + ")\n";
  char line[512];
  std::snprintf(line, sizeof line, "  %-19s %s%s%s, %s%g, %g] (default %g)\n", option, p->doc, *p->unit ? ", " : "", p->unit,
                p->check == ParamCheck::AboveMin ? "(" : "[", p->min, p->max, demoDefault);
  return line;
}
}  // namespace

void printHelp() {
  const Options d;
  std::printf(
      "usage: canopy-demo [options]\n"
      "Animates vegetation in wind with Canopy and writes the frames (PNG), a contact sheet and a per-pass\n"
      "timing summary to the output folder (plus an MP4 when ffmpeg is installed). --window shows it live.\n\n"
      "Scene:\n"
      "  --scene NAME        generated scene: shrub, tree, grass, kelp, field (default %s)\n"
      "  --faces N           generated scene's triangles, %llu..%llu, K/M suffixes (default %lluK)\n"
      "  --seed S            generated scene's seed, 0..4294967295 (default %u)\n"
      "  --gltf FILE         load a .gltf/.glb instead of generating a scene\n"
      "  --pusher PATH       a sphere walking through the scene (setCanopyPushers): line (across the view)\n"
      "                      or circle, over the written frames; pusher_path.txt holds its screen path\n"
      "  --scene-file FILE   a scene file (docs/scene-files.md): several species, placed copies and\n"
      "                      scatters, in one vegetation (instead of --scene / --gltf)\n"
      "  --rigid M1,M2       materials (names or #index) forced to be rigid background (trunk, branches)\n"
      "  --foliage M1,M2     materials forced to be foliage (default rule: render/material_split.h)\n"
      "Method:\n"
      "  --layers L          layer layout N(near-mid-far) or N, 1..32 layers (default %s)\n"
      "  --wind-dir X,Y,Z    the world direction the wind blows toward, y up (default %g,%g,%g)\n"
      "%s%s%s%s%s"
      "  --yaw DEG           the camera's start around the vertical through the vegetation's centre, degrees\n"
      "                      (0: the default view; also the orbit's start) (default 0)\n"
      "  Advanced, the wind as sides of the simulation plane fixed by the first camera (before 0.8;\n"
      "  any of these selects it):\n"
      "  --wind SIDES        wind source sides, comma-separated: left,right,top,bottom, or none (default left)\n"
      "%s%s%s"
      "                      the inflow speed is strength * (1 + b sin(2 pi f t)) * (1 + G * noise\n"
      "                      travelling along the side)\n"
      "%s"
      "  --delay MODE        layer delay: exact or approx (default exact)\n"
      "  --method M          2d (the paper's layers) or per-vertex (the 3D baseline: every vertex bent through\n"
      "                      its branch hierarchy each frame, Habel); the window switches with M (default 2d)\n"
      "  --per-vertex-wind W field (Kaimal wind field, damped oscillators per level) or uniform (one wind,\n"
      "                      noise per branch: before 0.7) for the per-vertex baseline (default field)\n"
      "  --impostors MODE    off, far (boxes in the far region) or size (any box) drawn as Lluch et al.'s\n"
      "                      impostors when their projected size is at or below --impostor-pixels (the\n"
      "                      leaves fade out over ImpostorSettings.band above it); the views are baked\n"
      "                      (or read from the cache) when the demo starts (default off)\n"
      "%s"
      "  --impostor-debug    colour leaves and impostors by their box's hierarchy level\n"
      "  --impostor-views N  6 (Lluch et al.'s diagonal planes) or 12 (and the box faces: before 0.7) (default 6)\n"
      "  --impostor-shape S  crossed (the paper's crossed polygons) or facing (one polygon facing the viewer,\n"
      "                      two views blended: before 0.7) (default crossed)\n"
      "  --debug VIEW        none, layers (false colour), velocity (simulation field), grid (warp grid), or\n"
      "                      shadow-map (implies --shadows; each frame's shadow map to shadow_NNNN.png) (default none)\n"
      "  --shadows           a grey ground under the scene, lit by the sun (--light) through the vegetation's\n"
      "                      shadow map (recordCanopyShadow, updated every frame; timing.txt: its cost and how\n"
      "                      it sways against the crown on screen)\n"
      "Light and leaf shading (Habel: specular front, diffuse back, transmission on the unlit side):\n"
      "  --light X,Y,Z       direction towards the light, world space, y up; the camera looks from +Z\n"
      "                      (default %g,%g,%g; behind the plant: e.g. 0.2,0.35,-1)\n"
      "  --light-color R,G,B linear light colour, each [0, 1000] (default %g,%g,%g)\n"
      "%s%s%s%s"
      "  --no-translucency   unlit leaf sides get the ambient term only\n"
      "  --nearest           the warp reads each layer's nearest texel instead of a bilinear sample (CompositeParams.bilinear)\n"
      "%s%s"
      "  --light-sheet       headless: after the frames, write light_sheet.png: the last frame lit by --light,\n"
      "                      by the light turned 180 degrees about the vertical (from behind), and by that\n"
      "                      light without translucency\n"
      "Output:\n"
      "  --size WxH          frame size, 16..8192 each (default %ux%u)\n"
      "  --frames N          frames to render, 1..100000 (default %u)\n"
      "  --warmup S          headless: seconds of animation run (not written) before the first frame,\n"
      "                      so the wind has reached the plant, [0, 60] (default %g)\n"
      "  --fps F             animation frames per second, dt = 1/F, [1, 1000] (default %g)\n"
      "  --camera PATH       still, orbit, dolly, strafe, turn (a pure rotation), zoom, walk (first person;\n"
      "                      for --scene field) (default still)\n"
      "  --orbit-degrees D   orbit path: total turn over the sequence, [-3600, 3600] (default %g)\n"
      "  --degrees-per-frame D  orbit/turn: yaw, zoom: field of view, walk: looking around, per frame,\n"
      "                      [-90, 90] (default 0.25; orbit without it: --orbit-degrees over the sequence)\n"
      "  --radii-per-frame R dolly, strafe, walk: the vegetation's bounding radius per frame, [0, 10]\n"
      "                      (default 0.005)\n"
      "  --swing D           turn, zoom, walk: degrees either side of the start, [0, 80] (default 5)\n"
      "  --reslice MODE      auto (re-slice by the policy) or every-frame (the reference a moving camera's\n"
      "                      frames are measured against) (default auto)\n"
      "%s"
      "%s"
      "%s"
      "%s"
      "  --compare-frames A B  the world-lock error of folder A's frame_NNNN.png against folder B's (coverage\n"
      "                      IoU, silhouette distance, colour; tools/world_lock.h), then exit\n"
      "  --measure-foliage W S  folder W's frame_NNNN.png (wind) against S's (the same run without wind):\n"
      "                      foliage coverage, the crown's sideways offset, sharpness (tools/foliage_measure.h), then exit\n"
      "%s"
      "                      (a re-slice after a camera move is spread over frames, then cross-faded in; one a\n"
      "                      moving camera would outrun is made at once)\n"
      "  --device-budget MIB device memory Canopy may allocate; a mesh that does not fit is streamed\n"
      "                      through a staging ring at each re-slice; 0: no limit, [0, 1048576] (default %g)\n"
      "  --ring MIB          the staging ring of a streamed mesh, [1, 4096] (default %g)\n"
      "  --out DIR           output folder, created if missing; frame files beyond --frames left there by\n"
      "                      an earlier run are removed (default %s)\n"
      "  --no-mp4            do not encode demo.mp4 even when ffmpeg is installed\n"
      "Window (needs a display; falls back to headless without one):\n"
      "  --window            open a window: left drag orbits, wheel zooms, right drag pushes the foliage;\n"
      "                      keys: arrows wind direction/strength, F/G frequency, L layout, D delay mode,\n"
      "                      V debug view, M method (2D / per-vertex), J/K turn the light, T translucency,\n"
      "                      I impostors (off / far / size), B impostor debug view (levels),\n"
      "                      space pause, O auto-orbit,\n"
      "                      P screenshot, Esc quit\n"
      "  --vsync on|off      present with vsync (default on)\n"
      "  --screenshot FILE   window: write the last frame read back from the swapchain (fails if blank)\n"
      "  --resize-at N       window: resize the window after N frames (tests; default 0 = never)\n"
      "  (with --window, --frames N closes the window after N frames; without it the window stays open)\n"
      "Both:\n"
      "  --validate          Vulkan validation + synchronization validation; any message fails the run\n"
      "  --device NAME       substring of the Vulkan device name (default: best device, or $CANOPY_DEVICE)\n"
      "  --inject-fault oom:N|lost:N  Canopy's Vulkan calls fail (out of device memory, device lost) after N\n"
      "                      successful object creations (tools/fault_loader.h; reliability tests)\n"
      "  --param-table       print every API parameter's default, range and unit (docs/parameters.md)\n"
      "  --help              this text\n",
      sceneName(d.scene), (unsigned long long)kMinSceneFaces, (unsigned long long)kMaxSceneFaces,
      (unsigned long long)(d.faces / 1000), d.seed, d.layout.c_str(),
      double(d.windDirection.x), double(d.windDirection.y), double(d.windDirection.z),
      mirrored("--wind-speed M", "WorldWind.speed", d.windSpeed).c_str(),
      mirrored("--gust-intensity G", "WorldWind.gustIntensity", d.gustIntensity).c_str(),
      mirrored("--gust-frequency F", "WorldWind.gustFrequency", d.gustFrequency).c_str(),
      mirrored("--turbulence T", "WorldWind.turbulence", d.turbulence).c_str(),
      mirrored("--sway S", "WorldWind.sway", d.sway).c_str(),
      mirrored("--strength V", "WindParams.strength", d.windStrength).c_str(),
      mirrored("--frequency F", "WindParams.frequency", d.windFrequency).c_str(),
      mirrored("--modulation B", "WindParams.modulation", d.windModulation).c_str(),
      mirrored("--gust G", "WindParams.gust", d.windGust).c_str(),
      mirrored("--impostor-pixels P", "ImpostorSettings.switchPixels", d.impostorPixels).c_str(), d.light.x, d.light.y,
      d.light.z, d.lightColor.x, d.lightColor.y, d.lightColor.z, mirrored("--ambient A", "LayerSettings.ambient", d.ambient).c_str(),
      mirrored("--leaf-ior N", "LayerSettings.leafRefractiveIndex", d.leafIor).c_str(),
      mirrored("--leaf-roughness S", "LayerSettings.leafRoughness", d.leafRoughness).c_str(),
      mirrored("--leaf-transmission T", "LayerSettings.leafTransmission", d.leafTransmission).c_str(), mirrored("--sharpness K", "CompositeParams.sharpness", d.sharpness).c_str(),
      mirrored("--max-stretch L", "DynamicsParams.maxStretch", d.maxStretch).c_str(), d.width, d.height,
      d.frames, d.warmupSeconds, d.fps, d.orbitDegrees,
      mirrored("--reslice-error PX", "LayerSettings.errorThresholdPixels", d.resliceErrorPixels).c_str(),
      mirrored("--guard-band F", "CanopyDesc.guardBand", d.guardBand).c_str(),
      mirrored("--half-res-layers N", "LayerSettings.halfResolutionLayers", d.halfResolutionLayers).c_str(),
      mirrored("--depth-search N", "CompositeParams.depthSearchSteps", d.depthSearchSteps).c_str(),
      mirrored("--rebuild-budget MS", "LayerSettings.rebuildBudgetMs", d.rebuildBudgetMs).c_str(), d.deviceBudgetMiB,
      d.ringMiB, d.outDir.c_str());
  std::printf("Caches of a --gltf model (leaf roots, impostor views; docs/design.md \"Files\"):\n%s", cli::cacheHelp());
}

namespace {
// 'text' built by appends: GCC 12's -Wrestrict misfires on "'" + std::string(text) once inlined.
std::string quoted(const std::string& text) {
  std::string q(1, '\'');
  q += text;
  q += '\'';
  return q;
}
}  // namespace

// The options that set one number in a range, and the switches: one line each (parseOptions).
// An option that mirrors a parameter names its schema line (`param`): its range is the
// parameter's (lo and hi are then not read).
struct NumberOption {
  const char* name;
  float lo, hi;
  float Options::*field;
  const char* what;
  const char* param = nullptr;
  float low() const { return param && findParam(param) ? float(findParam(param)->min) : lo; }
  float high() const { return param && findParam(param) ? float(findParam(param)->max) : hi; }
};
const NumberOption kNumberOptions[] = {
    {"--wind-speed", 0, 0, &Options::windSpeed, "a number", "WorldWind.speed"},
    {"--gust-intensity", 0, 0, &Options::gustIntensity, "a number", "WorldWind.gustIntensity"},
    {"--gust-frequency", 0, 0, &Options::gustFrequency, "a number", "WorldWind.gustFrequency"},
    {"--turbulence", 0, 0, &Options::turbulence, "a number", "WorldWind.turbulence"},
    {"--sway", 0, 0, &Options::sway, "a number", "WorldWind.sway"},
    {"--yaw", -3600, 3600, &Options::yawDegrees, "a number"},
    {"--strength", 0, 0, &Options::windStrength, "a number", "WindParams.strength"},
    {"--frequency", 0, 0, &Options::windFrequency, "a number", "WindParams.frequency"},
    {"--modulation", 0, 0, &Options::windModulation, "a number", "WindParams.modulation"},
    {"--gust", 0, 0, &Options::windGust, "a number", "WindParams.gust"},
    {"--warmup", 0, 60, &Options::warmupSeconds, "seconds"},
    {"--impostor-pixels", 0, 0, &Options::impostorPixels, "a number", "ImpostorSettings.switchPixels"},
    {"--ambient", 0, 0, &Options::ambient, "a number", "LayerSettings.ambient"},
    {"--leaf-ior", 0, 0, &Options::leafIor, "a number", "LayerSettings.leafRefractiveIndex"},
    {"--leaf-roughness", 0, 0, &Options::leafRoughness, "a number", "LayerSettings.leafRoughness"},
    {"--leaf-transmission", 0, 0, &Options::leafTransmission, "a number", "LayerSettings.leafTransmission"},
    {"--fps", 1, 1000, &Options::fps, "a number"},
    {"--orbit-degrees", -3600, 3600, &Options::orbitDegrees, "a number"},
    {"--radii-per-frame", 0, 10, &Options::radiiPerFrame, "a number"},
    {"--swing", 0, 80, &Options::swingDegrees, "a number"},
    {"--rebuild-budget", 0, 0, &Options::rebuildBudgetMs, "a number", "LayerSettings.rebuildBudgetMs"},
    {"--reslice-error", 0, 0, &Options::resliceErrorPixels, "a number", "LayerSettings.errorThresholdPixels"},
    {"--guard-band", 0, 0, &Options::guardBand, "a number", "CanopyDesc.guardBand"},
    {"--half-res-layers", 0, 0, &Options::halfResolutionLayers, "a number", "LayerSettings.halfResolutionLayers"},
    {"--depth-search", 0, 0, &Options::depthSearchSteps, "a number", "CompositeParams.depthSearchSteps"},
    {"--sharpness", 0, 0, &Options::sharpness, "a number", "CompositeParams.sharpness"},
    {"--max-stretch", 0, 0, &Options::maxStretch, "a number", "DynamicsParams.maxStretch"},
    {"--device-budget", 0, 1048576, &Options::deviceBudgetMiB, "a number"},
    {"--ring", 1, 4096, &Options::ringMiB, "a number"},
};
struct SwitchOption {
  const char* name;
  bool Options::*field;
  bool value;
};
const SwitchOption kSwitchOptions[] = {
    {"--impostor-debug", &Options::impostorDebug, true},
    {"--shadows", &Options::shadows, true},
    {"--no-translucency", &Options::translucency, false},
    {"--nearest", &Options::bilinear, false},
    {"--light-sheet", &Options::lightSheet, true},
    {"--window", &Options::window, true},
    {"--validate", &Options::validate, true},
    {"--no-mp4", &Options::mp4, false},
};
// Options that take one of a few words, each word setting Options its own way; `words` is what a
// refusal lists (an alias such as "approximate" is accepted without being listed).
struct ChoiceOption {
  const char* name;
  const char* words;
  std::vector<std::pair<std::string, std::function<void(Options&)>>> choices;
};
const std::vector<ChoiceOption>& choiceOptions() {
  static const std::vector<ChoiceOption> options = {
      {"--delay", "exact or approx",
       {{"exact", [](Options& o) { o.delay = DelayMode::Exact; }},
        {"approx", [](Options& o) { o.delay = DelayMode::Approximate; }},
        {"approximate", [](Options& o) { o.delay = DelayMode::Approximate; }}}},
      {"--pusher", "line or circle",
       {{"line", [](Options& o) { o.pusher = PusherPath::Line; }},
        {"circle", [](Options& o) { o.pusher = PusherPath::Circle; }},
        {"none", [](Options& o) { o.pusher = PusherPath::None; }}}},
      {"--method", "2d or per-vertex",
       {{"2d", [](Options& o) { o.method = AnimationMode::Layers2D; }},
        {"per-vertex", [](Options& o) { o.method = AnimationMode::PerVertex; }}}},
      {"--per-vertex-wind", "field or uniform",
       {{"field", [](Options& o) { o.perVertexWind = PerVertexWind::KaimalField; }},
        {"uniform", [](Options& o) { o.perVertexWind = PerVertexWind::UniformNoise; }}}},
      {"--impostor-views", "6 or 12",
       {{"6", [](Options& o) { o.impostorViews = ImpostorViews::Diagonal6; }},
        {"12", [](Options& o) { o.impostorViews = ImpostorViews::FacesAndDiagonals12; }}}},
      {"--impostor-shape", "crossed or facing",
       {{"crossed", [](Options& o) { o.impostorShape = ImpostorShape::CrossedPolygons; }},
        {"facing", [](Options& o) { o.impostorShape = ImpostorShape::FacingPolygon; }}}},
      {"--impostors", "off, far or size",
       {{"off", [](Options& o) { o.impostors = ImpostorMode::Off; }},
        {"far", [](Options& o) { o.impostors = ImpostorMode::FarRegion; }},
        {"size", [](Options& o) { o.impostors = ImpostorMode::ByProjectedSize; }}}},
      {"--debug", "none, layers, velocity, grid or shadow-map",
       {{"none", [](Options& o) { o.debug = CompositeDebugView::None; }},
        {"shadow-map", [](Options& o) { o.debugShadowMap = o.shadows = true; }},
        {"layers", [](Options& o) { o.debug = CompositeDebugView::Layers; }},
        {"velocity", [](Options& o) { o.debug = CompositeDebugView::Velocity; }},
        {"grid", [](Options& o) { o.debug = CompositeDebugView::Grid; }}}},
      {"--reslice", "auto or every-frame",
       {{"auto", [](Options& o) { o.reslice = ReslicePolicy::OnViewChange; }},
        {"every-frame", [](Options& o) { o.reslice = ReslicePolicy::EveryFrame; }}}},
      {"--vsync", "on or off",
       {{"on", [](Options& o) { o.vsync = true; }}, {"off", [](Options& o) { o.vsync = false; }}}},
  };
  return options;
}

int parseOptions(int argc, char** argv, Options* o, std::string* err) {
  bool framesGiven = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    auto takes = [&]() { return v ? (++i, true) : false; };
    auto bad = [&](const std::string& why) {
      *err = a + " " + why;
      return 2;
    };
    // A number in [lo, hi] into *dst; 0 when taken, else 2 with the reason.
    auto number = [&](float lo, float hi, float* dst, const char* what = "a number") {
      float f = 0;
      if (!takes() || !cli::parseFloat(v, &f) || !(f >= lo && f <= hi)) {
        char range[96];
        std::snprintf(range, sizeof range, "needs %s in [%g, %g]", what, double(lo), double(hi));
        return bad(range);
      }
      *dst = f;
      return 0;
    };
    const NumberOption* num = nullptr;
    for (const NumberOption& n : kNumberOptions)
      if (a == n.name) num = &n;
    const SwitchOption* sw = nullptr;
    for (const SwitchOption& n : kSwitchOptions)
      if (a == n.name) sw = &n;
    const ChoiceOption* choice = nullptr;
    for (const ChoiceOption& c : choiceOptions())
      if (a == c.name) choice = &c;
    if (num) {
      if (const int rc = number(num->low(), num->high(), &(o->*(num->field)), num->what)) return rc;
      if (num->param && std::strncmp(num->param, "WindParams.", 11) == 0) o->planeSides = true;
      if (num->field == &Options::halfResolutionLayers && o->halfResolutionLayers != std::floor(o->halfResolutionLayers))
        return bad("needs a whole number of layers");
      if (num->field == &Options::depthSearchSteps && o->depthSearchSteps != std::floor(o->depthSearchSteps))
        return bad("needs a whole number of samples");
    } else if (sw) {
      o->*(sw->field) = sw->value;
    } else if (choice) {
      if (!takes()) return bad(std::string("needs ") + choice->words);
      auto word = std::find_if(choice->choices.begin(), choice->choices.end(), [&](const auto& w) { return w.first == v; });
      if (word == choice->choices.end()) return bad(quoted(v) + " is not " + choice->words);
      word->second(*o);
    } else if (a == "--help" || a == "-h" || a == "--param-table") {
      if (a == "--param-table") std::fputs(paramTableMarkdown().c_str(), stdout);  // docs/parameters.md
      else printHelp();
      return 1;
    } else if (a == "--scene") {
      if (!takes()) return bad("needs a name: shrub, tree, grass, kelp, field");
      const Status s = parseSceneKind(v, &o->scene);
      if (!s.ok()) return bad(quoted(v) + " is not one of shrub, tree, grass, kelp, field");
    } else if (a == "--faces") {
      if (!takes() || !cli::parseCount(v, kMinSceneFaces, kMaxSceneFaces, &o->faces))
        return bad("needs a count in [" + std::to_string(kMinSceneFaces) + ", " + std::to_string(kMaxSceneFaces) + "]");
    } else if (a == "--seed") {
      if (!takes() || !cli::parseUint(v, 0, 0xffffffffull, &o->seed)) return bad("needs an integer in [0, 4294967295]");
    } else if (a == "--gltf") {
      if (!takes()) return bad("needs a file");
      o->gltf = v;
    } else if (a == "--scene-file") {
      if (!takes()) return bad("needs a file");
      o->sceneFile = v;
    } else if (a == "--rigid" || a == "--foliage") {
      if (!takes() || !*v) return bad("needs material names or #indices, comma-separated");
      (a == "--rigid" ? o->split.rigid : o->split.foliage) = cli::splitList(v);
    } else if (std::string why; const int c = cli::parseCacheOption(argc, argv, &i, &o->cache, &why)) {
      if (c < 0) {
        *err = why;
        return 2;
      }
    } else if (a == "--layers") {
      LayerLayout l;
      if (!takes()) return bad("needs a layout such as 5(3-1-1) or 3");
      const Status s = parseLayerLayout(v, &l);
      if (!s.ok()) {
        return bad(quoted(v) + ": " + s.message());
      }
      o->layout = v;
    } else if (a == "--wind") {
      if (!takes()) return bad("needs sides: left,right,top,bottom or none");
      uint32_t sides = 0;
      if (std::string(v) != "none")
        for (const std::string& side : cli::splitList(v)) {
          if (side == "left") sides |= kWindFromLeft;
          else if (side == "right") sides |= kWindFromRight;
          else if (side == "top") sides |= kWindFromTop;
          else if (side == "bottom") sides |= kWindFromBottom;
          else return bad("side '" + side + "' is not left, right, top or bottom");
        }
      o->windSides = sides;
      o->planeSides = true;
    } else if (a == "--wind-dir") {
      const std::vector<std::string> parts = takes() ? cli::splitList(v) : std::vector<std::string>();
      float x[3] = {0, 0, 0};
      bool good = parts.size() == 3;
      for (size_t k = 0; good && k < 3; ++k) good = cli::parseFloat(parts[k].c_str(), &x[k]) && std::abs(x[k]) <= 1e6f;
      if (!good || x[0] * x[0] + x[1] * x[1] + x[2] * x[2] <= 0.0f) return bad("needs X,Y,Z, three finite numbers, not all 0");
      o->windDirection = Float3{x[0], x[1], x[2]};
    } else if (a == "--light" || a == "--light-color") {
      const bool colour = a == "--light-color";
      const std::vector<std::string> parts = takes() ? cli::splitList(v) : std::vector<std::string>();
      float x[3] = {0, 0, 0};
      bool good = parts.size() == 3;
      for (size_t k = 0; good && k < 3; ++k)
        good = cli::parseFloat(parts[k].c_str(), &x[k]) && (colour ? x[k] >= 0 && x[k] <= 1000 : std::abs(x[k]) <= 1e6f);
      if (!good) return bad(colour ? "needs R,G,B, each in [0, 1000]" : "needs X,Y,Z, three finite numbers");
      (colour ? o->lightColor : o->light) = Float3{x[0], x[1], x[2]};
    } else if (a == "--size") {
      unsigned w = 0, h = 0;
      char tail = 0;
      if (!takes() || std::sscanf(v, "%ux%u%c", &w, &h, &tail) != 2 || w < 16 || h < 16 || w > 8192 || h > 8192)
        return bad("needs WxH with each side in [16, 8192]");
      o->width = w;
      o->height = h;
    } else if (a == "--frames") {
      if (!takes() || !cli::parseUint(v, 1, 100000, &o->frames)) return bad("needs an integer in [1, 100000]");
      framesGiven = true;
    } else if (a == "--camera") {
      if (!takes()) return bad("needs a path: still, orbit, dolly, strafe, turn, zoom, walk");
      const Status s = parseCameraMotion(v, &o->camera);
      if (!s.ok()) return bad(s.message());
    } else if (a == "--degrees-per-frame") {
      if (const int rc = number(-90, 90, &o->degreesPerFrame)) return rc;
      o->degreesGiven = true;
    } else if (a == "--compare-frames") {
      if (i + 2 >= argc || !*argv[i + 1] || !*argv[i + 2]) return bad("needs two folders");
      o->compareA = argv[++i];
      o->compareB = argv[++i];
    } else if (a == "--measure-foliage") {
      if (i + 2 >= argc || !*argv[i + 1] || !*argv[i + 2]) return bad("needs two folders");
      o->foliageWind = argv[++i];
      o->foliageStill = argv[++i];
    } else if (a == "--out") {
      if (!takes() || !*v) return bad("needs a folder");
      o->outDir = v;
    } else if (a == "--screenshot") {
      if (!takes() || !*v) return bad("needs a file");
      o->screenshot = v;
    } else if (a == "--resize-at") {
      if (!takes() || !cli::parseUint(v, 0, 100000, &o->resizeAt)) return bad("needs an integer in [0, 100000]");
    } else if (a == "--device") {
      if (!takes()) return bad("needs a device name");
      o->device = v;
    } else if (a == "--inject-fault") {
      fault::Mode mode;
      int64_t n;
      if (!takes() || !fault::parse(v, &mode, &n)) return bad("needs oom:N or lost:N (N a count of successful creations)");
      o->injectFault = v;
    } else {
      *err = "unknown option '" + a + "' (see --help)";
      return 2;
    }
  }
  if (o->window && !framesGiven) o->frames = 0;  // window: until closed
  return 0;
}

// ---- scene and camera -------------------------------------------------------------------------

namespace {
// A scene file's species (each loaded or generated once) and copies; `model` gets the copies'
// world bounds for the camera.
Status loadSceneFile(const Options& o, VegetationModel* model, std::string* label, SceneCopies* out) {
  const auto t0 = std::chrono::steady_clock::now();
  CanopyScene scene;
  CANOPY_TRY(readCanopyScene(o.sceneFile, &scene));
  *out = SceneCopies{};
  out->models.resize(scene.species.size());
  uint64_t triangles = 0;
  for (size_t i = 0; i < scene.species.size(); ++i) {
    const CanopySceneSpecies& sp = scene.species[i];
    VegetationModel& m = out->models[i];
    if (!sp.gltf.empty()) {
      CANOPY_TRY(loadGltf(sp.gltf, {}, &m).context(o.sceneFile + ": species '" + sp.name + "'"));
      for (const std::string& w : m.warnings) std::fprintf(stderr, "  warning: %s: %s\n", sp.name.c_str(), w.c_str());
    } else {
      SceneDesc d;
      CANOPY_TRY(parseSceneKind(sp.generated, &d.kind).context(o.sceneFile + ": species '" + sp.name + "'"));
      if (sp.faces) d.faces = sp.faces;
      d.seed = sp.seed;
      SceneStats st;
      CANOPY_TRY(generateScene(d, &m, &st).context(o.sceneFile + ": species '" + sp.name + "'"));
    }
    triangles += m.triangleCount();
    const glm::vec3 size = m.boundsMax - m.boundsMin;
    std::fprintf(stderr, "  species '%s': %zu triangles, %.2f x %.2f x %.2f (x y z) from %.2f %.2f %.2f, flexibility %.2f, "
                         "response speed %.2f\n",
                 sp.name.c_str(), m.triangleCount(), size.x, size.y, size.z, m.boundsMin.x, m.boundsMin.y, m.boundsMin.z,
                 sp.flexibility, sp.responseSpeed);
  }
  for (size_t i = 0; i < scene.species.size(); ++i)
    out->species.push_back({&out->models[i], scene.species[i].flexibility, scene.species[i].responseSpeed});
  *model = VegetationModel{};
  model->path = o.sceneFile;
  model->boundsMin = glm::vec3(INFINITY);
  model->boundsMax = glm::vec3(-INFINITY);
  std::vector<Float3> lo, hi;
  for (const VegetationModel& m : out->models) {
    lo.push_back(toFloat3(m.boundsMin));
    hi.push_back(toFloat3(m.boundsMax));
  }
  CANOPY_TRY(sceneCopies(scene, lo, hi, &out->instances));
  uint64_t placed = 0;
  for (const CanopyInstance& c : out->instances) {
    const VegetationModel& m = out->models[c.species];
    placed += m.triangleCount();
    const glm::mat4 t = toGlm(c.transform);
    for (int k = 0; k < 8; ++k) {
      const glm::vec3 p((k & 1) ? m.boundsMax.x : m.boundsMin.x, (k & 2) ? m.boundsMax.y : m.boundsMin.y,
                        (k & 4) ? m.boundsMax.z : m.boundsMin.z);
      const glm::vec3 w(t * glm::vec4(p, 1.0f));
      model->boundsMin = glm::min(model->boundsMin, w);
      model->boundsMax = glm::max(model->boundsMax, w);
    }
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::fprintf(stderr, "scene %s: %zu species (%llu triangles stored), %zu copies (%llu triangles placed, world bounds %.1f %.1f %.1f .. "
                       "%.1f %.1f %.1f) in %.2f s\n",
               o.sceneFile.c_str(), scene.species.size(), (unsigned long long)triangles, out->instances.size(),
               (unsigned long long)placed, model->boundsMin.x, model->boundsMin.y, model->boundsMin.z, model->boundsMax.x,
               model->boundsMax.y, model->boundsMax.z, s);
  *label = o.sceneFile;
  return Status();
}
}  // namespace

Status loadScene(const Options& o, VegetationModel* model, std::string* label, SceneCopies* copies) {
  if (!o.sceneFile.empty()) return loadSceneFile(o, model, label, copies);
  const auto t0 = std::chrono::steady_clock::now();
  auto seconds = [&]() { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };
  if (!o.gltf.empty()) {
    std::fprintf(stderr, "loading %s ...\n", o.gltf.c_str());
    CANOPY_TRY(loadGltf(o.gltf, {}, model));
    const double s = seconds();
    std::fprintf(stderr, "loaded %s: %zu triangles, %zu materials in %.2f s (%.2fM triangles/s)\n", o.gltf.c_str(),
                 model->triangleCount(), model->materials.size(), s, double(model->triangleCount()) / std::max(s, 1e-6) / 1e6);
    for (const std::string& w : model->warnings) std::fprintf(stderr, "  warning: %s\n", w.c_str());
    *label = o.gltf;
    return Status();
  }
  // Generating and preparing a scene peaks at 144 bytes per face for the 50M shrub (VmHWM of
  // `canopy-demo --scene shrub --faces 50M`: 6.70 GiB) and 203 for 10M (1.89 GiB: a resident mesh
  // counts twice on a CPU driver, whose GPU buffers are host memory); 350 keeps a margin for other
  // scenes and drivers. Refuse what cannot fit instead of being killed by the OOM killer half-way.
  constexpr uint64_t kPeakBytesPerFace = 350;
  const uint64_t available = cli::availableMemoryBytes();
  if (available > 0 && o.faces * kPeakBytesPerFace > available)
    return Status::error("--faces " + std::to_string(o.faces) + " needs about " +
                         std::to_string((o.faces * kPeakBytesPerFace + (1ull << 29)) >> 30) +
                         " GiB of memory to generate and prepare (about 350 bytes per face); this machine has " +
                         std::to_string((available + (1ull << 29)) >> 30) + " GiB available");
  SceneDesc d;
  d.kind = o.scene;
  d.faces = o.faces;
  d.seed = o.seed;
  d.hierarchy = bothMethods(o);
  d.boxes = withImpostors(o);
  SceneStats st;
  cli::ProgressLine progress(std::string("generating ") + sceneName(o.scene));
  CANOPY_TRY(generateScene(d, model, &st, o.faces >= 1'000'000 ? SceneProgress(std::ref(progress)) : SceneProgress()));
  std::fprintf(stderr, "generated %s: %llu faces (%llu rigid, %llu leaves) in %.2f s\n", sceneName(o.scene),
               (unsigned long long)st.faces, (unsigned long long)st.rigidFaces, (unsigned long long)st.leaves, seconds());
  *label = std::string(sceneName(o.scene)) + " " + std::to_string(st.faces) + " faces";
  return Status();
}

CanopyPusher pusherAt(PusherPath path, const glm::vec3& lo, const glm::vec3& hi, const glm::vec3& cameraRight, uint32_t i,
                      uint32_t frames, float fps, float windStrength) {
  // A sphere a twelfth of the scene's width across, half sunk into the ground, walking over the
  // written frames: along the camera's right through the centre, or once around a circle.
  const glm::vec3 c = 0.5f * (lo + hi);
  const float extent = std::max(hi.x - lo.x, hi.z - lo.z);
  const float radius = extent / 24.0f;
  const float t = frames > 1 ? float(i) / float(frames - 1) : 0.0f, seconds = float(std::max(frames, 2u) - 1) / fps;
  glm::vec3 right(cameraRight.x, 0.0f, cameraRight.z);
  right = glm::length(right) > 1e-6f ? glm::normalize(right) : glm::vec3(1.0f, 0.0f, 0.0f);
  glm::vec3 p, v;
  if (path == PusherPath::Circle) {
    const glm::vec3 fwd = glm::cross(glm::vec3(0.0f, 1.0f, 0.0f), right);
    const float a = 6.2831853f * t, r = 0.3f * extent;
    p = c + r * (std::cos(a) * right + std::sin(a) * fwd);
    v = (r * 6.2831853f / seconds) * (-std::sin(a) * right + std::cos(a) * fwd);
  } else {
    p = c + (0.8f * t - 0.4f) * extent * right;
    v = (0.8f * extent / seconds) * right;
  }
  p.y = lo.y + 0.5f * radius;
  CanopyPusher out;
  out.a = out.b = toFloat3(p);
  out.radius = radius;
  out.velocity = toFloat3(v);
  // Twice as far as the demo's wind (--strength, domain units/s) bends the grass: bend 1 is 0.5 of them.
  out.bend = std::clamp(4.0f * windStrength, 1.0f, 16.0f);
  return out;
}

std::string windText(const Options& o) {
  char t[256];
  if (o.planeSides)
    std::snprintf(t, sizeof t, "plane sides %u at %.2f domain units/s, %.2f Hz (modulation %.2f, gust %.2f)", o.windSides,
                  double(o.windStrength), double(o.windFrequency), double(o.windModulation), double(o.windGust));
  else
    std::snprintf(t, sizeof t, "%.2f m/s toward (%.2f, %.2f, %.2f), gusts %.2f at %.2f Hz, turbulence %.2f", double(o.windSpeed),
                  double(o.windDirection.x), double(o.windDirection.y), double(o.windDirection.z), double(o.gustIntensity),
                  double(o.gustFrequency), double(o.turbulence));
  return t;
}

float domainWindSpeed(const Options& o) {
  return o.planeSides ? o.windStrength : o.windSpeed / WorldWind{}.tileMetres;
}

CameraRig defaultRig(const Options& o) {
  CameraRig r;
  r.yaw += o.yawDegrees;
  if (!o.sceneFile.empty()) {
    r.pitch = 14.0f;
    r.distance = 0.7f;
  } else if (o.gltf.empty()) {
    switch (o.scene) {
      case SceneKind::GrassField: r.pitch = 28.0f; r.distance = 0.75f; break;
      case SceneKind::Field: r.pitch = 22.0f; r.distance = 0.8f; break;
      case SceneKind::Kelp: r.pitch = 8.0f; r.distance = 0.8f; break;
      default: r.distance = 0.7f; break;
    }
  }
  return r;
}

LayerView cameraView(const CameraRig& rig, const VegetationModel& m, uint32_t w, uint32_t h) {
  return orbitView(m.boundsMin, m.boundsMax, rig.yaw, rig.pitch, rig.fov, float(w) / float(h), rig.distance);
}

CameraPath cameraPathOf(const Options& o, const CameraRig& rig) {
  CameraPath p;
  p.motion = o.camera;
  p.degreesPerFrame = o.degreesPerFrame;
  if (o.camera == CameraMotion::Orbit && !o.degreesGiven)
    p.degreesPerFrame = o.frames > 1 ? o.orbitDegrees / float(o.frames - 1) : 0.0f;
  p.radiiPerFrame = o.radiiPerFrame;
  p.amplitudeDegrees = o.swingDegrees;
  p.yaw = rig.yaw;
  p.pitch = rig.pitch;
  p.fovY = rig.fov;
  p.distanceScale = rig.distance;
  return p;
}

glm::vec3 skySrgb(const Options& o) {
  return o.gltf.empty() && o.sceneFile.empty() && o.scene == SceneKind::Kelp ? glm::vec3(0.12f, 0.32f, 0.45f)  // water
                                                      : glm::vec3(0.62f, 0.75f, 0.88f);
}

CanopyParams paramsFrom(const Options& o, const CanopyParams& base) {
  CanopyParams p = base;
  if (!parseLayerLayout(o.layout, &p.layers.layout).ok()) p.layers.layout = base.layers.layout;  // checked by parseOptions
  p.windMode = o.planeSides ? WindMode::PlaneSides : WindMode::World;
  p.wind.direction = o.windDirection;
  p.wind.speed = o.windSpeed;
  p.wind.gustIntensity = o.gustIntensity;
  p.wind.gustFrequency = o.gustFrequency;
  p.wind.turbulence = o.turbulence;
  p.wind.sway = o.sway;
  p.simulation.wind.sides = o.windSides;
  p.simulation.wind.strength = o.windStrength;
  p.simulation.wind.frequency = o.windFrequency;
  p.simulation.wind.modulation = o.windModulation;
  p.simulation.wind.gust = o.windGust;
  p.dynamics.delay = o.delay;
  p.animation = o.method;
  p.perVertex.wind = o.perVertexWind;
  p.layers.rebuildBudgetMs = o.rebuildBudgetMs;
  p.layers.errorThresholdPixels = o.resliceErrorPixels;
  p.layers.halfResolutionLayers = uint32_t(o.halfResolutionLayers);
  p.composite.depthSearchSteps = uint32_t(o.depthSearchSteps);
  p.layers.policy = o.reslice;
  p.layers.lightDirection = o.light;
  p.layers.lightColor = o.lightColor;
  p.layers.ambient = o.ambient;
  p.layers.leafRefractiveIndex = o.leafIor;
  p.layers.leafRoughness = o.leafRoughness;
  p.layers.leafTransmission = o.leafTransmission;
  p.layers.translucency = o.translucency;
  p.layers.impostors.mode = o.impostors;
  p.layers.impostors.switchPixels = o.impostorPixels;
  p.layers.impostors.debugView = o.impostorDebug;
  p.layers.impostors.shape = o.impostorShape;
  p.composite.debugView = o.debug;
  p.composite.bilinear = o.bilinear;
  p.composite.sharpness = o.sharpness;
  p.dynamics.maxStretch = o.maxStretch;
  p.composite.debugVelocityScale = std::max(0.05f, domainWindSpeed(o));
  return p;
}

// ---- host ---------------------------------------------------------------------------------------

namespace {

Status buildGraph(Host& h) {
  h.graph.release(*h.device);
  h.graph = rg::RenderGraph();
  rg::RenderGraph& g = h.graph;
  h.presentTarget = rg::kInvalidResource;
  h.readbackId = rg::kInvalidResource;
  const rg::State colorAfter = h.wantsReadback || h.presentFormat != VK_FORMAT_UNDEFINED
                                   ? rg::stateOf(rg::Use::TransferSrc)
                                   : rg::stateOf(rg::Use::ColorAttachmentReadWrite);
  CompositeTargets t;
  // They arrive as the previous frame (maybe still executing) left them: its last accesses are
  // ordered before this frame's clear (createTargets put them in these states once).
  const rg::State depthAfter = rg::stateOf(rg::Use::DepthAttachmentWrite);
  t.color = g.importImage("demo colour", descOf(h.color), colorAfter, colorAfter);
  t.depth = g.importImage("demo depth", descOf(h.depth), depthAfter, depthAfter);
  const glm::vec4 clear = h.clear;
  g.addPass("demo: clear", [t, clear](rg::PassContext& x) {
     const VkClearColorValue cv{{clear.r, clear.g, clear.b, clear.a}};
     const VkClearDepthStencilValue dv{1.0f, 0};
     const VkImageSubresourceRange cr{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}, dr{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
     vkCmdClearColorImage(x.cmd, x.image(t.color).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &cv, 1, &cr);
     vkCmdClearDepthStencilImage(x.cmd, x.image(t.depth).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &dv, 1, &dr);
     return Status();
   })
      .write(t.color, rg::Use::TransferDst)
      .write(t.depth, rg::Use::TransferDst)
      .sideEffect();
  CANOPY_TRY(g.bindImage(t.color, h.color));
  CANOPY_TRY(g.bindImage(t.depth, h.depth));
  if (h.shadow.on) {
    // The ground under the vegetation, lit through the shadow map Canopy drew after the previous
    // frame (the map rests sampled; recordCanopyShadow leaves it so).
    const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
    const auto map = g.importImage("demo: shadow map", descOf(h.shadow.map), sampled, sampled);
    CANOPY_TRY(g.bindImage(map, h.shadow.map));
    Host* hp = &h;
    g.addPass("demo: ground", [hp, t](rg::PassContext& x) {
       beginHostRendering(x, t, hp->width, hp->height, false);
       const Host::Shadow& sh = hp->shadow;
       Status st = bindGraphics(*x.device, x.cmd, sh.ground,
                                {bindBuffer(sh.groundFrame.buffer),
                                 bindImage(sh.map.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL, sh.sampler)},
                                sh.viewProj);
       if (st.ok()) vkCmdDraw(x.cmd, 6, 1, 0, 0);
       x.device->cmdEndRendering(x.cmd);
       return st;
     })
        .write(t.color, rg::Use::ColorAttachmentReadWrite)
        .write(t.depth, rg::Use::DepthAttachmentWrite)
        .read(map, rg::Use::FragmentSampled)
        .sideEffect();
  }
  CANOPY_TRY(addCanopyPasses(h.canopy, g, t));
  if (h.presentFormat != VK_FORMAT_UNDEFINED) {
    // The swapchain image arrives undefined (its old contents are not needed) and leaves ready to present.
    const rg::State present{VK_PIPELINE_STAGE_2_ALL_COMMANDS_BIT, VK_ACCESS_2_NONE, VK_IMAGE_LAYOUT_PRESENT_SRC_KHR};
    ImageDesc pd;
    pd.format = h.presentFormat;
    pd.width = h.width;
    pd.height = h.height;
    pd.usage = VK_IMAGE_USAGE_TRANSFER_DST_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT;
    h.presentTarget = g.importImage("swapchain image", pd, {}, present);
    const uint32_t w = h.width, ht = h.height;
    const rg::ResourceId dst = h.presentTarget;
    g.addPass("demo: blit to swapchain", [t, dst, w, ht](rg::PassContext& x) {
       VkImageBlit b{};
       b.srcSubresource = b.dstSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
       b.srcOffsets[1] = b.dstOffsets[1] = {int32_t(w), int32_t(ht), 1};
       vkCmdBlitImage(x.cmd, x.image(t.color).image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, x.image(dst).image,
                      VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &b, VK_FILTER_NEAREST);
       return Status();
     })
        .read(t.color, rg::Use::TransferSrc)
        .write(dst, rg::Use::TransferDst)
        .sideEffect();
  }
  if (h.wantsReadback) {
    const rg::State hostRead = rg::stateOf(rg::Use::HostRead);
    const auto rb = g.importBuffer("demo readback", h.readback[0].size, hostRead, hostRead);
    h.readbackId = rb;  // bound per frame to its slot's buffer
    const uint32_t w = h.width, ht = h.height;
    // From the swapchain image when there is one (the window's screenshot is what was presented).
    const rg::ResourceId src = h.presentTarget != rg::kInvalidResource ? h.presentTarget : t.color;
    g.addPass("demo: copy to host", [src, rb, w, ht](rg::PassContext& x) {
       VkBufferImageCopy r{};
       r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
       r.imageExtent = {w, ht, 1};
       vkCmdCopyImageToBuffer(x.cmd, x.image(src).image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, x.buffer(rb), 1, &r);
       return Status();
     })
        .read(src, rg::Use::TransferSrc)
        .write(rb, rg::Use::TransferDst)
        .sideEffect();
  }
  CANOPY_TRY(g.compile());
  CANOPY_TRY(g.realize(*h.device));
  h.graphGeneration = canopyResourceGeneration(h.canopy);
  return Status();
}

}  // namespace

namespace {

// The host's own colour (sRGB: the layers hold linear colour, so the PNG bytes and the swapchain
// show the colours the textures were painted with), depth and read-back buffer at the host's size.
Status createTargets(Host& host) {
  Device& d = *host.device;
  ImageDesc c;
  c.format = VK_FORMAT_R8G8B8A8_SRGB;
  c.width = host.width;
  c.height = host.height;
  c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, c, &host.color, "demo colour"));
  c.format = VK_FORMAT_D32_SFLOAT;
  c.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, c, &host.depth, "demo depth"));
  if (host.wantsReadback)
    for (Buffer& b : host.readback)
      CANOPY_TRY(createBuffer(d, VkDeviceSize(host.width) * host.height * 4, VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                              MemoryUsage::Readback, &b, "demo readback"));
  // Once, at creation: the targets go into the states every frame's graph imports them in.
  const bool copies = host.wantsReadback || host.presentFormat != VK_FORMAT_UNDEFINED;
  rg::RenderGraph g;
  const auto ci = g.importImage("demo colour", descOf(host.color), {},
                               rg::stateOf(copies ? rg::Use::TransferSrc : rg::Use::ColorAttachmentReadWrite));
  const auto zi = g.importImage("demo depth", descOf(host.depth), {}, rg::stateOf(rg::Use::DepthAttachmentWrite));
  g.addPass("demo: first clear", [ci, zi](rg::PassContext& x) {
     const VkClearColorValue cv{};
     const VkClearDepthStencilValue dv{1.0f, 0};
     const VkImageSubresourceRange cr{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1}, dr{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
     vkCmdClearColorImage(x.cmd, x.image(ci).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &cv, 1, &cr);
     vkCmdClearDepthStencilImage(x.cmd, x.image(zi).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &dv, 1, &dr);
     return Status();
   })
      .write(ci, rg::Use::TransferDst)
      .write(zi, rg::Use::TransferDst);
  CANOPY_TRY(g.bindImage(ci, host.color));
  CANOPY_TRY(g.bindImage(zi, host.depth));
  CANOPY_TRY(g.compile());
  CANOPY_TRY(g.realize(d));
  return submitAndWait(d, [&](VkCommandBuffer cmd) { return g.record(cmd); });
}

void destroyTargets(Host& h) {
  Device& d = *h.device;
  h.graph.release(d);
  h.graph = rg::RenderGraph();
  h.graphGeneration = ~0ull;
  destroyImage(d, h.color);
  destroyImage(d, h.depth);
  for (Buffer& b : h.readback) destroyBuffer(d, b);
}

}  // namespace

namespace {

// --shadows: the ground under the scene's bounds (wide enough for the shadow of its height), the sun's
// orthographic view around the ground and the vegetation, the shadow map, the ground's pipeline and
// (with a read-back) the map's copy per slot.
Status createShadow(Host& host, const VegetationModel& model, const Options& o) {
  Device& d = *host.device;
  Host::Shadow& sh = host.shadow;
  sh.on = true;
  sh.readback = host.wantsReadback;
  const glm::vec3 lo = model.boundsMin, hi = model.boundsMax, ext = hi - lo;
  sh.groundCenter = glm::vec3(0.5f * (lo.x + hi.x), lo.y, 0.5f * (lo.z + hi.z));
  sh.groundHalf = 0.5f * std::max(ext.x, ext.z) + ext.y;
  glm::vec3 l(o.light.x, o.light.y, o.light.z);
  l = glm::length(l) > 0.0f ? glm::normalize(l) : glm::vec3(0, 1, 0);
  const glm::vec3 centre(sh.groundCenter.x, lo.y + 0.5f * ext.y, sh.groundCenter.z);
  const float reach = glm::length(glm::vec3(sh.groundHalf, ext.y, sh.groundHalf));
  const glm::mat4 view = glm::lookAt(centre + l * (2.0f * reach), centre, std::abs(l.y) > 0.99f ? glm::vec3(0, 0, 1) : glm::vec3(0, 1, 0));
  // The map spans the casters only (the ground outside it reads the cleared edge: lit), so its
  // texels go to the vegetation.
  glm::vec3 vlo(INFINITY), vhi(-INFINITY);
  for (int k = 0; k < 8; ++k) {
    const glm::vec3 p(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z);
    const glm::vec3 q(view * glm::vec4(p, 1.0f));
    vlo = glm::min(vlo, q);
    vhi = glm::max(vhi, q);
  }
  const glm::vec2 pad = 0.02f * glm::vec2(vhi - vlo);
  sh.light = glm::orthoRH_ZO(vlo.x - pad.x, vhi.x + pad.x, vlo.y - pad.y, vhi.y + pad.y, -vhi.z - 0.01f * reach, -vlo.z + 0.01f * reach) * view;
  ImageDesc m;
  m.format = VK_FORMAT_D32_SFLOAT;
  m.width = m.height = Host::Shadow::kSize;
  m.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
            VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, m, &sh.map, "demo: shadow map"));
  VkSamplerCreateInfo si{VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO};
  si.magFilter = si.minFilter = VK_FILTER_NEAREST;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  CANOPY_VK(vkCreateSampler(d.device, &si, nullptr, &sh.sampler));
  struct GroundFrame {
    glm::mat4 light;
    glm::vec4 origin, u, v, albedo, lightTexel;
  } gf{sh.light, glm::vec4(sh.groundCenter, 1.0f), glm::vec4(sh.groundHalf, 0, 0, 0), glm::vec4(0, 0, sh.groundHalf, 0),
       glm::vec4(0.45f, 0.45f, 0.45f, 0.35f), glm::vec4(l, 1.0f / float(Host::Shadow::kSize))};
  CANOPY_TRY(createBuffer(d, sizeof gf, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUsage::Upload, &sh.groundFrame, "demo: ground"));
  void* mapped = hostCoherentPointer(d, sh.groundFrame.allocation);
  if (!mapped) return Status::error("demo: the ground's buffer is not host-visible");
  std::memcpy(mapped, &gf, sizeof gf);
  GraphicsPipelineDesc gp;
  gp.vertexShader = "demo_ground.vert";
  gp.fragmentShader = "demo_ground.frag";
  gp.shaderLookup = canopy_demo::findEmbeddedShader;
  gp.pushConstantSize = sizeof(glm::mat4);
  gp.colorFormats = {VK_FORMAT_R8G8B8A8_SRGB};
  gp.depthFormat = VK_FORMAT_D32_SFLOAT;
  CANOPY_TRY(createGraphicsPipeline(d, gp, &sh.ground));
  // Once: the map cleared (nothing casts yet) into the state every frame imports it in.
  {
    rg::RenderGraph g;
    const auto mi = g.importImage("demo: shadow map", descOf(sh.map), {}, rg::stateOf(rg::Use::FragmentSampled));
    g.addPass("demo: shadow map's first clear", [mi](rg::PassContext& x) {
       const VkClearDepthStencilValue dv{1.0f, 0};
       const VkImageSubresourceRange dr{VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
       vkCmdClearDepthStencilImage(x.cmd, x.image(mi).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &dv, 1, &dr);
       return Status();
     }).write(mi, rg::Use::TransferDst);
    CANOPY_TRY(g.bindImage(mi, sh.map));
    CANOPY_TRY(g.compile());
    CANOPY_TRY(g.realize(d));
    CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) { return g.record(cmd); }));
  }
  if (!sh.readback) return Status();
  const VkDeviceSize bytes = VkDeviceSize(Host::Shadow::kSize) * Host::Shadow::kSize * 4;
  for (Buffer& b : sh.mapReadback)
    CANOPY_TRY(createBuffer(d, bytes, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUsage::Readback, &b, "demo: shadow map read-back"));
  rg::RenderGraph& g = sh.copy;
  const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled), hostRead = rg::stateOf(rg::Use::HostRead);
  const auto mi = g.importImage("demo: shadow map", descOf(sh.map), sampled, sampled);
  sh.copyTarget = g.importBuffer("demo: shadow map read-back", bytes, hostRead, hostRead);
  const rg::ResourceId rb = sh.copyTarget;
  g.addPass("demo: shadow map to host", [mi, rb](rg::PassContext& x) {
     VkBufferImageCopy r{};
     r.imageSubresource = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 0, 1};
     r.imageExtent = {Host::Shadow::kSize, Host::Shadow::kSize, 1};
     vkCmdCopyImageToBuffer(x.cmd, x.image(mi).image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, x.buffer(rb), 1, &r);
     return Status();
   })
      .read(mi, rg::Use::TransferSrc)
      .write(rb, rg::Use::TransferDst)
      .sideEffect();
  CANOPY_TRY(g.bindImage(mi, sh.map));
  CANOPY_TRY(g.bindBuffer(rb, sh.mapReadback[0].buffer));
  CANOPY_TRY(g.compile());
  return g.realize(d);
}

void destroyShadow(Host& h) {
  Device& d = *h.device;
  Host::Shadow& sh = h.shadow;
  sh.copy.release(d);
  for (Buffer& b : sh.mapReadback) destroyBuffer(d, b);
  destroyGraphicsPipeline(d, sh.ground);
  destroyBuffer(d, sh.groundFrame);
  if (sh.sampler) vkDestroySampler(d.device, sh.sampler, nullptr);
  destroyImage(d, sh.map);
  sh = Host::Shadow{};
}

}  // namespace

Status createHost(Device& d, const VegetationModel& model, const Options& o, uint32_t w, uint32_t h, bool readback,
                  VkFormat presentFormat, Host* out) {
  Host& host = *out;
  host.device = &d;
  host.width = w;
  host.height = h;
  host.wantsReadback = readback;
  host.presentFormat = presentFormat;
  auto linear = [](float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); };
  const glm::vec3 sky = skySrgb(o);
  host.clear = glm::vec4(linear(sky.r), linear(sky.g), linear(sky.b), 1.0f);
  host.clearSrgb = sky;
  CANOPY_TRY(createTargets(host));
  for (GpuTimer& t : host.timer) CANOPY_TRY(t.init(d, 64));
  CanopyDesc desc;
  desc.width = w;
  desc.height = h;
  desc.colorFormat = VK_FORMAT_R8G8B8A8_SRGB;
  // A generated scene has no file to key a cache by. A loaded model's caches go to the folder
  // main() resolved (the user's cache folder unless the options say otherwise).
  LayerLayout layout;
  if (parseLayerLayout(o.layout, &layout).ok()) desc.maxLayers = std::max(desc.maxLayers, layout.count());
  desc.rootCacheDir = o.cacheFolder;
  desc.cacheMaxBytes = uint64_t(o.cache.maxMiB) << 20;
  desc.split = o.split;
  desc.deviceMemoryBudget = uint64_t(double(o.deviceBudgetMiB) * double(1 << 20));
  desc.guardBand = o.guardBand;
  desc.meshStagingRingBytes = uint64_t(double(o.ringMiB) * double(1 << 20));
  desc.allowPerVertex = bothMethods(o);
  desc.impostors.enable = withImpostors(o);
  desc.impostors.views = o.impostorViews;
  // The preparation's own peak above what is resident before it (the model): issue 16's
  // "bytes per face" of preparation, printed below.
  const uint64_t residentBefore = cli::residentBytes();
  const bool peakReset = cli::resetPeakResident();
  const auto t0 = std::chrono::steady_clock::now();
  cli::ProgressLine progress("preparing");
  if (model.triangleCount() >= 1'000'000) {
    std::fprintf(stderr, "preparing %zu triangles (material split, leaf roots, GPU upload) ...\n", model.triangleCount());
    desc.progress = std::ref(progress);
  }
  // A scene file's species in one vegetation, its copies placed (docs/scene-files.md).
  const SceneCopies* copies = o.copies.get();
  if (copies) desc.instances = copies->instances;
  auto create = [&]() {
    return copies ? createCanopy(d, copies->species, desc, &host.canopy) : createCanopy(d, model, desc, &host.canopy);
  };
  Status made = create();
  if (!made.ok() && desc.allowPerVertex && o.method != AnimationMode::PerVertex) {
    // The window offers both methods; a mesh the baseline cannot keep resident runs 2D only.
    std::fprintf(stderr, "canopy-demo: the per-vertex baseline is off for this scene (%s)\n", made.message().c_str());
    desc.allowPerVertex = false;
    made = create();
  }
  if (!made.ok())
    return made.context(std::to_string(w) + "x" + std::to_string(h) + " frame, " + std::to_string(desc.maxLayers) + " layers at most");
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (model.triangleCount() >= 1'000'000)
    std::fprintf(stderr, "prepared %zu triangles (material split, leaf roots, GPU upload) in %.2f s (%.2fM/s)\n",
                 model.triangleCount(), s, double(model.triangleCount()) / std::max(s, 1e-6) / 1e6);
  if (peakReset) {
    const uint64_t peak = cli::procKilobytes("/proc/self/status", "VmHWM");
    const double faces = double(std::max<size_t>(model.triangleCount(), 1));
    std::fprintf(stderr,
                 "preparation memory: model %.2f GiB resident before (%.1f bytes per face), peak %.2f GiB above it "
                 "(%.1f bytes per face), %.1f bytes per face kept after it\n",
                 double(residentBefore) / double(1ull << 30), double(residentBefore) / faces,
                 double(peak - std::min(peak, residentBefore)) / double(1ull << 30),
                 double(peak - std::min(peak, residentBefore)) / faces,
                 double(cli::residentBytes() - std::min(cli::residentBytes(), residentBefore)) / faces);
  }
  if (!desc.rootCacheDir.empty() && !model.path.empty()) {
    // What became of the caches, why one was not used (a line each).
    const CanopyStats st = canopyStats(host.canopy);
    std::printf("cache: leaf roots: %s\n", st.layers.rootCacheNote.c_str());
    if (desc.impostors.enable) std::printf("cache: impostor views: %s\n", st.layers.impostorCacheNote.c_str());
  }
  CANOPY_TRY(setCanopyParams(host.canopy, paramsFrom(o, canopyParams(host.canopy))));
  if (o.shadows) CANOPY_TRY(createShadow(host, model, o));
  return Status();
}

Status resizeHost(Host& host, uint32_t width, uint32_t height, VkFormat presentFormat) {
  vkDeviceWaitIdle(host.device->device);
  destroyTargets(host);
  host.width = width;
  host.height = height;
  host.presentFormat = presentFormat;
  CANOPY_TRY(createTargets(host));
  return resizeCanopy(host.canopy, width, height);
}

void destroyHost(Host& h) {
  if (!h.device) return;
  Device& d = *h.device;
  vkDeviceWaitIdle(d.device);
  destroyTargets(h);
  for (GpuTimer& t : h.timer) t.destroy(d);
  if (h.shadow.on) destroyShadow(h);
  destroyCanopy(h.canopy);
  h.canopy = nullptr;
  h.device = nullptr;
}

Status recordHostFrame(Host& h, VkCommandBuffer cmd, const CanopyFrame& frame, const Image* present, uint32_t slot) {
  if (slot >= Host::kFramesInFlight) return Status::error("demo: frame slot " + std::to_string(slot) + " out of range");
  CANOPY_TRY(beginCanopyFrame(h.canopy, frame));
  if (h.graphGeneration != canopyResourceGeneration(h.canopy)) CANOPY_TRY(buildGraph(h));
  if (h.presentTarget != rg::kInvalidResource) {
    if (!present) return Status::error("demo: no swapchain image for this frame");
    CANOPY_TRY(h.graph.bindImage(h.presentTarget, *present));
  }
  if (h.readbackId != rg::kInvalidResource) CANOPY_TRY(h.graph.bindBuffer(h.readbackId, h.readback[slot].buffer));
  h.timer[slot].reset(cmd);
  h.shadow.viewProj = toGlm(frame.camera.proj) * toGlm(frame.camera.view);
  CANOPY_TRY(h.graph.record(cmd, &h.timer[slot]));
  if (!h.shadow.on) return Status();
  // The vegetation's shadow of this frame (the ground of the next frame reads it), then its read-back.
  Host::Shadow& sh = h.shadow;
  const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
  CanopyShadowInputs in;
  in.depth = canopyImage(sh.map.image, sh.map.view,
                         VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
                             VK_IMAGE_USAGE_TRANSFER_DST_BIT,
                         VK_FORMAT_D32_SFLOAT, sampled, sampled);
  in.width = in.height = Host::Shadow::kSize;
  in.lightViewProj = toFloat4x4(sh.light);
  h.timer[slot].begin(cmd, "canopy: shadow map");
  const Status st = recordCanopyShadow(h.canopy, cmd, in);
  h.timer[slot].end(cmd);
  CANOPY_TRY(st);
  if (!sh.readback) return Status();
  CANOPY_TRY(sh.copy.bindBuffer(sh.copyTarget, sh.mapReadback[slot].buffer));
  return sh.copy.record(cmd);
}

void readShadowMap(const Host& h, uint32_t slot, std::vector<float>* depth) {
  depth->resize(size_t(Host::Shadow::kSize) * Host::Shadow::kSize);
  std::memcpy(depth->data(), h.shadow.mapReadback[slot].allocation.mapped, depth->size() * sizeof(float));
}

Status createFrameRing(Device& d, FrameRing* r) {
  VkCommandPoolCreateInfo pci{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
  pci.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
  pci.queueFamilyIndex = d.queueFamily;
  CANOPY_VK(vkCreateCommandPool(d.device, &pci, nullptr, &r->pool));
  VkCommandBufferAllocateInfo ai{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  ai.commandPool = r->pool;
  ai.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  ai.commandBufferCount = Host::kFramesInFlight;
  CANOPY_VK(vkAllocateCommandBuffers(d.device, &ai, r->cmds));
  for (uint32_t i = 0; i < Host::kFramesInFlight; ++i) {
    VkFenceCreateInfo fi{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
    VkSemaphoreCreateInfo si{VK_STRUCTURE_TYPE_SEMAPHORE_CREATE_INFO};
    CANOPY_VK(vkCreateFence(d.device, &fi, nullptr, &r->fences[i]));
    CANOPY_VK(vkCreateSemaphore(d.device, &si, nullptr, &r->acquired[i]));
  }
  return Status();
}

Status waitFrameSlot(Device& d, FrameRing& r, uint32_t slot, bool* waited) {
  if (waited) *waited = r.pending[slot];
  if (!r.pending[slot]) return Status();
  CANOPY_VK(vkWaitForFences(d.device, 1, &r.fences[slot], VK_TRUE, UINT64_MAX));
  CANOPY_VK(vkResetFences(d.device, 1, &r.fences[slot]));
  r.pending[slot] = false;
  return Status();
}

Status recordFrameSlot(Host& h, FrameRing& r, uint32_t slot, const CanopyFrame& frame, const Image* present) {
  VkCommandBuffer cmd = r.cmds[slot];
  CANOPY_VK(vkResetCommandBuffer(cmd, 0));
  VkCommandBufferBeginInfo bi{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  bi.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  CANOPY_VK(vkBeginCommandBuffer(cmd, &bi));
  const Status rs = recordHostFrame(h, cmd, frame, present, slot);
  CANOPY_VK(vkEndCommandBuffer(cmd));
  return rs;
}

void destroyFrameRing(Device& d, FrameRing& r) {
  if (!d.device) return;
  for (uint32_t i = 0; i < Host::kFramesInFlight; ++i) {
    if (r.fences[i]) vkDestroyFence(d.device, r.fences[i], nullptr);  // the caller waited for its frames
    if (r.acquired[i]) vkDestroySemaphore(d.device, r.acquired[i], nullptr);
  }
  if (r.pool) vkDestroyCommandPool(d.device, r.pool, nullptr);
  r = FrameRing{};
}

void readPixels(const Host& h, uint32_t slot, std::vector<uint8_t>* rgba) {
  rgba->resize(size_t(h.width) * h.height * 4);
  std::memcpy(rgba->data(), h.readback[slot].allocation.mapped, rgba->size());
  const bool bgra = h.presentFormat == VK_FORMAT_B8G8R8A8_UNORM || h.presentFormat == VK_FORMAT_B8G8R8A8_SRGB;
  for (size_t i = 0; i < rgba->size(); i += 4) {
    if (bgra) std::swap((*rgba)[i], (*rgba)[i + 2]);
    (*rgba)[i + 3] = 255;
  }
}

// ---- timing -------------------------------------------------------------------------------------

void TimingLog::add(const std::vector<PassTiming>& passes, double wall) {
  for (const PassTiming& p : passes) {
    if (!passMs.count(p.name)) order.push_back(p.name);
    passMs[p.name].push_back(p.milliseconds);
  }
  wallMs.push_back(wall);
}

std::string TimingLog::summary(const std::string& title) const {
  std::string s = title + "\n";
  char line[256];
  std::snprintf(line, sizeof line, "  %-40s %10s %10s\n", "pass (GPU timestamps)", "median ms", "max ms");
  s += line;
  for (const std::string& name : order) {
    const std::vector<double>& v = passMs.at(name);
    std::snprintf(line, sizeof line, "  %-40s %10.3f %10.3f\n", name.c_str(), median(v), *std::max_element(v.begin(), v.end()));
    s += line;
  }
  if (!wallMs.empty()) {
    std::snprintf(line, sizeof line, "  %-40s %10.3f %10.3f   (%.1f FPS)\n", "whole frame, wall clock (completion to completion)",
                  median(wallMs), *std::max_element(wallMs.begin(), wallMs.end()), 1000.0 / std::max(median(wallMs), 1e-6));
    s += line;
  }
  return s;
}

}  // namespace canopy::demo
