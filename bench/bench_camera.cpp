// canopy-bench camera: the moving camera (docs/design.md "Moving camera: paths and the world-lock
// measure"). For each camera path (tools/camera_paths.h) two contexts on the same scene, wind off
// so they differ only by the method: one re-slices by its policy ("auto", spread over frames with
// --budget ms, 0: at once), the other every frame (the reference). Each frame of the path is drawn
// by both and compared (tools/world_lock.h: coverage IoU, silhouette distance, colour), and each
// one's frame time is kept; the still camera of the same run is the baseline, and for each frame
// that only reprojected, a still frame at the same camera (a third context re-sliced there).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "engine/device.h"
#include "engine/transfer.h"
#include "render/canopy.h"
#include "tools/camera_paths.h"
#include "tools/scene_generator.h"
#include "tools/world_lock.h"

namespace canopy::bench {
namespace {

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(std::ceil(q * double(v.size()))) - (q > 0 ? 1 : 0))];
}

// What a frame of the policy side did (canopyStats after beginCanopyFrame): re-sliced at once, a step
// of a spread re-slice (placing, drawing or cross-fading), or neither — the layers only reprojected.
enum class FrameKind { Reprojected, Spread, Reslice };

// One context with its host targets and frame graph.
struct Side {
  Device& d;
  CanopyContext* ctx = nullptr;
  HostTargets host;
  rg::RenderGraph graph;
  uint32_t w = 0, h = 0;
  uint32_t halfResolutionLayers = 0;  // LayerSettings.halfResolutionLayers (both sides alike)
  uint32_t depthSearchSteps = CompositeParams{}.depthSearchSteps;  // CompositeParams.depthSearchSteps
  FrameKind lastKind = FrameKind::Reprojected;
  explicit Side(Device& dev, uint32_t half = 0) : d(dev), halfResolutionLayers(half) {}
  ~Side() {
    graph.release(d);
    destroyHostTargets(d, host);
    destroyCanopy(ctx);
  }
  Status init(const VegetationModel& model, uint32_t width, uint32_t height, ReslicePolicy policy, float budgetMs,
              float errorPixels = LayerSettings{}.errorThresholdPixels, float guardBand = 0.0f) {
    w = width;
    h = height;
    CanopyDesc desc;
    desc.width = w;
    desc.height = h;
    desc.guardBand = guardBand;
    CANOPY_TRY(createCanopy(d, model, desc, &ctx));
    CanopyParams p = canopyParams(ctx);
    CANOPY_TRY(parseLayerLayout("5(3-1-1)", &p.layers.layout));
    p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    p.simulation.wind.strength = 0.0f;  // both sides then differ only by the method
    p.layers.policy = policy;
    p.layers.rebuildBudgetMs = policy == ReslicePolicy::EveryFrame ? 0.0f : budgetMs;
    p.layers.errorThresholdPixels = errorPixels;
    p.layers.halfResolutionLayers = halfResolutionLayers;
    p.composite.depthSearchSteps = depthSearchSteps;
    CANOPY_TRY(setCanopyParams(ctx, p));
    CANOPY_TRY(createHostTargets(d, w, h, VK_FORMAT_R8G8B8A8_UNORM, &host));
    return buildHostGraph(d, ctx, host, true, rg::stateOf(rg::Use::ColorAttachmentReadWrite), &graph);
  }
  // One frame at `view`: its wall clock (submit to fence), and its pixels and depth coverage (1
  // where Canopy wrote the host's depth: a layer's alpha >= depthAlpha, or a trunk) when asked.
  Status frame(const LayerView& view, double* ms, std::vector<uint8_t>* pixels, std::vector<uint8_t>* covered = nullptr) {
    CanopyFrame f;
    f.camera = toCamera(view);
    f.dt = 1.0f / 30.0f;
    CANOPY_TRY(beginCanopyFrame(ctx, f));
    const CanopyStats st = canopyStats(ctx);
    lastKind = st.layersRebuilt ? FrameKind::Reslice : st.layers.spreadPhase != 0 ? FrameKind::Spread : FrameKind::Reprojected;
    const double t0 = nowMs();
    CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) { return graph.record(cmd, nullptr); }));
    *ms = nowMs() - t0;
    if (!pixels) return Status();
    pixels->resize(size_t(w) * h * 4);
    CANOPY_TRY(readbackImage(d, host.color, 0, 4, pixels->data(), rg::stateOf(rg::Use::ColorAttachmentReadWrite)));
    if (!covered) return Status();
    std::vector<float> z(size_t(w) * h);
    CANOPY_TRY(readbackImage(d, host.depth, 0, 4, z.data(), rg::stateOf(rg::Use::DepthAttachmentWrite)));
    covered->resize(z.size());
    for (size_t i = 0; i < z.size(); ++i) (*covered)[i] = z[i] < 1.0f;  // the host clears to 1
    return Status();
  }
};

