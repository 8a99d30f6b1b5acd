// canopy-bench rebuild (issue 16): what a re-slice costs and whether spreading it over frames keeps
// the frame rate. Per face count, one generated scene, 5(3-1-1), still camera:
//   - a re-slice at once (requestCanopyRebuild(immediate)): that frame's wall clock minus the
//     still frame's, median of --rebuilds (a mesh streamed through the staging ring, over
//     --device-budget: the sum over the frames it takes);
//   - up to --spread-max-faces, a spread re-slice after a 2-degree camera turn with LayerSettings.rebuildBudgetMs = --budget
//     (after an untimed one: first-use shader compilation on CPU drivers): every frame from the
//     turn to the end of the cross-fade and the one after it (occupancy recomputed) timed, against the still frame and the
//     bound "2 x still + budget" (issue 16's must), with the largest slice and the frame count.
// Frames are timed from beginCanopyFrame (the CPU placement runs there) to the fence, one at a
// time, without timestamp queries; the host's clear is part of both the still and the timed frames.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "demo/cli.h"
#include "engine/device.h"
#include "engine/timing.h"
#include "render/canopy.h"
#include "render/layer_layout.h"
#include "tools/scene_generator.h"

namespace canopy::bench {
namespace {

struct Run {
  Device& d;
  VegetationModel model;
  CanopyContext* ctx = nullptr;
  HostTargets host;
  rg::RenderGraph graph;
  uint32_t w, h;
  float yaw = 20.0f;
  explicit Run(Device& dev, uint32_t width, uint32_t height) : d(dev), w(width), h(height) {}
  ~Run() {
    graph.release(d);
    destroyHostTargets(d, host);
    destroyCanopy(ctx);
  }
  Status rebuildGraph() {
    graph.release(d);
    graph = rg::RenderGraph();
    return buildHostGraph(d, ctx, host, true, rg::stateOf(rg::Use::ColorAttachmentReadWrite), &graph);
  }
  Status setBudget(float ms) {
    CanopyParams p = canopyParams(ctx);
    p.layers.rebuildBudgetMs = ms;
    CANOPY_TRY(setCanopyParams(ctx, p));
    return rebuildGraph();  // the second layer set comes and goes with the budget
  }
  // One frame, timed from beginCanopyFrame to the fence.
  Status frame(double* ms) {
    CanopyFrame f;
    f.camera = toCamera(orbitView(model.boundsMin, model.boundsMax, yaw, 10.0f, 40.0f, float(w) / float(h), 0.8f));
    f.dt = 1.0f / 30.0f;
    const double t0 = nowMs();
    CANOPY_TRY(beginCanopyFrame(ctx, f));
    CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) { return graph.record(cmd, nullptr); }));
    *ms = nowMs() - t0;
    return Status();
  }
  Status still(int frames, double* medianMs) {
    std::vector<double> v;
    for (int i = 0; i < frames; ++i) {
      double ms = 0;
      CANOPY_TRY(frame(&ms));
      v.push_back(ms);
    }
    *medianMs = median(v);
    return Status();
  }
};

}  // namespace

