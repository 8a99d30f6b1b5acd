// canopy-bench impostors (issues 18, 36): what Lluch et al.'s impostors save at a re-slice and what
// they change in the far layers. Per face count, one generated scene with its box hierarchy
// (default the large vegetation field), 5(3-1-1), a low camera looking across it (a far region full
// of plants) and one far away, every frame a re-slice (ReslicePolicy::EveryFrame); per view set
// (six diagonal views, the default; twelve, before 0.7: each baked in its own context, storage per
// box printed) the variants (off, far region, by projected size; crossed or facing polygons)
// alternated round by round in the same run:
//   - re-slice wall clock (view update with the CPU placement and the cut, record, submit, fence),
//     the GPU timestamps of the foliage pass, the CPU placement, triangles and impostors drawn;
//   - the image difference against the mode without impostors: the far region's layers flattened
//     ("over", front to back), and all layers flattened: mean |RGBA difference| over covered
//     pixels, coverage agreement (IoU of alpha > 0.5);
//   - with --images DIR: the far layers of each mode, and the debug view (levels; by projected size) as PNG.
// Medians of --rebuilds re-slices per mode, after one untimed round.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "bench/bench.h"
#include "engine/device.h"
#include "engine/timing.h"
#include "render/layers.h"
#include "tools/image_io.h"
#include "tools/scene_generator.h"

namespace canopy::bench {
namespace {

double medianOf(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Layers [first, last) flattened front to back.
Status flatten(LayeredVegetation& lv, uint32_t first, uint32_t last, std::vector<glm::vec4>* out) {
  out->assign(size_t(lv.desc.width) * lv.desc.height, glm::vec4(0.0f));
  for (uint32_t l = first; l < last; ++l) {
    std::vector<glm::vec4> px;
    CANOPY_TRY(readLayerColor(lv, l, &px));
    for (size_t i = 0; i < out->size(); ++i) (*out)[i] += px[i] * (1.0f - (*out)[i].a);
  }
  return Status();
}

struct Diff {
  double meanAbs = 0, iou = 1;
};
Diff compare(const std::vector<glm::vec4>& a, const std::vector<glm::vec4>& b) {
  Diff d;
  double sum = 0;
  uint64_t covered = 0, both = 0, either = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].a <= 1.0f / 255 && b[i].a <= 1.0f / 255) continue;
    covered++;
    const glm::vec4 e = glm::abs(a[i] - b[i]);
    sum += (e.r + e.g + e.b + e.a) / 4.0;
    both += a[i].a > 0.5f && b[i].a > 0.5f;
    either += a[i].a > 0.5f || b[i].a > 0.5f;
  }
  d.meanAbs = covered ? sum / double(covered) : 0.0;
  d.iou = either ? double(both) / double(either) : 1.0;
  return d;
}

Status writeImage(const std::string& path, uint32_t w, uint32_t h, const std::vector<glm::vec4>& px) {
  std::vector<uint8_t> rgba(size_t(w) * h * 4);
  const glm::vec3 sky(0.62f, 0.75f, 0.88f);
  for (size_t i = 0; i < px.size(); ++i) {
    const glm::vec3 c = glm::vec3(px[i]) + glm::pow(sky, glm::vec3(2.2f)) * (1.0f - px[i].a);
    for (int k = 0; k < 3; ++k) rgba[4 * i + k] = uint8_t(std::clamp(std::pow(std::max(c[k], 0.0f), 1.0f / 2.2f), 0.0f, 1.0f) * 255.0f + 0.5f);
    rgba[4 * i + 3] = 255;
  }
  return writePng(path, w, h, rgba);
}

}  // namespace

