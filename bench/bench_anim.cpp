// Animation benchmark (issue 5): per-frame cost of delay + warp + composite, and of the whole
// still-camera frame (simulation + delay + warp + composite), at a fixed resolution for leaf
// clouds of different face counts and for different layer counts, through Canopy's public API
// embedded in a host graph (path 1). Then the compositing levers side by side in the same run.
//
// Wall = submit-to-fence of one frame alone (median); GPU = timestamps around each pass (median).
// On lavapipe timestamps around compute work read near zero once anything was drawn (docs/design.md),
// so the compute passes' timestamps are printed for reference only and wall clock is the figure.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <map>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "engine/device.h"
#include "engine/timing.h"
#include "render/canopy.h"
#include "tools/leaf_cloud.h"
#include "tools/scene_generator.h"

namespace canopy::bench {
namespace {

struct FrameStats {
  double wallMs = 0;
  std::map<std::string, double> passMs;  // medians
};

// `frames` frames after one warm-up; dt = 0 holds the simulation (animation only).
Status measure(Device& d, CanopyContext* ctx, rg::RenderGraph& g, GpuTimer& timer, const LayerView& view, float dt,
               int frames, bool canopy, FrameStats* out) {
  FrameSamples s;
  CANOPY_TRY(sampleFrames(d, canopy ? ctx : nullptr, g, timer, [&](int) { return view; }, dt, frames, &s));
  out->wallMs = median(s.wallMs);
  for (auto& [name, v] : s.passMs) out->passMs[name] = median(v);
  return Status();
}

// Every "composite: ..." pass (occupancy, classification, tile kernel, resolve, or the fragment pass).
double compositeMs(const FrameStats& s) {
  double sum = 0;
  for (const auto& [name, ms] : s.passMs)
    if (name.rfind("composite:", 0) == 0) sum += ms;
  return sum;
}

}  // namespace

int runAnimBench(Device& dev, const std::vector<uint64_t>& faceCounts, const std::vector<std::string>& layouts,
                 int frames, uint32_t width, uint32_t height, const std::string& scene) {
  std::printf("\nAnimation at %ux%u, still camera (layers sliced once, not per frame); medians of %d frames; %s.\n", width,
              height, frames, scene.empty() ? "leaf clouds with a trunk" : ("generated scene '" + scene + "'").c_str());
  std::printf("anim = delay + warp + composite (simulation held, dt = 0); frame = simulation step (N = 64, dt = 1/30 s)\n"
              "+ delay + warp + composite. Wall = submit-to-fence of one frame, minus the host's own clear.\n\n");
  std::printf("  %-10s %-9s %10s %8s %10s %8s %13s %13s\n", "faces", "layers", "anim ms", "FPS", "frame ms", "FPS",
              "composite ts", "dynamics ts");
  struct LeverRow {
    std::string label;
    std::vector<double> ms;
  };
  std::vector<std::string> leverHeads;
  std::vector<LeverRow> leverRows;
  for (uint64_t faces : faceCounts) {
    const double g0 = nowMs();
    VegetationModel model;
    if (scene.empty()) {
      model = makeLeafCloud(faces, 7, true);
    } else {
      SceneDesc sd;
      sd.faces = faces;
      Status gs = parseSceneKind(scene, &sd.kind);
      if (gs.ok()) gs = generateScene(sd, &model);
      if (!gs.ok()) {
        std::fprintf(stderr, "canopy-bench: %s\n", gs.message().c_str());
        return 2;
      }
    }
    const double genMs = nowMs() - g0;
    CanopyDesc desc;
    desc.width = width;
    desc.height = height;
    CanopyContext* ctx = nullptr;
    Status s = createCanopy(dev, model, desc, &ctx);
    HostTargets host;
    if (s.ok()) s = createHostTargets(dev, width, height, VK_FORMAT_R8G8B8A8_UNORM, &host);
    const LayerView view = orbitView(model.boundsMin, model.boundsMax, 20, 10, 40, float(width) / float(height), 0.8f);
    GpuTimer timer;
    if (s.ok()) s = timer.init(dev, 64);
    // The host's clear alone, subtracted from every wall figure.
    FrameStats clearOnly;
    rg::RenderGraph clearGraph;
    if (s.ok()) s = buildHostGraph(dev, ctx, host, false, rg::stateOf(rg::Use::ColorAttachmentReadWrite), &clearGraph);
    if (s.ok()) s = measure(dev, ctx, clearGraph, timer, view, 0.0f, frames, false, &clearOnly);
    clearGraph.release(dev);
    for (const std::string& text : layouts) {
      if (!s.ok()) break;
      CanopyParams p = canopyParams(ctx);
      s = parseLayerLayout(text, &p.layers.layout);
      if (s.ok()) s = setCanopyParams(ctx, p);
      rg::RenderGraph g;
      if (s.ok()) s = buildHostGraph(dev, ctx, host, true, rg::stateOf(rg::Use::ColorAttachmentReadWrite), &g);
      // The first frame slices the layers (not measured: a still camera never re-slices).
      FrameStats warm, anim, whole;
      if (s.ok()) s = measure(dev, ctx, g, timer, view, 0.0f, 1, true, &warm);
      if (s.ok()) s = measure(dev, ctx, g, timer, view, 0.0f, frames, true, &anim);
      if (s.ok()) s = measure(dev, ctx, g, timer, view, 1.0f / 30.0f, frames, true, &whole);
      if (s.ok()) {
        const double a = anim.wallMs - clearOnly.wallMs, f = whole.wallMs - clearOnly.wallMs;
        std::printf("  %-10llu %-9s %10.2f %8.1f %10.2f %8.1f %13.2f %13.2f\n", (unsigned long long)faces,
                    toString(p.layers.layout).c_str(), a, 1000.0 / a, f, 1000.0 / f,
                    compositeMs(anim), anim.passMs["dynamics: displacement"]);
      }
      // The levers, side by side (animation only).
      struct Lever {
        const char* name;
        bool early, skip, bilinear;
        CompositePath path = CompositePath::Compute;
      };
      const Lever levers[] = {{"none", false, false, true},
                              {"early exit", true, false, true},
                              {"skip empty", false, true, true},
                              {"both", true, true, true},
                              {"both+nearest", true, true, false},
                              {"fragment none", false, false, true, CompositePath::Fragment},
                              {"fragment both", true, true, true, CompositePath::Fragment}};
      LeverRow row{std::to_string(faces) + " " + toString(p.layers.layout), {}};
      for (const Lever& l : levers) {
        if (!s.ok()) break;
        if (leverHeads.size() < std::size(levers)) leverHeads.push_back(l.name);
        CanopyParams q = p;
        q.composite.earlyExit = l.early;
        q.composite.skipEmptyTiles = l.skip;
        q.composite.bilinear = l.bilinear;
        q.composite.path = l.path;
        s = setCanopyParams(ctx, q);
        FrameStats st;
        if (s.ok()) s = measure(dev, ctx, g, timer, view, 0.0f, frames, true, &st);
        row.ms.push_back(st.wallMs - clearOnly.wallMs);
      }
      if (s.ok()) s = setCanopyParams(ctx, p);
      leverRows.push_back(row);
      g.release(dev);
    }
    timer.destroy(dev);
    destroyHostTargets(dev, host);
    destroyCanopy(ctx);
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
      return 1;
    }
    std::printf("  (%llu faces generated in %.0f ms; host clear %.2f ms wall, subtracted)\n", (unsigned long long)faces,
                genMs, clearOnly.wallMs);
  }
  std::printf("\nCompositing levers, anim ms (wall, minus the clear): early exit = front to back, stop when opaque;\n"
              "skip empty = tile classification (compute: a layer is visited on an 8x8 tile only when its occupancy\n"
              "meets the tile moved by the displacement's range); nearest = no bilinear. The first five run the\n"
              "compute path (tile kernel + resolve draw), the last two the fused full-screen fragment pass.\n\n");
  std::printf("  %-20s", "faces layers");
  for (const std::string& h : leverHeads) std::printf(" %13s", h.c_str());
  std::printf("\n");
  for (const LeverRow& r : leverRows) {
    std::printf("  %-20s", r.label.c_str());
    for (double v : r.ms) std::printf(" %13.2f", v);
    std::printf("\n");
  }
  return 0;
}

}  // namespace canopy::bench