// The alpha channel of a readback: with the host's clear alpha 0 it is what Canopy's premultiplied
// "over" left there, the vegetation's (and trunks') coverage. Mean alpha, and the share of pixels
// with alpha >= 1/2.
struct Coverage {
  double meanAlpha = 0, covered = 0;
};
Coverage coverageOf(const std::vector<uint8_t>& rgba) {
  Coverage c;
  const size_t n = rgba.size() / 4;
  for (size_t i = 0; i < n; ++i) {
    c.meanAlpha += rgba[4 * i + 3] / 255.0;
    c.covered += rgba[4 * i + 3] >= 128 ? 1.0 : 0.0;
  }
  c.meanAlpha /= double(std::max<size_t>(n, 1));
  c.covered /= double(std::max<size_t>(n, 1));
  return c;
}

// A spread re-slice at one camera fades the new set in (docs/design.md "Layers: spread
// re-slicing", the cross-fade): the coverage of every frame from the change until the re-slice has
// ended, against the old set's (the frame before) and the new set's (settled after). `change`
// alters the parameters: a light change keeps each leaf in its layer, a layout of the same layer
// count moves leaves between layers.
struct FadeResult {
  std::string change;
  Coverage before, after, lowest;  // lowest: the minimum over the frames of the re-slice, each figure alone
  uint32_t fadeFrames = 0, frames = 0;
  double stillMs = 0, fadeMs = 0;  // medians: the frames before the change, the fade's blend frames
};
Status measureCrossFade(Device& d, const VegetationModel& model, const CameraBenchOptions& o, const std::string& change,
                        const std::function<void(CanopyParams&)>& alter, FadeResult* out) {
  Side side(d, o.halfResolutionLayers);
  // The fade does not depend on how fast the slices before it were drawn: a large budget keeps the
  // run short at any face count.
  CANOPY_TRY(side.init(model, o.width, o.height, ReslicePolicy::OnViewChange, std::max(o.budgetMs, 100.0f), o.errorPixels, o.guardBand));
  const LayerView view = cameraPathView(CameraPath{}, model.boundsMin, model.boundsMax, float(o.width) / float(o.height), 0);
  std::vector<uint8_t> px;
  double ms = 0;
  std::vector<double> still, fade;
  for (int i = 0; i < 8; ++i) {
    CANOPY_TRY(side.frame(view, &ms, &px));
    if (i >= 2) still.push_back(ms);
  }
  *out = FadeResult{};
  out->change = change;
  out->before = coverageOf(px);
  out->lowest = out->before;
  CanopyParams p = canopyParams(side.ctx);
  alter(p);
  CANOPY_TRY(setCanopyParams(side.ctx, p));
  for (int i = 0; i < 100000; ++i) {
    CANOPY_TRY(side.frame(view, &ms, &px));
    const CanopyStats st = canopyStats(side.ctx);
    const Coverage c = coverageOf(px);
    out->lowest.meanAlpha = std::min(out->lowest.meanAlpha, c.meanAlpha);
    out->lowest.covered = std::min(out->lowest.covered, c.covered);
    out->frames++;
    if (st.layers.spreadPhase == 3) out->fadeFrames++;
    if (st.layers.spreadPhase == 3 && st.layers.crossFade > 0.0f && st.layers.crossFade < 1.0f) fade.push_back(ms);
    if (st.layers.spreadPhase == 0) break;
  }
  for (int i = 0; i < 2; ++i) CANOPY_TRY(side.frame(view, &ms, &px));
  out->after = coverageOf(px);
  out->stillMs = quantile(still, 0.5);
  out->fadeMs = quantile(fade, 0.5);
  return Status();
}

struct PathResult {
  std::string name;
  std::vector<double> autoMs, everyMs;
  std::vector<double> stillMs;        // the still camera's frames, one drawn before each of this path's
  std::vector<double> reprojectedMs;  // the policy side's frames that only reprojected (no re-slice work)
  // For each of those, a still frame at the same camera: a third context re-sliced there at once,
  // then drawn again (the camera moved the vegetation's size on screen: a dolly's frames cover up to
  // a third more pixels than the path's start).
  std::vector<double> stillHereMs;
  WorldLockError worst;          // min IoU, max of the distances and colour
  WorldLockError worstDepth;     // the same over depth coverage (alpha >= depthAlpha)
  double silhouetteMeanAvg = 0;  // the silhouette mean over the frames
  uint32_t reslices = 0;         // the auto side's re-slices along the path
};

}  // namespace

