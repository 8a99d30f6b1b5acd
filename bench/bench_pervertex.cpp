// canopy-bench pervertex (issue 17): the 2D method against the per-vertex wind baseline (seed 004,
// Habel IV-VI; render/per_vertex.h) on the same generated scene, context, resolution and camera, in
// one run: per face count, the whole frame of the 2D method with a still camera (simulation,
// dynamics, warp, composite: the layers were sliced once), of the 2D method with the camera turning
// every frame and a re-slice every frame (ReslicePolicy::EveryFrame: its worst case, the paper's
// segmentation per frame), and of the baseline (the whole mesh bent and drawn every frame, whatever
// the camera does) with its wind field (PerVertexWind::KaimalField, the default) and with the
// uniform wind of before 0.7, as medians and as ratios. The still rows are measured in two blocks
// each, alternated (2D, field, uniform, 2D, field, uniform), so this machine's drift falls on all. Wall clock (submit-to-fence, the host's clear subtracted) is the figure; GPU
// timestamps per pass are printed beside it (on lavapipe they read near zero for compute after a
// draw: docs/design.md). A CSV for scripts/plot_bench.py --pervertex.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <map>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "engine/device.h"
#include "engine/timing.h"
#include "render/canopy.h"
#include "tools/scene_generator.h"

namespace canopy::bench {
namespace {

struct Block {
  std::vector<double> wallMs;
  std::map<std::string, std::vector<double>> passMs;
};

struct Context {
  Device& d;
  VegetationModel model;
  CanopyContext* ctx = nullptr;
  HostTargets host;
  GpuTimer timer;
  rg::RenderGraph graph;
  uint32_t w = 0, h = 0;
  double clearMs = 0;

  explicit Context(Device& dev) : d(dev) {}
  ~Context() {
    graph.release(d);
    timer.destroy(d);
    destroyHostTargets(d, host);
    destroyCanopy(ctx);
  }
  LayerView view(int i, float orbitDegrees) const {
    return orbitView(model.boundsMin, model.boundsMax, 20.0f + orbitDegrees * float(i), 10.0f, 40.0f,
                     float(w) / float(h), 0.8f);
  }
  Status init(const std::string& scene, uint64_t faces, uint32_t width, uint32_t height, uint64_t budget) {
    w = width;
    h = height;
    SceneDesc sd;
    sd.faces = faces;
    sd.hierarchy = true;  // the baseline's branch hierarchy; the 2D method ignores it
    CANOPY_TRY(parseSceneKind(scene, &sd.kind));
    CANOPY_TRY(generateScene(sd, &model));
    CanopyDesc desc;
    desc.width = w;
    desc.height = h;
    desc.allowPerVertex = true;
    desc.deviceMemoryBudget = budget;
    // The demo's wind (demo/demo_app.h): the same for both methods.
    desc.params.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    desc.params.simulation.wind.strength = 2.0f;
    desc.params.simulation.wind.frequency = 0.5f;
    desc.params.simulation.wind.modulation = 0.8f;
    CANOPY_TRY(createCanopy(d, model, desc, &ctx));
    CANOPY_TRY(createHostTargets(d, w, h, VK_FORMAT_R8G8B8A8_UNORM, &host));
    CANOPY_TRY(timer.init(d, 64));
    rg::RenderGraph clear;
    Block b;
    Status s = buildHostGraph(d, ctx, host, false, rg::stateOf(rg::Use::ColorAttachmentReadWrite), &clear);
    if (s.ok()) s = sample(nullptr, clear, 0.0f, 10, &b);
    clear.release(d);
    clearMs = median(b.wallMs);
    return s;
  }
  Status sample(CanopyContext* c, rg::RenderGraph& g, float orbitDegrees, int frames, Block* out) {
    FrameSamples s;
    CANOPY_TRY(sampleFrames(d, c, g, timer, [&](int i) { return view(i, orbitDegrees); }, 1.0f / 30.0f, frames, &s));
    for (double v : s.wallMs) out->wallMs.push_back(std::max(0.0, v - clearMs));
    for (auto& [name, v] : s.passMs) out->passMs[name].insert(out->passMs[name].end(), v.begin(), v.end());
    return Status();
  }
  // Switches the method; the host's graph holds Canopy's passes, so it is rebuilt.
  Status use(AnimationMode mode, PerVertexWind wind, ReslicePolicy policy) {
    CanopyParams p = canopyParams(ctx);
    p.animation = mode;
    p.perVertex.wind = wind;
    p.layers.policy = policy;
    CANOPY_TRY(setCanopyParams(ctx, p));
    graph.release(d);
    graph = rg::RenderGraph();
    return buildHostGraph(d, ctx, host, true, rg::stateOf(rg::Use::ColorAttachmentReadWrite), &graph);
  }
  // A block of `frames` frames in `mode` (sampleFrames' two warm-ups slice the layers first).
  Status block(AnimationMode mode, float orbitDegrees, int frames, Block* out,
               PerVertexWind wind = PerVertexWind::KaimalField, ReslicePolicy policy = ReslicePolicy::OnViewChange) {
    CANOPY_TRY(use(mode, wind, policy));
    return sample(ctx, graph, orbitDegrees, frames, out);
  }
};

double p95(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(0.95 * double(v.size())))];
}

}  // namespace

