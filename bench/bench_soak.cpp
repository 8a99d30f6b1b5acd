// Soak (issue "Reliability"): many frames of one context with the parameters changed at random
// (within their ranges) every frame and the layers re-sliced every `rebuildEvery` frames (a new
// camera yaw and the layer count switched between 3 and 5, so parts are replaced), each frame
// submitted and completed. It checks what a long run could break: NaN or Inf in the simulation's
// fields, the warp grid or the frame (an RGBA16F target, which keeps NaN), growth of the process's
// resident memory and of Canopy's live device allocations, and growth of the frame time.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <unistd.h>

#include <glm/gtc/packing.hpp>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "engine/device.h"
#include "engine/transfer.h"
#include "render/canopy.h"
#include "tools/leaf_cloud.h"

namespace canopy::bench {
namespace {

double rssMiB() {
  long pages = 0, resident = 0;
  FILE* f = std::fopen("/proc/self/statm", "r");
  if (!f) return 0;
  if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
  std::fclose(f);
  return double(resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}


// Non-finite floats in a buffer read back whole.
Status countNonFinite(Device& d, const Buffer& b, uint64_t* bad, uint64_t* seen) {
  std::vector<float> v(size_t(b.size / 4));
  CANOPY_TRY(readbackBuffer(d, b, v.data(), v.size() * 4, rg::stateOf(rg::Use::ComputeStorageReadWrite)));
  for (float x : v) *bad += !std::isfinite(x);
  *seen += v.size();
  return Status();
}

}  // namespace

int runSoakBench(Device& dev, int frames, int rebuildEvery, bool check) {
  const uint32_t w = 192, h = 128;
  const VegetationModel model = makeLeafCloud(3000, 11, true);
  std::printf("\nSoak: %d frames of a %zu-face leaf cloud at %ux%u, parameters changed every frame, layers re-sliced every %d "
              "frames (camera turned, layer count 3 <-> 5).\n",
              frames, model.triangleCount(), w, h, rebuildEvery);
  CanopyContext* ctx = nullptr;
  HostTargets host;
  rg::RenderGraph g;
  uint64_t builtFor = ~0ull;
  Status s = [&]() -> Status {
    CANOPY_TRY(createHostTargets(dev, w, h, VK_FORMAT_R16G16B16A16_SFLOAT, &host));
    const Image& color = host.color;
    CanopyDesc desc;
    desc.width = w;
    desc.height = h;
    desc.colorFormat = host.color.format;
    desc.depthFormat = host.depth.format;
    CANOPY_TRY(createCanopy(dev, model, desc, &ctx));

    std::mt19937 rng(7);
    auto uni = [&](float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(rng); };
    const CanopyParams base = canopyParams(ctx);
    const rg::State src = rg::stateOf(rg::Use::TransferSrc);
    uint64_t badSim = 0, seenSim = 0, badFrame = 0, seenFrame = 0, rebuilds = 0, checks = 0;
    double rss0 = 0, rssEnd = 0;
    uint64_t alloc0 = 0, blocks0 = 0;
    std::vector<double> times;
    const int warm = std::max(1, frames / 10);  // the baseline for growth: after caches and pools settled
    const int checkEvery = std::max(1, std::min(500, frames / 20));
    float yaw = 20.0f;
    bool five = true;
    const double t0 = nowMs();
    for (int i = 0; i < frames; ++i) {
      CanopyParams p = base;
      p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
      p.simulation.wind.strength = uni(0.0f, 3.0f);
      p.simulation.wind.frequency = uni(0.0f, 2.0f);
      p.simulation.wind.gust = uni(0.0f, 1.0f);
      p.simulation.wind.sides = 1 + uint32_t(rng() % 15);
      p.simulation.wave.stiffness = uni(5.0f, 200.0f);
      p.simulation.wave.damping = uni(0.2f, 6.0f);
      p.simulation.wave.gain = uni(-2.0f, 2.0f);
      p.simulation.motors = {Motor{uni(0, 1), uni(0, 1), uni(0.02f, 0.3f), uni(-3, 3)}};
      p.dynamics.vd = uni(0.2f, 5.0f);
      p.dynamics.delay = rng() % 2 ? DelayMode::Exact : DelayMode::Approximate;
      p.dynamics.lambda = {uni(50, 500), uni(50, 500), uni(0, 300)};
      p.dynamics.rigidity = uni(0.0f, 3.0f);
      p.composite.exposure = uni(0.25f, 4.0f);
      if (i % rebuildEvery == 0 && i > 0) {
        yaw += 7.0f;
        five = !five;
        ++rebuilds;
      }
      p.layers.layout = five ? LayerLayout{{3, 1, 1}} : LayerLayout{{1, 1, 1}};
      CANOPY_TRY(setCanopyParams(ctx, p));
      if (canopyResourceGeneration(ctx) != builtFor) {  // new layer images: the host's graph again
        g.release(dev);
        g = rg::RenderGraph();
        CANOPY_TRY(buildHostGraph(dev, ctx, host, true, src, &g));
        builtFor = canopyResourceGeneration(ctx);
      }
      const LayerView view = orbitView(model.boundsMin, model.boundsMax, yaw, 12.0f, 40.0f, float(w) / float(h), 1.1f);
      CANOPY_TRY(beginCanopyFrame(ctx, makeCanopyFrame(view, 1.0f / 30.0f, uint64_t(i + 1))));
      const double f0 = nowMs();
      CANOPY_TRY(submitAndWait(dev, [&](VkCommandBuffer cmd) { return g.record(cmd); }));
      times.push_back(nowMs() - f0);
      if (i == warm) {
        rss0 = rssMiB();
        alloc0 = dev.allocator->allocationCount;
        blocks0 = dev.allocator->blocks.size();
      }
      if ((i + 1) % 1000 == 0) {
        std::printf("  ... %d frames, %.0f s\n", i + 1, (nowMs() - t0) / 1000.0);
        std::fflush(stdout);
      }
      if (i % checkEvery == checkEvery - 1 || i == frames - 1) {
        ++checks;
        const Simulation& sim = canopySimulation(ctx);
        for (const Buffer* b : {&sim.velocity, &sim.wave, &sim.tiled, &sim.ring})
          CANOPY_TRY(countNonFinite(dev, *b, &badSim, &seenSim));
        CANOPY_TRY(countNonFinite(dev, canopyDynamics(ctx).displacement, &badSim, &seenSim));
        std::vector<uint64_t> half(size_t(w) * h);
        CANOPY_TRY(readbackImage(dev, color, 0, 8, half.data(), src));
        for (uint64_t v : half) {
          const glm::vec4 c = glm::unpackHalf4x16(v);
          badFrame += !(std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z) && std::isfinite(c.w));
        }
        seenFrame += half.size();
      }
    }
    const double seconds = (nowMs() - t0) / 1000.0;
    rssEnd = rssMiB();
    const uint64_t allocEnd = dev.allocator->allocationCount, blocksEnd = dev.allocator->blocks.size();
    const size_t k = std::min<size_t>(1000, times.size() / 3);
    const std::vector<double> first(times.begin() + long(std::min<size_t>(size_t(warm), times.size() - k)),
                                    times.begin() + long(std::min<size_t>(size_t(warm), times.size() - k) + k));
    const std::vector<double> last(times.end() - long(k), times.end());
    const CanopyStats st = canopyStats(ctx);
    std::printf("  %d frames (simulation steps) in %.1f s; layers re-sliced %llu times (%llu rebuild requests); "
                "%d parameter sets applied\n",
                frames, seconds, (unsigned long long)st.layers.rebuilds, (unsigned long long)rebuilds, frames);
    std::printf("  NaN/Inf: %llu of %llu simulation and warp-grid values, %llu of %llu frame pixels (%llu checks)\n",
                (unsigned long long)badSim, (unsigned long long)seenSim, (unsigned long long)badFrame,
                (unsigned long long)seenFrame, (unsigned long long)checks);
    std::printf("  host RSS: %.1f MiB at frame %d, %.1f MiB at the end: growth %+.1f MiB\n", rss0, warm, rssEnd, rssEnd - rss0);
    std::printf("  Canopy device allocations: %llu live at frame %d, %llu at the end; memory blocks %llu -> %llu; "
                "releases pending %llu\n",
                (unsigned long long)alloc0, warm, (unsigned long long)allocEnd, (unsigned long long)blocks0,
                (unsigned long long)blocksEnd, (unsigned long long)st.pendingReleases);
    std::printf("  frame time, median of %zu frames: %.2f ms after warm-up, %.2f ms at the end (%+.1f %%)\n", k,
                median(first), median(last), 100.0 * (median(last) / std::max(median(first), 1e-9) - 1.0));
    if (check) {
      if (badSim || badFrame) return Status::error("soak: non-finite values");
      // The same layer count at both points: the same live allocations.
      if (allocEnd > alloc0 + 8 || blocksEnd > blocks0)
        return Status::error("soak: Canopy's device allocations grew from " + std::to_string(alloc0) + " to " +
                             std::to_string(allocEnd));
      if (rssEnd - rss0 > 64.0) return Status::error("soak: resident memory grew by " + std::to_string(rssEnd - rss0) + " MiB");
    }
    return Status();
  }();
  if (dev.device) vkQueueWaitIdle(dev.queue);
  destroyCanopy(ctx);
  g.release(dev);
  destroyHostTargets(dev, host);
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
    return 1;
  }
  return 0;
}

}  // namespace canopy::bench