int runRebuildBench(Device& d, const std::vector<uint64_t>& faceCounts, const std::string& scene, float budgetMs,
                    int rebuilds, uint32_t w, uint32_t h, uint64_t spreadMaxFaces, uint64_t deviceMemoryBudget) {
  std::printf("\nRe-slicing (issue 16): generated scene '%s', %ux%u, 5(3-1-1), still camera; frames timed one at a time\n"
              "from beginCanopyFrame (CPU placement) to the fence, no timestamp queries. At once: a requested re-slice's\n"
              "frame minus the still frame (median of %d). Spread: a 2-degree turn re-sliced with a %.1f ms budget, every\n"
              "frame to the end of the cross-fade and the one after timed; the bound is 2 x still + budget.\n\n",
              scene.c_str(), w, h, rebuilds, budgetMs);
  std::printf("  %-10s %8s %9s %7s %8s %9s %9s %9s %6s %10s %9s %9s\n", "faces", "still ms", "at once", "frames",
              "spread", "median ms", "max ms", "bound ms", "within", "max slice", "host GiB", "dev MiB");
  for (uint64_t faces : faceCounts) {
    Run r(d, w, h);
    Status s = [&]() -> Status {
      SceneDesc sd;
      sd.faces = faces;
      CANOPY_TRY(parseSceneKind(scene, &sd.kind));
      CANOPY_TRY(generateScene(sd, &r.model));
      CanopyDesc desc;
      desc.width = w;
      desc.height = h;
      desc.deviceMemoryBudget = deviceMemoryBudget;
      CANOPY_TRY(createCanopy(d, r.model, desc, &r.ctx));
      const bool streamed = !canopyStats(r.ctx).layers.meshResident;
      CANOPY_TRY(createHostTargets(d, w, h, VK_FORMAT_R8G8B8A8_UNORM, &r.host));
      CANOPY_TRY(r.rebuildGraph());
      double stillMs = 0, ms = 0;
      CANOPY_TRY(r.still(5, &stillMs));
      // At once.
      // A streamed mesh's re-slice at once takes a slice a frame (as large as the ring segment):
      // its cost is the sum over those frames of each frame minus the still frame.
      std::vector<double> atOnce;
      uint32_t atOnceFrames = 0;
      double atOnceWorst = 0;
      for (int i = 0; i < rebuilds; ++i) {
        CANOPY_TRY(r.still(10, &stillMs));
        CANOPY_TRY(requestCanopyRebuild(r.ctx, true));
        const uint64_t done = canopyStats(r.ctx).layers.spreadRebuilds;
        double total = 0;
        atOnceFrames = 0;
        do {
          CANOPY_TRY(r.frame(&ms));
          total += ms - stillMs;
          atOnceWorst = std::max(atOnceWorst, ms);
          ++atOnceFrames;
          if (atOnceFrames > 100000) return Status::error("the streamed re-slice did not end");
        } while (streamed && canopyStats(r.ctx).layers.spreadRebuilds == done);
        atOnce.push_back(total);
      }
      if (streamed)
        std::printf("  %-10llu mesh %.1f MiB streamed through a %.1f MiB ring (device budget %.0f MiB): a re-slice at once took %u "
                    "frames, the longest %.1f ms\n",
                    (unsigned long long)faces, double(canopyStats(r.ctx).layers.meshBytes) / double(1 << 20),
                    double(canopyStats(r.ctx).layers.meshRingBytes) / double(1 << 20), double(deviceMemoryBudget) / double(1 << 20),
                    atOnceFrames, atOnceWorst);
      if (faces > spreadMaxFaces) {
        std::printf("  %-10llu %8.2f %9.1f %7s %8s %9s %9s %9s %6s %10s %9.2f %9.1f\n", (unsigned long long)faces, stillMs,
                    median(atOnce), "-", "", "-", "-", "-", "-", "-", double(cli::peakResidentBytes()) / double(1ull << 30),
                    double(canopyStats(r.ctx).peakDeviceBytes) / double(1 << 20));
        std::fflush(stdout);
        return Status();
      }
      // Spread: one untimed first with a large budget (a CPU driver compiles the slice and
      // cross-fade draws' shader variants at their first use; big slices measure the drawing rate
      // quickly), then the timed one with the budget asked for.
      CANOPY_TRY(r.setBudget(100.0f));
      CANOPY_TRY(r.still(10, &stillMs));
      r.yaw -= 2.0f;
      for (uint64_t n = canopyStats(r.ctx).layers.spreadRebuilds; canopyStats(r.ctx).layers.spreadRebuilds == n;)
        CANOPY_TRY(r.frame(&ms));
      CANOPY_TRY(r.setBudget(budgetMs));
      CANOPY_TRY(r.still(40, &stillMs));
      const uint64_t before = canopyStats(r.ctx).layers.spreadRebuilds;
      r.yaw += 2.0f;
      std::vector<double> spread;
      // To the end of the cross-fade, and the frame after it (which recomputes the occupancy).
      for (int after = -1; after < 1;) {
        CANOPY_TRY(r.frame(&ms));
        spread.push_back(ms);
        if (std::getenv("CANOPY_BENCH_TRACE"))
          std::printf("    frame %zu: %.2f ms, phase %u, slice %llu, fade %.3f\n", spread.size(), ms,
                      canopyStats(r.ctx).layers.spreadPhase, (unsigned long long)canopyStats(r.ctx).layers.lastSliceTriangles,
                      canopyStats(r.ctx).layers.crossFade);
        if (after >= 0 || canopyStats(r.ctx).layers.spreadRebuilds != before) ++after;
        if (spread.size() > 200000) return Status::error("the spread re-slice did not end");
      }
      const CanopyStats st = canopyStats(r.ctx);
      const double maxMs = *std::max_element(spread.begin(), spread.end());
      const double bound = 2.0 * stillMs + budgetMs;
      // Control: as many still frames right after, with the same bound (this machine's own spikes).
      std::vector<double> control;
      for (size_t i = 0; i < spread.size(); ++i) {
        CANOPY_TRY(r.frame(&ms));
        control.push_back(ms);
      }
      const double controlMax = *std::max_element(control.begin(), control.end());
      const size_t over = size_t(std::count_if(spread.begin(), spread.end(), [&](double v) { return v > bound; }));
      const size_t controlOver = size_t(std::count_if(control.begin(), control.end(), [&](double v) { return v > bound; }));
      std::printf("  %-10llu %8.2f %9.1f %7zu %8s %9.2f %9.2f %9.2f %6s %10llu %9.2f %9.1f\n", (unsigned long long)faces,
                  stillMs, median(atOnce), spread.size(), "", median(spread), maxMs, bound, maxMs <= bound ? "yes" : "NO",
                  (unsigned long long)st.layers.maxSliceTriangles, double(cli::peakResidentBytes()) / double(1ull << 30),
                  double(st.peakDeviceBytes) / double(1 << 20));
      std::printf("             (placement %.1f ms CPU in total; %u frames placing+drawing+fading; drawing rate estimate %.0f "
                  "triangles/ms; re-slice reason: %s)\n"
                  "             frames over the bound: %zu of %zu while spreading; control, as many still frames after it: "
                  "max %.2f ms, %zu over the bound\n",
                  st.layers.lastPlacementMs, st.layers.lastSpreadFrames, st.layers.trianglesPerMs,
                  st.layers.lastRebuildReason.c_str(), over, spread.size(), controlMax, controlOver);
      std::fflush(stdout);
      return Status();
    }();
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench rebuild: %llu faces: %s\n", (unsigned long long)faces, s.message().c_str());
      return 1;
    }
  }
  return 0;
}

}  // namespace canopy::bench