int runPerVertexBench(Device& dev, const std::vector<uint64_t>& faceCounts, const std::string& scene, int frames,
                      uint32_t width, uint32_t height, uint64_t deviceMemoryBudget, const std::string& csvPath) {
  std::printf("\n2D method vs per-vertex baseline (Habel), %s, %ux%u, 5(3-1-1), wind 2 units/s, one context per face count\n",
              scene.c_str(), width, height);
  std::printf("whole frame, wall clock, ms (median / p95; the host's clear subtracted); ratio = baseline / 2D\n");
  std::printf("%12s %10s %19s %19s %19s %19s %12s %12s %12s\n", "faces", "frames", "2D still", "2D turning",
              "per-vertex field", "pv uniform (<0.7)", "pv/2D still", "pv/2D turn", "unif/2D st.");
  std::ofstream csv;
  if (!csvPath.empty()) {
    csv.open(csvPath);
    csv << "faces,2d_still_ms,2d_still_p95,2d_turning_ms,2d_turning_p95,per_vertex_ms,per_vertex_p95,"
           "per_vertex_uniform_ms,per_vertex_uniform_p95\n";
  }
  for (uint64_t faces : faceCounts) {
    // Fewer frames where a frame takes seconds (lavapipe at 10M faces).
    const int n = faces >= 5000000 ? std::max(3, frames / 6) : faces >= 500000 ? std::max(4, frames / 2) : frames;
    Context c(dev);
    Status s = c.init(scene, faces, width, height, deviceMemoryBudget);
    Block still2d, turning2d, perVertex, uniform;
    for (int round = 0; round < 2 && s.ok(); ++round) {
      s = c.block(AnimationMode::Layers2D, 0.0f, n, &still2d);
      if (s.ok()) s = c.block(AnimationMode::PerVertex, 0.0f, n, &perVertex);
      if (s.ok()) s = c.block(AnimationMode::PerVertex, 0.0f, n, &uniform, PerVertexWind::UniformNoise);
    }
    if (s.ok()) s = c.block(AnimationMode::Layers2D, 1.0f, n, &turning2d, PerVertexWind::KaimalField, ReslicePolicy::EveryFrame);
    if (!s.ok()) {
      std::fprintf(stderr, "pervertex bench at %llu faces: %s\n", (unsigned long long)faces, s.message().c_str());
      return 1;
    }
    const double a = median(still2d.wallMs), t = median(turning2d.wallMs), p = median(perVertex.wallMs),
                 u = median(uniform.wallMs);
    char cell[4][40];
    std::snprintf(cell[0], 40, "%.2f / %.2f", a, p95(still2d.wallMs));
    std::snprintf(cell[1], 40, "%.2f / %.2f", t, p95(turning2d.wallMs));
    std::snprintf(cell[2], 40, "%.2f / %.2f", p, p95(perVertex.wallMs));
    std::snprintf(cell[3], 40, "%.2f / %.2f", u, p95(uniform.wallMs));
    std::printf("%12llu %10d %19s %19s %19s %19s %12.2f %12.2f %12.2f\n", (unsigned long long)faces, n, cell[0], cell[1], cell[2],
                cell[3], a > 0 ? p / a : 0.0, t > 0 ? p / t : 0.0, a > 0 ? u / a : 0.0);
    for (const auto& [name, v] : perVertex.passMs)
      std::printf("%12s   per-vertex pass %-28s GPU %.3f ms\n", "", name.c_str(), median(v));
    for (const auto& [name, v] : uniform.passMs)
      if (name.rfind("per-vertex", 0) == 0) std::printf("%12s   uniform    pass %-28s GPU %.3f ms\n", "", name.c_str(), median(v));
    for (const char* pass : {"layers: foliage", "composite: warp + composite (tiles)", "simulation: step"})
      if (turning2d.passMs.count(pass))
        std::printf("%12s   2D turning pass %-28s GPU %.3f ms\n", "", pass, median(turning2d.passMs[pass]));
    if (csv) csv << faces << ',' << a << ',' << p95(still2d.wallMs) << ',' << t << ',' << p95(turning2d.wallMs) << ','
                 << p << ',' << p95(perVertex.wallMs) << ',' << u << ',' << p95(uniform.wallMs) << '\n';
    std::fflush(stdout);
  }
  if (csv) std::printf("wrote %s\n", csvPath.c_str());
  return 0;
}

}  // namespace canopy::bench