namespace {

struct Variant {
  ImpostorMode mode;
  ImpostorShape shape;
  const char* name;
  const char* file;
};

// One camera of one view set: every variant re-sliced `rebuilds` times (alternated), its far and
// all layers against the six-view set's 'off' (kept in refFar/refAll), images to `imageDir`, a table row each.
Status measureCamera(Device& dev, LayeredVegetation& lv, const std::vector<Variant>& variants, const LayerView& view, int cam, bool six,
                     uint64_t faces, int rebuilds, uint32_t width, uint32_t height, const std::string& imageDir,
                     std::vector<glm::vec4> refFar[2], std::vector<glm::vec4> refAll[2]) {
  const int nv = int(variants.size());
  const char* camName = cam == 0 ? "across" : "distant";
  rg::RenderGraph g;
  GpuTimer timer;
  Status s = addLayerPasses(lv, g, nullptr);
  if (s.ok()) s = g.compile();
  if (s.ok()) s = g.realize(dev);
  if (s.ok()) s = timer.init(dev, 16);
  struct Samples {
    std::vector<double> wall, gpu, place;
    uint64_t triangles = 0;
    uint32_t impostors = 0, fading = 0;
    std::vector<glm::vec4> far, all;
  };
  std::vector<Samples> per(nv);
  auto reslice = [&](int v, bool keep, bool debug) -> Status {
    LayerSettings ls = lv.settings;
    ls.impostors.mode = variants[v].mode;
    ls.impostors.shape = variants[v].shape;
    ls.impostors.debugView = debug;
    CANOPY_TRY(setLayerSettings(lv, ls));
    const double w0 = nowMs();
    bool changed = false;
    CANOPY_TRY(updateLayerView(lv, view, &changed));
    CANOPY_TRY(submitAndWait(dev, [&](VkCommandBuffer cmd) {
      timer.reset(cmd);
      return g.record(cmd, &timer);
    }));
    const double w1 = nowMs();
    std::vector<PassTiming> t;
    CANOPY_TRY(timer.read(dev, &t));
    if (!keep) return Status();
    Samples& p = per[v];
    const bool off = variants[v].mode == ImpostorMode::Off;
    p.wall.push_back(w1 - w0);
    p.place.push_back(lv.stats.lastPlacementMs);
    for (const PassTiming& x : t)
      if (x.name == "layers: foliage") p.gpu.push_back(x.milliseconds);
    p.triangles = off ? lv.stats.foliageTriangles : lv.stats.lastDrawnTriangles;
    p.impostors = off ? 0 : lv.stats.lastImpostors;
    p.fading = off ? 0 : lv.stats.lastFadingBoxes;
    return Status();
  };
  for (int r = 0; r <= rebuilds && s.ok(); ++r)
    for (int v = 0; v < nv && s.ok(); ++v) s = reslice(v, r > 0, false);
  // The images of each variant (one more re-slice each), and the debug view.
  const LayerLayout& l = lv.settings.layout;
  const uint32_t farFirst = l.region[0] + l.region[1], n = l.count();
  for (int v = 0; v < nv && s.ok(); ++v) {
    s = reslice(v, false, false);
    if (s.ok()) s = flatten(lv, farFirst, n, &per[v].far);
    if (s.ok()) s = flatten(lv, 0, n, &per[v].all);
    if (s.ok() && !imageDir.empty() && (six || v > 0)) {
      const std::string name = imageDir + "/impostors_" + camName + "_" + std::to_string(faces) + "_" + variants[v].file + ".png";
      s = writeImage(name, width, height, per[v].far);
    }
  }
  if (s.ok() && six) {
    refFar[cam] = per[0].far;
    refAll[cam] = per[0].all;
  }
  if (s.ok() && six && !imageDir.empty()) {
    std::vector<glm::vec4> dbg;
    s = reslice(2, false, true);  // by projected size: the most impostors
    if (s.ok()) s = flatten(lv, 0, n, &dbg);
    if (s.ok())
      s = writeImage(imageDir + "/impostors_debug_" + camName + "_" + std::to_string(faces) + ".png", width, height, dbg);
  }
  timer.destroy(dev);
  g.release(dev);
  if (!s.ok()) return s;
  std::printf("  camera %s:\n", camName);
  std::printf("  %-15s %10s %9s %9s %11s %10s %9s | %-16s | %-16s\n", "mode", "wall ms", "GPU ms", "place ms",
              "tris drawn", "impostors", "x wall", "far |d|  IoU", "all |d|  IoU");
  const double base = medianOf(per[0].wall);
  for (int v = 0; v < nv; ++v) {
    const Samples& p = per[v];
    const Diff far = compare(p.far, refFar[cam]), all = compare(p.all, refAll[cam]);
    char imp[32];
    std::snprintf(imp, sizeof imp, "%u (%u)", p.impostors, p.fading);
    std::printf("  %-15s %10.2f %9.2f %9.2f %11llu %10s %9.2f | %7.4f %7.3f  | %7.4f %7.3f\n", variants[v].name,
                medianOf(p.wall), medianOf(p.gpu), medianOf(p.place), (unsigned long long)p.triangles, imp,
                base / std::max(medianOf(p.wall), 1e-9), far.meanAbs, far.iou, all.meanAbs, all.iou);
  }
  return Status();
}

}  // namespace

