// canopy-smoke: the foundation's main job. Prints the chosen Vulkan device, runs the example
// write -> transform -> reduce compute graph, checks it against the CPU reference and prints a
// per-pass timing table: GPU timestamps (median over frames) next to wall clock, since CPU
// drivers' timestamps are not trustworthy on their own (docs/design.md).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "tools/example_passes.h"
#include "engine/device.h"
#include "tools/own_device.h"
#include "engine/timing.h"
#include "demo/cli.h"

using namespace canopy;

namespace {

const char* typeName(VkPhysicalDeviceType t) {
  switch (t) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: return "discrete GPU";
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: return "integrated GPU";
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: return "virtual GPU";
    case VK_PHYSICAL_DEVICE_TYPE_CPU: return "CPU";
    default: return "other";
  }
}

int usage(const char* why) {
  if (why) std::fprintf(stderr, "canopy-smoke: %s\n", why);
  std::fprintf(why ? stderr : stdout,
               "usage: canopy-smoke [--size WxH] [--frames N] [--device NAME]\n"
               "  --size WxH     example graph size (default 1024x1024)\n"
               "  --frames N     frames to time, 3..10000 (default 30)\n"
               "  --device NAME  substring of the Vulkan device name (default: $CANOPY_DEVICE or best device)\n");
  return why ? 2 : 0;
}

double nowMs() {
  using namespace std::chrono;
  return duration<double, std::milli>(steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int main(int argc, char** argv) {
  ExampleParams prm;
  prm.width = prm.height = 1024;
  int frames = 30;
  DeviceDesc desc;
  desc.applicationName = "canopy-smoke";
  for (int i = 1; i < argc; ++i) {
    std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    if (a == "--help" || a == "-h") return usage(nullptr);
    if (a == "--size") {
      const char* v = next();
      unsigned w = 0, h = 0;
      if (!v || std::sscanf(v, "%ux%u", &w, &h) != 2 || w == 0 || h == 0 || w > 8192 || h > 8192)
        return usage("--size needs WxH with 1 <= W, H <= 8192");
      prm.width = w;
      prm.height = h;
    } else if (a == "--frames") {
      uint32_t n;
      if (!cli::parseUint(next(), 3, 10000, &n)) return usage("--frames needs an integer in [3, 10000]");
      frames = int(n);
    } else if (a == "--device") {
      const char* v = next();
      if (!v) return usage("--device needs a name");
      desc.preferredDevice = v;
    } else {
      return usage(("unknown option '" + a + "'").c_str());
    }
  }

  Device dev;
  Status s = createDevice(desc, &dev);
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-smoke: %s\n", s.message().c_str());
    return 1;
  }
  const auto& p = dev.properties;
  std::printf("Device: %s (%s), Vulkan %u.%u.%u, timestamp period %.3f ns\n", p.deviceName, typeName(p.deviceType),
              VK_API_VERSION_MAJOR(p.apiVersion), VK_API_VERSION_MINOR(p.apiVersion), VK_API_VERSION_PATCH(p.apiVersion),
              p.limits.timestampPeriod);
  // What a new driver is judged by (scripts/figures_of_record.sh reads these lines).
  std::printf("Driver version 0x%08x, vendor 0x%04x, device 0x%04x; subgroup size %u (compute shuffles %s); "
              "max workgroup %u invocations; pipeline statistics %s\n",
              p.driverVersion, p.vendorID, p.deviceID, dev.subgroupSize, dev.computeSubgroupShuffle ? "yes" : "no",
              p.limits.maxComputeWorkGroupInvocations, dev.pipelineStatistics ? "yes" : "no");

  int rc = 0;
  ExamplePipelines pipes;
  Buffer result;
  GpuTimer timer;
  s = createExamplePipelines(dev, &pipes);
  if (s.ok()) s = createBuffer(dev, sizeof(gpu::ExampleResult), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUsage::Readback, &result, "result");
  if (s.ok()) s = timer.init(dev, 8);

  // Wall clock: median submit-to-fence time of graphs holding the first k passes; the difference
  // between consecutive prefixes is one pass's wall time (k = 0: an empty submit, the overhead).
  double wall[4] = {0, 0, 0, 0};
  std::vector<double> gpuMs[3];
  std::vector<double> totalWall;
  for (int k = 0; k <= 3 && s.ok(); ++k) {
    ExampleParams q = prm;
    q.passCount = k == 0 ? 1 : k;
    ExampleGraph eg;
    if (k > 0) s = buildExampleGraph(dev, pipes, q, result, &eg);
    std::vector<double> samples;
    for (int f = 0; f < frames + 2 && s.ok(); ++f) {
      double t0 = nowMs();
      s = submitAndWait(dev, [&](VkCommandBuffer cmd) {
        if (k == 0) return Status();
        timer.reset(cmd);
        return eg.graph.record(cmd, k == 3 ? &timer : nullptr);
      });
      double t1 = nowMs();
      if (f < 2) continue;  // warm-up (pipeline caches, first-touch memory)
      samples.push_back(t1 - t0);
      if (k == 3 && s.ok()) {
        std::vector<PassTiming> t;
        s = timer.read(dev, &t);
        for (size_t i = 0; i < t.size() && i < 3; ++i) gpuMs[i].push_back(t[i].milliseconds);
      }
    }
    wall[k] = median(samples);
    if (k == 3) {
      totalWall = samples;
      std::printf("\nRender graph schedule (%u passes):\n%s", eg.graph.passCount(), eg.graph.describe().c_str());
    }
    eg.graph.release(dev);
  }

  if (s.ok()) {
    const ExampleReference ref = exampleReference(prm);
    gpu::ExampleResult r;
    std::memcpy(&r, result.allocation.mapped, sizeof r);
    const double tol = 1e-5 * std::max(1.0, std::fabs(ref.sum));
    bool ok = std::fabs(r.sum - ref.sum) <= tol && std::fabs(r.minValue - ref.minValue) <= 1e-5 &&
              std::fabs(r.maxValue - ref.maxValue) <= 1e-5 && r.count == prm.width * prm.height;
    std::printf("\nResult (%ux%u): sum %.6g (CPU %.6g), min %.6g (CPU %.6g), max %.6g (CPU %.6g): %s\n", prm.width,
                prm.height, r.sum, ref.sum, r.minValue, ref.minValue, r.maxValue, ref.maxValue,
                ok ? "matches the CPU reference" : "MISMATCH");
    if (!ok) rc = 1;
    const char* names[3] = {"write", "transform", "reduce"};
    std::printf("\nPer-pass timing, median of %d frames:\n", frames);
    std::printf("  %-12s %14s %16s\n", "pass", "GPU ts (ms)", "wall alone (ms)");
    double gsum = 0;
    for (int i = 0; i < 3; ++i) {
      double g = median(gpuMs[i]);
      gsum += g;
      std::printf("  %-12s %14.3f %16.3f\n", names[i], g, wall[i + 1] - wall[i]);
    }
    std::printf("  %-12s %14.3f %16.3f\n", "total", gsum, wall[3] - wall[0]);
    std::printf("  (wall alone = median submit-to-fence time of the first k passes minus the first k-1;\n"
                "   submit overhead %.3f ms; whole frame %.3f ms wall)\n", wall[0], median(totalWall));
  }
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-smoke: %s\n", s.message().c_str());
    rc = 1;
  }
  timer.destroy(dev);
  destroyBuffer(dev, result);
  destroyExamplePipelines(dev, pipes);
  destroyDevice(dev);
  return rc;
}
