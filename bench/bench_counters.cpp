// canopy-bench counters (issue 56; docs/performance.md "Work per frame, counted"): the work each
// frame kind does, counted rather than timed — vertex, primitive, fragment and compute invocations
// from pipeline statistics queries around every pass, and the bytes of the images and buffers each
// pass declares (an estimate: whole resources) — for a still frame, a reprojected one (the camera
// moved 0.25 degrees, no re-slice), a re-slice at once and the first step of a spread re-slice; per
// pixel and per face, and as JSON. Properties of the algorithm, not of the driver: they carry to a GPU.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "engine/device.h"
#include "engine/pass_counters.h"
#include "engine/transfer.h"
#include "tools/scene_generator.h"

namespace canopy::bench {
namespace {

struct FrameCounts {
  std::string kind;
  PassCounts total;
  std::vector<PassCounts> passes;
};

const char* const kKinds[4] = {"still", "reprojected", "re-slice", "spread step"};

Status countFrames(Device& d, const VegetationModel& m, uint32_t w, uint32_t h, std::vector<FrameCounts>* out) {
  CanopyDesc desc;
  desc.width = w;
  desc.height = h;
  desc.colorFormat = VK_FORMAT_R8G8B8A8_UNORM;
  desc.deviceMemoryBudget = 0;  // the mesh resident: the counts are the method's, not the staging ring's
  desc.params.layers.rebuildBudgetMs = 4.0f;  // re-slices spread unless asked at once
  CanopyContext* ctx = nullptr;
  HostTargets targets;
  rg::RenderGraph graph;
  PassCounters counters;
  Status s = [&]() -> Status {
    CANOPY_TRY(createCanopy(d, m, desc, &ctx));
    CANOPY_TRY(createHostTargets(d, w, h, VK_FORMAT_R8G8B8A8_UNORM, &targets));
    CANOPY_TRY(counters.init(d, 128));
    CANOPY_TRY(buildHostGraph(d, ctx, targets, true, rg::stateOf(rg::Use::TransferSrc), &graph));
    static uint64_t number = 0;  // the device's frame numbers never decrease
    auto frame = [&](const LayerView& view, FrameCounts* fc) -> Status {
      CanopyFrame f;
      f.camera = toCamera(view);
      f.dt = 1.0f / 30.0f;
      f.frameNumber = ++number;
      CANOPY_TRY(beginCanopyFrame(ctx, f));
      CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) {
        counters.reset(cmd);
        return graph.record(cmd, nullptr, &counters);
      }));
      if (!fc) return Status();
      CANOPY_TRY(counters.read(d, &fc->passes));
      for (const PassCounts& p : fc->passes) {
        fc->total.vertexInvocations += p.vertexInvocations;
        fc->total.clippingPrimitives += p.clippingPrimitives;
        fc->total.fragmentInvocations += p.fragmentInvocations;
        fc->total.computeInvocations += p.computeInvocations;
        fc->total.bytesRead += p.bytesRead;
        fc->total.bytesWritten += p.bytesWritten;
      }
      return Status();
    };
    const float aspect = float(w) / float(h);
    const LayerView still = orbitView(m.boundsMin, m.boundsMax, 20.0f, 15.0f, 40.0f, aspect);
    // The first slice (spread over frames), then a few frames of the history.
    for (int i = 0; i < 400 && (i < 3 || canopyStats(ctx).layers.spreadPhase != 0); ++i) CANOPY_TRY(frame(still, nullptr));
    FrameCounts fc[4];
    for (int k = 0; k < 4; ++k) fc[k].kind = kKinds[k];
    CANOPY_TRY(frame(still, &fc[0]));
    const uint64_t rebuilds = canopyStats(ctx).layers.rebuilds;
    CANOPY_TRY(frame(orbitView(m.boundsMin, m.boundsMax, 20.25f, 15.0f, 40.0f, aspect), &fc[1]));
    if (canopyStats(ctx).layers.rebuilds != rebuilds || canopyStats(ctx).layers.spreadPhase != 0)
      return Status::error("counters: the 0.25-degree move re-sliced");
    CANOPY_TRY(requestCanopyRebuild(ctx, true));
    CANOPY_TRY(frame(still, &fc[2]));
    // A spread re-slice: the placement's frames, then the first frame that draws part of the new set.
    CANOPY_TRY(requestCanopyRebuild(ctx, false));
    for (int i = 0; i < 2000 && canopyStats(ctx).layers.spreadPhase != 2; ++i) CANOPY_TRY(frame(still, nullptr));
    if (canopyStats(ctx).layers.spreadPhase != 2) return Status::error("counters: the spread re-slice never reached its drawing phase");
    CANOPY_TRY(frame(still, &fc[3]));
    for (const FrameCounts& f : fc) out->push_back(f);
    return Status();
  }();
  vkDeviceWaitIdle(d.device);
  graph.release(d);
  counters.destroy(d);
  destroyHostTargets(d, targets);
  if (ctx) destroyCanopy(ctx);
  return s;
}

}  // namespace