// One face count's tables: each path against the still camera, the reprojected frames, the cross-fades.
void printCameraResults(uint64_t faces, const std::vector<double>& stillMs, const std::vector<PathResult>& results,
                        const std::vector<FadeResult>& fades) {
  const double stillMed = quantile(stillMs, 0.5);
  std::printf("\n%llu faces: still camera %.2f ms (median), p95 %.2f ms\n", (unsigned long long)faces, stillMed,
              quantile(stillMs, 0.95));
  std::printf("  (IoU, sil.: covered = differs from the clear colour by > 1 level; depth IoU, sil.: covered = Canopy wrote\n"
              "   the host's depth there, alpha >= 0.5)\n");
  std::printf("  %-7s %9s %8s %7s %10s %8s %7s %9s %9s %8s %8s %8s %9s %8s\n", "path", "auto ms", "p95", "x still", "every ms",
              "p95", "x still", "re-slices", "IoU min", "sil. avg", "sil. max", "p99 max", "depth IoU", "sil. max");
  for (const PathResult& r : results) {
    const double am = quantile(r.autoMs, 0.5), em = quantile(r.everyMs, 0.5);
    std::printf("  %-7s %9.2f %8.2f %7.2f %10.2f %8.2f %7.2f %9u %9.4f %8.3f %8.3f %8.2f %9.4f %8.3f\n", r.name.c_str(), am,
                quantile(r.autoMs, 0.95), am / std::max(stillMed, 1e-9), em, quantile(r.everyMs, 0.95),
                em / std::max(stillMed, 1e-9), r.reslices, r.worst.coverageIoU, r.silhouetteMeanAvg, r.worst.silhouetteMeanPx,
                r.worst.silhouetteP99Px, r.worstDepth.coverageIoU, r.worstDepth.silhouetteMeanPx);
  }
  // The issue-56 figure: the frames that only reprojected, against the still frames drawn alternately.
  std::printf("\n  Reprojected frames (the policy side's frames with no re-slice work: not re-sliced at once, no step of a\n"
              "  spread re-slice) against the still camera's frames drawn alternately with them (the path's start\n"
              "  view), and against a still frame at the same camera (re-sliced there, then drawn again), medians:\n");
  std::printf("  %-7s %7s %12s %9s %11s %11s %9s\n", "path", "frames", "reproj. ms", "still ms", "x still", "here ms", "x here");
  for (const PathResult& r : results) {
    const double rm = quantile(r.reprojectedMs, 0.5), sm = quantile(r.stillMs, 0.5), hm = quantile(r.stillHereMs, 0.5);
    std::printf("  %-7s %7zu %12.2f %9.2f %11.2f %11.2f %9.2f\n", r.name.c_str(), r.reprojectedMs.size(), rm, sm,
                rm / std::max(sm, 1e-9), hm, rm / std::max(hm, 1e-9));
  }
  if (!fades.empty()) {
    std::printf("\n  Cross-fade at one camera (spread re-slice, %u frames of fade): coverage of each frame of the re-slice\n"
                "  against the old and the new set (mean alpha; covered = alpha >= 1/2), the lowest frame over the smaller set\n",
                LayerSettings{}.crossFadeFrames);
    std::printf("  %-30s %6s %5s %9s %9s %9s %9s %9s %9s %9s %9s %8s %8s\n", "change", "frames", "fade", "alpha old", "new",
                "lowest", "/smaller", "cov. old", "new", "lowest", "/smaller", "still ms", "fade ms");
    for (const FadeResult& f : fades) {
      const double sa = std::min(f.before.meanAlpha, f.after.meanAlpha), sc = std::min(f.before.covered, f.after.covered);
      std::printf("  %-30s %6u %5u %9.5f %9.5f %9.5f %9.4f %9.5f %9.5f %9.5f %9.4f %8.2f %8.2f\n", f.change.c_str(), f.frames,
                  f.fadeFrames, f.before.meanAlpha, f.after.meanAlpha, f.lowest.meanAlpha, f.lowest.meanAlpha / std::max(sa, 1e-12),
                  f.before.covered, f.after.covered, f.lowest.covered, f.lowest.covered / std::max(sc, 1e-12), f.stillMs, f.fadeMs);
    }
  }
}

