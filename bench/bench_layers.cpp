// Layer benchmark (issue 4): leaf-root preprocessing throughput and layered rasterization time
// for synthetic leaf clouds, one gl_Layer draw against one draw per layer, side by side.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "bench/bench.h"
#include "engine/device.h"
#include "engine/timing.h"
#include "render/layers.h"
#include "tools/leaf_cloud.h"

namespace canopy::bench {
int runLayersBench(Device& dev, const std::vector<uint64_t>& faceCounts, int rebuilds, const std::string& layoutText,
                   uint32_t width, uint32_t height) {
  LayerLayout layout;
  Status s = parseLayerLayout(layoutText, &layout);
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
    return 2;
  }
  std::printf("\nLayers %s at %ux%u: preprocessing (leaf roots, CPU, one core) and layer rebuilds\n",
              toString(layout).c_str(), width, height);
  std::printf("Rebuild: GPU = timestamps around the foliage pass; wall = submit-to-fence of the rebuild alone;\n"
              "placement = CPU depth range + per-layer bounds; medians of %d rebuilds. Draws: one with gl_Layer or\n"
              "one per layer (clip distances), each shaded once (LayerSettings.shadeOnce: a depth pre-pass first),\n"
              "on every fragment, and on every fragment with the middle and far regions' layers at half resolution\n"
              "(LayerSettings.halfResolutionLayers).\n\n", rebuilds);
  std::printf("  %-11s %11s %9s %12s | %-26s %10s %10s %12s %10s\n", "faces", "roots ms", "M tris/s", "cache read ms",
              "draw", "GPU ms", "wall ms", "M tris/s", "place ms");
  for (uint64_t faces : faceCounts) {
    double t0 = nowMs();
    VegetationModel m = makeLeafCloud(faces, 7);
    const double genMs = nowMs() - t0;
    // Preprocessing alone (the figure the issue asks for), then through the cache.
    std::vector<uint8_t> foliage(m.triangleCount(), 1);
    LeafRoots roots;
    t0 = nowMs();
    s = computeLeafRoots(m, foliage, {}, &roots);
    const double rootsMs = nowMs() - t0;
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
      return 1;
    }
    const std::string cache = "/tmp/canopy_bench.leafroots";
    const uint64_t key = leafRootKey(m, foliage, {});
    (void)writeLeafRootCache(cache, key, roots);
    t0 = nowMs();
    LeafRoots back;
    std::string why;
    const bool hit = readLeafRootCache(cache, key, m.positions.size(), &back, &why);
    const double cacheMs = nowMs() - t0;
    std::remove(cache.c_str());
    const double mtris = double(m.triangleCount()) / rootsMs / 1e3;
    bool first = true;
    // Each draw path shaded once (a depth pre-pass first) and on every fragment, side by side; then
    // each on every fragment with the middle and far regions' layers at half resolution
    // (LayerSettings.halfResolutionLayers).
    const uint32_t halfN = layout.region[1] + layout.region[2];
    for (int run = 0; run < 6; ++run) {
      const LayerDrawMode mode = (run < 4 ? run < 2 : run == 4) ? LayerDrawMode::SinglePass : LayerDrawMode::PerLayer;
      const bool once = run < 4 && run % 2 == 0;
      const uint32_t half = run >= 4 ? halfN : 0;
      if (mode == LayerDrawMode::SinglePass && !dev.shaderOutputLayer) continue;
      if (half && (!halfN || !dev.shaderClipDistance)) continue;
      LayeredVegetationDesc d;
      d.width = width;
      d.height = height;
      d.settings.layout = layout;
      d.settings.draw = mode;
      d.settings.policy = ReslicePolicy::EveryFrame;
      d.settings.shadeOnce = once;
      d.settings.halfResolutionLayers = half;
      LayeredVegetation lv;
      s = createLayeredVegetation(dev, m, d, &lv);
      if (!s.ok()) {
        std::fprintf(stderr, "canopy-bench: %llu faces: %s\n", (unsigned long long)faces, s.message().c_str());
        return 1;
      }
      rg::RenderGraph g;
      GpuTimer timer;
      s = addLayerPasses(lv, g, nullptr);
      if (s.ok()) s = g.compile();
      if (s.ok()) s = g.realize(dev);
      if (s.ok()) s = timer.init(dev, 8);
      std::vector<double> gpu, wall, place;
      const LayerView view = orbitView(m.boundsMin, m.boundsMax, 20, 10, 40, float(width) / float(height), 0.8f);
      for (int i = 0; i < rebuilds + 1 && s.ok(); ++i) {
        bool rebuild = false;
        s = updateLayerView(lv, view, &rebuild);
        place.push_back(lv.stats.lastPlacementMs);
        const double w0 = nowMs();
        if (s.ok()) s = submitAndWait(dev, [&](VkCommandBuffer cmd) {
                   timer.reset(cmd);
                   return g.record(cmd, &timer);
                 });
        const double w1 = nowMs();
        std::vector<PassTiming> t;
        if (s.ok()) s = timer.read(dev, &t);
        if (i == 0) continue;  // warm-up
        wall.push_back(w1 - w0);
        for (const PassTiming& p : t)
          if (p.name == "layers: foliage") gpu.push_back(p.milliseconds);
      }
      timer.destroy(dev);
      g.release(dev);
      destroyLayeredVegetation(lv);
      if (!s.ok()) {
        std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
        return 1;
      }
      const double g50 = median(gpu), w50 = median(wall);
      char drawName[64];
      const std::string how = half ? "far " + std::to_string(half) + " at half res" : once ? "shaded once" : "every fragment";
      if (mode == LayerDrawMode::SinglePass)
        std::snprintf(drawName, sizeof drawName, "1 draw, %s", how.c_str());
      else
        std::snprintf(drawName, sizeof drawName, "%u draws, %s", layout.count(), how.c_str());
      if (first)
        std::printf("  %-11llu %11.1f %9.2f %12.1f | ", (unsigned long long)faces, rootsMs, mtris, hit ? cacheMs : -1.0);
      else
        std::printf("  %-11s %11s %9s %12s | ", "", "", "", "");
      std::printf("%-26s %10.2f %10.2f %12.2f %10.2f\n", drawName, g50, w50, double(faces) / w50 / 1e3, median(place));
      first = false;
    }
    std::printf("  (%llu faces: %u leaves, generated in %.0f ms)\n", (unsigned long long)faces, roots.leafCount(), genMs);
  }
  return 0;
}

}  // namespace canopy::bench
