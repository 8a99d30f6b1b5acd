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
      "  --paper-roots       each leaf rooted at its smallest (u, v), as the paper (default: where it meets a\n"
      "                      branch, LeafRootOptions.attachRoots)\n"
      "Method:\n"
      "  --rigid-motion M    follow (trunks and branches drawn every frame, moving with the leaves they carry)\n"
      "                      or still (a background drawn per re-slice, before 0.8) (default follow)\n"
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
    {"--paper-roots", &Options::attachRoots, false},
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
      {"--rigid-motion", "follow or still",
       {{"follow", [](Options& o) { o.rigidMotion = RigidMotion::FollowFoliage; }},
        {"still", [](Options& o) { o.rigidMotion = RigidMotion::Still; }}}},
      {"--vsync", "on or off",
       {{"on", [](Options& o) { o.vsync = true; }}, {"off", [](Options& o) { o.vsync = false; }}}},
  };
  return options;
}

namespace {

// --wind's sides: left,right,top,bottom (any of them) or none.
bool parseWindSides(const char* v, uint32_t* out, std::string* why) {
  uint32_t sides = 0;
  if (std::string(v) != "none")
    for (const std::string& side : cli::splitList(v)) {
      if (side == "left") sides |= kWindFromLeft;
      else if (side == "right") sides |= kWindFromRight;
      else if (side == "top") sides |= kWindFromTop;
      else if (side == "bottom") sides |= kWindFromBottom;
      else return *why = "side '" + side + "' is not left, right, top or bottom", false;
    }
  *out = sides;
  return true;
}

// "X,Y,Z": three numbers, each in [lo, hi].
bool parseTriple(const char* v, float lo, float hi, Float3* out) {
  const std::vector<std::string> parts = cli::splitList(v);
  float x[3] = {0, 0, 0};
  bool good = parts.size() == 3;
  for (size_t k = 0; good && k < 3; ++k) good = cli::parseFloat(parts[k].c_str(), &x[k]) && x[k] >= lo && x[k] <= hi;
  if (good) *out = Float3{x[0], x[1], x[2]};
  return good;
}

}  // namespace

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
      // Given, the roughness overrides every material's own (LayerSettings.overrideLeafRoughness).
      if (num->field == &Options::leafRoughness) o->overrideLeafRoughness = true;
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
      std::string why;
      if (!parseWindSides(v, &o->windSides, &why)) return bad(why);
      o->planeSides = true;
    } else if (a == "--wind-dir") {
      Float3 x;
      if (!(takes() && parseTriple(v, -1e6f, 1e6f, &x)) || x.x * x.x + x.y * x.y + x.z * x.z <= 0.0f)
        return bad("needs X,Y,Z, three finite numbers, not all 0");
      o->windDirection = x;
    } else if (a == "--light" || a == "--light-color") {
      const bool colour = a == "--light-color";
      if (!(takes() && parseTriple(v, colour ? 0.0f : -1e6f, colour ? 1000.0f : 1e6f, colour ? &o->lightColor : &o->light)))
        return bad(colour ? "needs R,G,B, each in [0, 1000]" : "needs X,Y,Z, three finite numbers");
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

}  // namespace canopy::demo