int runCameraBench(Device& d, const CameraBenchOptions& o) {
  const uint8_t* clear = kHostClearRgba8;
  char policy[192] = "at once";
  if (o.budgetMs > 0) std::snprintf(policy, sizeof policy, "spread over frames, %.1f ms budget", double(o.budgetMs));
  std::snprintf(policy + std::strlen(policy), sizeof policy - std::strlen(policy), ", error threshold %g px, guard band %g%s",
                double(o.errorPixels), double(o.guardBand),
                o.halfResolutionLayers ? (", the far " + std::to_string(o.halfResolutionLayers) + " layers at half resolution").c_str() : "");
  std::printf("\nMoving camera at %ux%u, 5(3-1-1), generated scene '%s', wind off: each path's %d frames drawn with the\n"
              "re-slicing policy (auto: %s) and re-sliced every frame (the reference), compared frame by frame\n"
              "(coverage IoU, silhouette distance in pixels, colour difference in 8-bit levels over covered pixels);\n"
              "frame times are wall clock, submit to fence, ms.\n",
              o.width, o.height, o.scene.c_str(), o.frames, policy);
  FILE* csv = nullptr;
  if (!o.csvPath.empty()) {
    csv = std::fopen(o.csvPath.c_str(), "w");
    if (!csv) {
      std::fprintf(stderr, "canopy-bench: cannot write %s\n", o.csvPath.c_str());
      return 1;
    }
    std::fprintf(csv, "faces,path,frame,auto_ms,every_ms,reslices,iou,sil_mean_px,sil_p99_px,colour_mean,depth_iou\n");
  }
  struct CsvCloser {
    FILE* f;
    ~CsvCloser() {
      if (f) std::fclose(f);
    }
  } closer{csv};
  for (uint64_t faces : o.faces) {
    SceneDesc sd;
    sd.faces = faces;
    VegetationModel model;
    Status s = parseSceneKind(o.scene, &sd.kind);
    if (s.ok()) s = generateScene(sd, &model);
    const float aspect = float(o.width) / float(o.height);
    // The still camera: a context's frames after its first two (the first slices the layers), one
    // drawn before each frame of every path, so the still and moving frames share the machine's state.
    std::vector<double> stillMs;
    const LayerView view0 = cameraPathView(CameraPath{}, model.boundsMin, model.boundsMax, aspect, 0);
    Side still(d, o.halfResolutionLayers);
    if (s.ok()) s = still.init(model, o.width, o.height, ReslicePolicy::OnViewChange, o.budgetMs, o.errorPixels, o.guardBand);
    if (s.ok()) {
      const LayerStats st = canopyStats(still.ctx).layers;
      std::printf("%llu faces: layer images %ux%u, the output and a guard band of %u x %u px on each side\n",
                  (unsigned long long)faces, st.layerWidth, st.layerHeight, st.guardX, st.guardY);
    }
    for (int i = 0; i < 2 && s.ok(); ++i) {
      double ms = 0;
      s = still.frame(view0, &ms, nullptr);
    }
    std::vector<PathResult> results;
    for (CameraMotion m : o.paths) {
      if (!s.ok()) break;
      PathResult r;
      r.name = cameraMotionName(m);
      CameraPath path;
      path.motion = m;
      path.degreesPerFrame = o.degreesPerFrame;
      path.radiiPerFrame = o.radiiPerFrame;
      path.amplitudeDegrees = o.swingDegrees;
      // Fresh contexts per path, each settled on the path's first view (two frames: the first slices).
      Side autoSide(d, o.halfResolutionLayers), every(d, o.halfResolutionLayers), here(d, o.halfResolutionLayers);
      autoSide.depthSearchSteps = o.depthSearchSteps;
      s = autoSide.init(model, o.width, o.height, ReslicePolicy::OnViewChange, o.budgetMs, o.errorPixels, o.guardBand);
      if (s.ok()) s = every.init(model, o.width, o.height, ReslicePolicy::EveryFrame, 0.0f);
      if (s.ok()) s = here.init(model, o.width, o.height, ReslicePolicy::OnViewChange, 0.0f, o.errorPixels, o.guardBand);
      const LayerView first = cameraPathView(path, model.boundsMin, model.boundsMax, aspect, 0);
      for (int k = 0; k < 2 && s.ok(); ++k) {
        double ms = 0;
        s = autoSide.frame(first, &ms, nullptr);
        if (s.ok()) s = every.frame(first, &ms, nullptr);
      }
      const uint32_t before = s.ok() ? uint32_t(canopyStats(autoSide.ctx).layers.rebuilds) : 0;
      std::vector<uint8_t> a, b, ca, cb;
      double silSum = 0;
      uint32_t lastRebuilds = before;
      for (int i = 0; i < o.frames && s.ok(); ++i) {
        const LayerView v = cameraPathView(path, model.boundsMin, model.boundsMax, aspect, uint32_t(i));
        // The reference first, and the third context re-sliced at v; then the three timed frames back to
        // back, each after the same kinds of work: the still camera's, the policy side's, the still
        // frame at v.
        double ms0 = 0, ma = 0, mb = 0, mr = 0, mh = 0;
        s = every.frame(v, &mb, &b, &cb);
        if (s.ok()) s = requestCanopyRebuild(here.ctx, true);
        if (s.ok()) s = here.frame(v, &mr, nullptr);
        if (s.ok()) s = still.frame(view0, &ms0, nullptr);
        if (s.ok()) s = autoSide.frame(v, &ma, &a, &ca);
        if (s.ok()) s = here.frame(v, &mh, nullptr);
        if (!s.ok()) break;
        stillMs.push_back(ms0);
        r.stillMs.push_back(ms0);
        r.autoMs.push_back(ma);
        r.everyMs.push_back(mb);
        if (autoSide.lastKind == FrameKind::Reprojected) {
          r.reprojectedMs.push_back(ma);
          r.stillHereMs.push_back(mh);
        }
        if (csv) std::fprintf(csv, "%llu,still,%d,%.3f,%.3f,0,1,0,0,0,1\n", (unsigned long long)faces, int(stillMs.size()) - 1, ms0, ms0);
        const uint32_t rebuilds = uint32_t(canopyStats(autoSide.ctx).layers.rebuilds);
        const WorldLockError e = compareFrames(a, b, o.width, o.height, clear);
        if (i == 0 || e.coverageIoU < r.worst.coverageIoU) r.worst.coverageIoU = e.coverageIoU;
        r.worst.silhouetteMeanPx = std::max(r.worst.silhouetteMeanPx, e.silhouetteMeanPx);
        r.worst.silhouetteP99Px = std::max(r.worst.silhouetteP99Px, e.silhouetteP99Px);
        r.worst.centroidPx = std::max(r.worst.centroidPx, e.centroidPx);
        r.worst.colourMean = std::max(r.worst.colourMean, e.colourMean);
        silSum += e.silhouetteMeanPx;
        const WorldLockError z = compareMasks(ca, cb, a, b, o.width, o.height);
        if (i == 0 || z.coverageIoU < r.worstDepth.coverageIoU) r.worstDepth.coverageIoU = z.coverageIoU;
        r.worstDepth.silhouetteMeanPx = std::max(r.worstDepth.silhouetteMeanPx, z.silhouetteMeanPx);
        r.worstDepth.silhouetteP99Px = std::max(r.worstDepth.silhouetteP99Px, z.silhouetteP99Px);
        if (csv)
          std::fprintf(csv, "%llu,%s,%d,%.3f,%.3f,%u,%.5f,%.4f,%.4f,%.3f,%.5f\n", (unsigned long long)faces, r.name.c_str(), i, ma,
                       mb, rebuilds - lastRebuilds, e.coverageIoU, e.silhouetteMeanPx, e.silhouetteP99Px, e.colourMean,
                       z.coverageIoU);
        lastRebuilds = rebuilds;
      }
      if (s.ok()) r.reslices = uint32_t(canopyStats(autoSide.ctx).layers.rebuilds) - before;
      r.silhouetteMeanAvg = silSum / std::max(1.0, double(r.autoMs.size()));
      results.push_back(r);
    }
    std::vector<FadeResult> fades;
    if (o.crossFade && s.ok()) {
      const std::pair<std::string, std::function<void(CanopyParams&)>> changes[] = {
          {"light turned 60 deg", [](CanopyParams& p) { p.layers.lightDirection = Float3{-0.6f, 0.7f, 0.4f}; }},
          {"layout 5(3-1-1) -> 5(1-1-3)", [](CanopyParams& p) { (void)parseLayerLayout("5(1-1-3)", &p.layers.layout); }},
      };
      for (const auto& [name, alter] : changes) {
        FadeResult f;
        if (s.ok()) s = measureCrossFade(d, model, o, name, alter, &f);
        fades.push_back(f);
      }
    }
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
      return 1;
    }
    printCameraResults(faces, stillMs, results, fades);
  }
  return 0;
}

}  // namespace canopy::bench