int runCounterBench(Device& d, const std::vector<uint64_t>& faceCounts, const std::vector<std::pair<uint32_t, uint32_t>>& sizes,
                    const std::string& jsonPath) {
  if (!d.pipelineStatistics) {
    std::fprintf(stderr, "canopy-bench counters: the device has no pipelineStatisticsQuery feature\n");
    return 1;
  }
  std::printf("\nWork per frame, counted (issue 56): pipeline statistics around every pass and the bytes of the\n"
              "resources each pass declares (an estimate: whole resources), 5(3-1-1), a shrub; per frame kind:\n"
              "still, reprojected (0.25 degrees, no re-slice), a re-slice at once, the first step of a spread one.\n"
              "Fragment invocations include the helper lanes a driver counts along triangle edges.\n\n");
  std::printf("  %-9s %-10s %-12s %12s %12s %13s %12s %10s %10s %10s %9s\n", "faces", "size", "frame", "vertex inv.", "primitives",
              "fragment inv.", "compute inv.", "frag/px", "comp/px", "MB r+w", "B/px");
  std::ofstream json;
  if (!jsonPath.empty()) json.open(jsonPath);
  if (json) json << "{\n  \"device\": \"" << d.properties.deviceName << "\",\n  \"rows\": [\n";
  bool first = true;
  for (uint64_t faces : faceCounts) {
    VegetationModel m;
    SceneDesc sd;
    sd.kind = SceneKind::Shrub;
    sd.faces = faces;
    Status s = generateScene(sd, &m);
    for (const auto& [w, h] : sizes) {
      std::vector<FrameCounts> rows;
      if (s.ok()) s = countFrames(d, m, w, h, &rows);
      if (!s.ok()) {
        std::fprintf(stderr, "canopy-bench counters: %s\n", s.message().c_str());
        return 1;
      }
      const double px = double(w) * h, f = double(m.triangleCount());
      for (const FrameCounts& r : rows) {
        const PassCounts& t = r.total;
        const double bytes = double(t.bytesRead + t.bytesWritten);
        std::printf("  %-9llu %4ux%-5u %-12s %12llu %12llu %13llu %12llu %10.2f %10.2f %10.1f %9.1f\n",
                    (unsigned long long)m.triangleCount(), w, h, r.kind.c_str(), (unsigned long long)t.vertexInvocations,
                    (unsigned long long)t.clippingPrimitives, (unsigned long long)t.fragmentInvocations,
                    (unsigned long long)t.computeInvocations, double(t.fragmentInvocations) / px, double(t.computeInvocations) / px,
                    bytes / 1e6, bytes / px);
        if (!json) continue;
        json << (first ? "" : ",\n") << "    {\"faces\": " << m.triangleCount() << ", \"width\": " << w << ", \"height\": " << h
             << ", \"frame\": \"" << r.kind << "\", \"vertexInvocations\": " << t.vertexInvocations
             << ", \"primitives\": " << t.clippingPrimitives << ", \"fragmentInvocations\": " << t.fragmentInvocations
             << ", \"computeInvocations\": " << t.computeInvocations << ", \"bytesRead\": " << t.bytesRead
             << ", \"bytesWritten\": " << t.bytesWritten << ", \"vertexPerFace\": " << double(t.vertexInvocations) / f
             << ", \"fragmentsPerPixel\": " << double(t.fragmentInvocations) / px << ", \"passes\": [";
        for (size_t i = 0; i < r.passes.size(); ++i) {
          const PassCounts& p = r.passes[i];
          json << (i ? ", " : "") << "{\"name\": \"" << p.name << "\", \"vertex\": " << p.vertexInvocations
               << ", \"primitives\": " << p.clippingPrimitives << ", \"fragment\": " << p.fragmentInvocations
               << ", \"compute\": " << p.computeInvocations << ", \"bytesRead\": " << p.bytesRead << ", \"bytesWritten\": " << p.bytesWritten
               << "}";
        }
        json << "]}";
        first = false;
      }
      // Ratios between frame kinds (fragments and bytes against the still frame).
      const PassCounts& still = rows[0].total;
      for (size_t k = 1; k < rows.size(); ++k)
        std::printf("  %-9s %-10s %-12s fragments %.2fx, compute %.2fx, bytes %.2fx the still frame\n", "", "", rows[k].kind.c_str(),
                    double(rows[k].total.fragmentInvocations) / std::max(1.0, double(still.fragmentInvocations)),
                    double(rows[k].total.computeInvocations) / std::max(1.0, double(still.computeInvocations)),
                    double(rows[k].total.bytesRead + rows[k].total.bytesWritten) /
                        std::max(1.0, double(still.bytesRead + still.bytesWritten)));
    }
  }
  if (json) {
    json << "\n  ]\n}\n";
    std::printf("\nwrote %s\n", jsonPath.c_str());
  }
  return 0;
}

}  // namespace canopy::bench