int runImpostorBench(Device& dev, const std::vector<uint64_t>& faceCounts, const std::string& sceneName, int rebuilds,
                     uint32_t width, uint32_t height, const std::string& imageDir) {
  SceneKind kind;
  Status s = parseSceneKind(sceneName.empty() ? "field" : sceneName, &kind);
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
    return 2;
  }
  const ImpostorSettings defaults;
  std::printf("\nImpostors (Lluch et al.): %s scene with its box hierarchy, 5(3-1-1) at %ux%u, a low camera across it,\n"
              "a re-slice every frame; switch at %g px, band %g; medians of %d re-slices per mode, modes alternated.\n"
              "wall = view update (CPU placement + cut) + record + submit-to-fence; GPU = timestamps of the foliage pass;\n"
              "far layers / all layers: mean |RGBA difference| over covered pixels and coverage IoU against 'off'.\n",
              sceneName.empty() ? "field" : sceneName.c_str(), width, height, defaults.switchPixels, defaults.band, rebuilds);
  for (uint64_t faces : faceCounts) {
    const double g0 = nowMs();
    SceneDesc sd;
    sd.kind = kind;
    sd.faces = faces;
    sd.boxes = true;
    VegetationModel m;
    SceneStats st;
    s = generateScene(sd, &m, &st);
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
      return 1;
    }
    const double genMs = nowMs() - g0;
    std::printf("\n%llu faces (%llu leaf faces), generated in %.0f ms\n", (unsigned long long)st.faces,
                (unsigned long long)st.leafFaces, genMs);
    const glm::vec3 lo = m.boundsMin, hi = m.boundsMax, c = 0.5f * (lo + hi);
    // Two cameras: across the scene from its near edge, low (a far region behind a near one), and
    // the whole scene in the distance (five times its depth away, 30-degree field of view).
    LayerView views[2];
    views[0].view = glm::lookAt(glm::vec3(c.x, lo.y + 0.15f * (hi.y - lo.y) + 1.0f, hi.z + 0.05f * (hi.z - lo.z)),
                                glm::vec3(c.x, lo.y, lo.z), glm::vec3(0, 1, 0));
    views[0].proj = perspectiveVulkan(glm::radians(60.0f), float(width) / float(height), 0.1f, 10000.0f);
    const float depth = hi.z - lo.z;
    views[1].view = glm::lookAt(glm::vec3(c.x, lo.y + 0.6f * (hi.y - lo.y), hi.z + 5.0f * depth), c, glm::vec3(0, 1, 0));
    views[1].proj = perspectiveVulkan(glm::radians(30.0f), float(width) / float(height), 0.1f, 10000.0f);
    // The 'off' images of the first view set are every later row's reference (the leaves do not
    // depend on the views baked).
    std::vector<glm::vec4> refFar[2], refAll[2];
    // The view sets, each baked in its own context: Lluch et al.'s six diagonal views (the default),
    // then the twelve of before 0.7. Per set the variants alternated round by round.
    for (ImpostorViews set : {ImpostorViews::Diagonal6, ImpostorViews::FacesAndDiagonals12}) {
    const bool six = set == ImpostorViews::Diagonal6;
    LayeredVegetationDesc d;
    d.width = width;
    d.height = height;
    d.impostors.enable = true;
    d.impostors.views = set;
    d.settings.policy = ReslicePolicy::EveryFrame;
    LayeredVegetation lv;
    const double c0 = nowMs();
    s = createLayeredVegetation(dev, m, d, &lv);
    const double createMs = nowMs() - c0;
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench: %llu faces: %s\n", (unsigned long long)faces, s.message().c_str());
      return 1;
    }
    std::printf("\n%s: created in %.0f ms: %llu foliage triangles, %u leaves, %u boxes, %u with %u views of %u px "
                "(%.0f KiB a box, colour and depth; atlas %.1f MiB), bake %.0f ms\n",
                six ? "six diagonal views (default)" : "twelve views (before 0.7)", createMs,
                (unsigned long long)lv.stats.foliageTriangles, lv.stats.leafCount, lv.stats.impostorBoxes,
                lv.stats.impostorBakedBoxes, lv.stats.impostorViewsPerBox, lv.stats.impostorTilePixels,
                double(lv.stats.impostorBytesPerBox) / 1024.0, double(lv.stats.impostorBytes) / double(1 << 20),
                lv.stats.impostorBakeMs);
    std::vector<Variant> variants = {{ImpostorMode::Off, ImpostorShape::CrossedPolygons, "off", "off"}};
    if (six) {
      variants.push_back({ImpostorMode::FarRegion, ImpostorShape::CrossedPolygons, "far, crossed", "far"});
      variants.push_back({ImpostorMode::ByProjectedSize, ImpostorShape::CrossedPolygons, "size, crossed", "size"});
      variants.push_back({ImpostorMode::ByProjectedSize, ImpostorShape::FacingPolygon, "size, facing", "size_facing6"});
    } else {
      variants.push_back({ImpostorMode::ByProjectedSize, ImpostorShape::FacingPolygon, "size, facing", "size_facing12"});
      variants.push_back({ImpostorMode::ByProjectedSize, ImpostorShape::CrossedPolygons, "size, crossed", "size_crossed12"});
    }
    for (int cam = 0; cam < 2 && s.ok(); ++cam)
      s = measureCamera(dev, lv, variants, views[cam], cam, six, faces, rebuilds, width, height, imageDir, refFar, refAll);
    destroyLayeredVegetation(lv);
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
      return 1;
    }
    }
    std::printf("  (impostors: boxes drawn as impostors, in parentheses those inside the transition band; x wall: "
                "speed-up of the re-slice against 'off' of the same set; far |d|: the far region's layers, all |d|: every\n"
                "  layer, against 'off' of the six-view set; crossed: Lluch et al.'s crossed polygons, facing: one polygon\n"
                "  facing the viewer, two views blended)\n");
  }
  return 0;
}

}  // namespace canopy::bench
