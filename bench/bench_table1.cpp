// canopy-bench table1 (issue 15): the paper's Table 1 at 1024x768 — face counts x layouts
// 3(1-1-1) / 5(3-1-1) x still / orbiting / re-sliced every frame — the last printed beside the paper's FPS, the share of the
// frame the vegetation covers, side-by-side baselines from the same run (as ratios), optional
// scaling series (CSV, drawn by scripts/plot_bench.py), and a JSON file of all of it.
//
// Figures of record are wall clock (submit-to-fence of one whole frame, the host's clear
// subtracted): on CPU devices (lavapipe) GPU timestamps around compute work read near zero after
// any draw (docs/design.md), so per-pass timestamps are written with "trusted": false there.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "compute/sim_reference.h"
#include "compute/simulation.h"
#include "engine/device.h"
#include "engine/timing.h"
#include "engine/transfer.h"
#include "render/canopy.h"
#include "render/layer_layout.h"
#include "tools/scene_generator.h"
#include "tools/world_lock.h"

namespace canopy::bench {
namespace {

struct Spread {
  double median = 0, p95 = 0, max = 0;
};
Spread spreadOf(std::vector<double> v) {
  Spread s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  s.median = median(v);
  s.p95 = v[std::min(v.size() - 1, size_t(std::ceil(0.95 * double(v.size()))) - 1)];
  s.max = v.back();
  return s;
}

struct Measured {
  Spread wall;                          // whole frame, ms, the host's clear subtracted
  std::map<std::string, Spread> passes; // GPU timestamps per pass, ms
};

// `frames` frames (and as many with timestamp queries, sampleFrames) after two warm-ups; the camera orbits by `orbitDegrees` per frame (0: still).
Status measure(Device& d, CanopyContext* ctx, rg::RenderGraph& g, GpuTimer& timer, const VegetationModel& model,
               float aspect, float dt, int frames, float orbitDegrees, double clearMs, Measured* out) {
  FrameSamples s;
  CANOPY_TRY(sampleFrames(
      d, ctx, g, timer,
      [&](int i) {
        return orbitView(model.boundsMin, model.boundsMax, 20.0f + orbitDegrees * float(i), 10.0f, 40.0f, aspect, 0.8f);
      },
      dt, frames, &s));
  for (double& w : s.wallMs) w = std::max(0.0, w - clearMs);
  out->wall = spreadOf(s.wallMs);
  for (auto& [name, v] : s.passMs) out->passes[name] = spreadOf(v);
  return Status();
}

// Share of pixels whose colour differs from the host's clear (the vegetation's coverage).
Status coverage(Device& d, const HostTargets& host, uint32_t w, uint32_t h, double* share) {
  std::vector<uint8_t> px(size_t(w) * h * 4);
  CANOPY_TRY(readbackImage(d, host.color, 0, 4, px.data(), rg::stateOf(rg::Use::ColorAttachmentReadWrite)));
  size_t covered = 0;
  for (uint8_t m : coverageMask(px, w, h, kHostClearRgba8)) covered += m;
  *share = double(covered) / double(size_t(w) * h);
  return Status();
}

std::string jsonString(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    if (uint8_t(c) < 0x20) continue;
    o += c;
  }
  return o + "\"";
}
std::string jsonSpread(const Spread& s) {
  std::ostringstream o;
  o << "{\"median\": " << s.median << ", \"p95\": " << s.p95 << ", \"max\": " << s.max << "}";
  return o.str();
}

struct Row {
  uint64_t faces = 0;
  std::string layout, camera;
  uint32_t width = 0, height = 0;
  Measured m;
  double coverage = -1;
  double paperFps = 0;
};

struct Baseline {
  std::string name, a, b;  // ratio = b / a
  double aMs = 0, bMs = 0;
};

// The paper's Table 1 (GTX 275, 1024x768): 80K faces 70 / 65 FPS, 50M faces 40 / 34 FPS for
// 3(1-1-1) / 5(3-1-1). Our reading: its frames include segmenting the layers (its frame rate falls
// with the face count only through segmentation), so only a row that re-slices every frame is
// measured as the paper measured, and only at the paper's own face counts (docs/performance.md
// "The paper's Table 1"); 0: no comparable figure.
double paperFps(uint64_t faces, uint32_t layers, const std::string& camera) {
  if (camera != "every-frame") return 0;
  if (faces >= 76000 && faces <= 84000) return layers == 3 ? 70 : 65;
  if (faces >= 47500000 && faces <= 52500000) return layers == 3 ? 40 : 34;
  return 0;
}

// One context at `faces`, `w` x `h`: the host's clear alone, then each configuration.
struct Bench {
  Device& d;
  const Table1Options& o;
  VegetationModel model;
  CanopyContext* ctx = nullptr;
  HostTargets host;
  GpuTimer timer;
  rg::RenderGraph graph;
  double clearMs = 0;
  uint32_t w = 0, h = 0;

  Bench(Device& dev, const Table1Options& opt) : d(dev), o(opt) {}
  ~Bench() {
    graph.release(d);
    timer.destroy(d);
    destroyHostTargets(d, host);
    destroyCanopy(ctx);
  }
  Status init(uint64_t faces, uint32_t width, uint32_t height) {
    w = width;
    h = height;
    SceneDesc sd;
    sd.faces = faces;
    CANOPY_TRY(parseSceneKind(o.scene, &sd.kind));
    CANOPY_TRY(generateScene(sd, &model));
    CanopyDesc desc;
    desc.width = w;
    desc.height = h;
    desc.maxLayers = CANOPY_MAX_LAYERS;  // the layer series goes to 9
    desc.deviceMemoryBudget = o.deviceMemoryBudget;
    desc.guardBand = o.guardBand;
    CANOPY_TRY(createCanopy(d, model, desc, &ctx));
    CANOPY_TRY(createHostTargets(d, w, h, VK_FORMAT_R8G8B8A8_UNORM, &host));
    CANOPY_TRY(timer.init(d, 64));
    rg::RenderGraph clear;
    Measured m;
    Status s = buildHostGraph(d, ctx, host, false, rg::stateOf(rg::Use::ColorAttachmentReadWrite), &clear);
    if (s.ok()) s = measure(d, nullptr, clear, timer, model, float(w) / float(h), 0.0f, std::min(o.frames, 10), 0.0f, 0.0, &m);
    clear.release(d);
    clearMs = m.wall.median;
    return s;
  }
  Status set(const std::string& layout, CompositePath path = CompositePath::Compute,
             LayerDrawMode draw = LayerDrawMode::Auto, ReslicePolicy policy = ReslicePolicy::OnViewChange) {
    CanopyParams p = canopyParams(ctx);
    CANOPY_TRY(parseLayerLayout(layout, &p.layers.layout));
    p.composite.path = path;
    p.layers.draw = draw;
    p.layers.policy = policy;
    CANOPY_TRY(setCanopyParams(ctx, p));
    // A new layout can replace Canopy's images: the host's graph imports them, so it is rebuilt.
    graph.release(d);
    graph = rg::RenderGraph();
    return buildHostGraph(d, ctx, host, true, rg::stateOf(rg::Use::ColorAttachmentReadWrite), &graph);
  }
  // Still-camera frames until no re-slice is running: a mesh over the device budget is streamed,
  // and its re-slice (the first view, a new layout) takes a slice a frame (docs/design.md "Layers:
  // mesh budget and staging ring"); a still row must not time those.
  Status settle() {
    for (int i = 0; i < 100000; ++i) {
      CanopyFrame f;
      f.camera = toCamera(orbitView(model.boundsMin, model.boundsMax, 20.0f, 10.0f, 40.0f, float(w) / float(h), 0.8f));
      f.dt = 1.0f / 30.0f;
      CANOPY_TRY(beginCanopyFrame(ctx, f));
      CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) { return graph.record(cmd, nullptr); }));
      if (canopyStats(ctx).layers.spreadPhase == 0) return Status();
    }
    return Status::error("table1: the re-slice did not end");
  }
  // Whole frame (simulation + dynamics + warp + composite); the first frame slices the layers.
  Status frame(float orbitDegrees, int frames, Measured* m, float dt = 1.0f / 30.0f) {
    Measured warm;
    CANOPY_TRY(settle());
    CANOPY_TRY(measure(d, ctx, graph, timer, model, float(w) / float(h), dt, 1, 0.0f, clearMs, &warm));
    return measure(d, ctx, graph, timer, model, float(w) / float(h), dt, frames, orbitDegrees, clearMs, m);
  }
};

// Still-camera frames of two contexts (e.g. 80K and 10M faces) alternated frame by frame, A B A B
// ..., after two warm-ups each (the first slices the layers): this machine's drift and bursts then
// fall on both alike, where rows measured a minute apart differ by their noise. Medians, each
// context's host clear subtracted; frames without timestamp queries. `pairMedian`: the median of each
// B frame over the A frame just before it, which a burst longer than the pair cannot skew.
Status pairedStill(Bench& a, Bench& b, const std::string& layout, int frames, double* aMs, double* bMs,
                   double* pairMedian) {
  CANOPY_TRY(a.set(layout));
  CANOPY_TRY(b.set(layout));
  CANOPY_TRY(a.settle());
  CANOPY_TRY(b.settle());
  std::vector<double> wa, wb;
  for (int i = 0; i < 2 * (frames + 2); ++i) {
    Bench& x = (i & 1) ? b : a;
    CanopyFrame f;
    f.camera = toCamera(orbitView(x.model.boundsMin, x.model.boundsMax, 20.0f, 10.0f, 40.0f, float(x.w) / float(x.h), 0.8f));
    f.dt = 1.0f / 30.0f;
    CANOPY_TRY(beginCanopyFrame(x.ctx, f));
    const double t0 = nowMs();
    CANOPY_TRY(submitAndWait(x.d, [&](VkCommandBuffer cmd) { return x.graph.record(cmd, nullptr); }));
    const double ms = std::max(0.0, nowMs() - t0 - x.clearMs);
    if (i >= 4) ((i & 1) ? wb : wa).push_back(ms);
  }
  *aMs = spreadOf(wa).median;
  *bMs = spreadOf(wb).median;
  std::vector<double> ratios;
  for (size_t i = 0; i < wa.size() && i < wb.size(); ++i) ratios.push_back(wb[i] / std::max(wa[i], 1e-9));
  *pairMedian = median(ratios);
  return Status();
}

// The paper's split: the same step by the CPU reference, its tiled field and history slot
// uploaded every frame (measured: the CPU step and the upload, each median of `frames`).
Status cpuSplitMs(Device& d, int frames, double* stepMs, double* uploadMs) {
  const uint32_t n = 64;
  ref::SimState st = ref::makeState(n, 8);
  SimulationParams p;
  std::vector<double> step, up;
  Buffer staging;
  CANOPY_TRY(createBuffer(d, 2ull * 2 * n * n * sizeof(float), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                          MemoryUsage::DeviceLocal, &staging, "bench: cpu split upload"));
  std::vector<float> field(2ull * 2 * n * n, 0.25f);
  Status s;
  double t = 0;
  for (int f = 0; f < frames + 2 && s.ok(); ++f) {
    gpu::SimFrame fr;
    s = makeSimFrame(p, n, float(t), 1.0f / 30.0f, uint32_t(f % 8), 8, &fr);
    if (!s.ok()) break;
    const double t0 = nowMs();
    ref::step(fr, st);
    const double t1 = nowMs();
    s = uploadBuffer(d, nullptr, staging, field.data(), field.size() * sizeof(float), rg::stateOf(rg::Use::ComputeStorageRead));
    const double t2 = nowMs();
    t += 1.0 / 30.0;
    if (f >= 2) {
      step.push_back(t1 - t0);
      up.push_back(t2 - t1);
    }
  }
  destroyBuffer(d, staging);
  CANOPY_TRY(s);
  *stepMs = median(step);
  *uploadMs = median(up);
  return Status();
}

std::string layoutFor(uint32_t layers) {
  // Near-heavy like the paper's 5(3-1-1): the far two regions get one layer each.
  if (layers == 1) return "1(1-0-0)";
  if (layers == 2) return "2(1-1-0)";
  return std::to_string(layers) + "(" + std::to_string(layers - 2) + "-1-1)";
}

}  // namespace

namespace {

struct FaceRatio {
  std::string layout;
  double smallMs = 0, largeMs = 0, pairMedian = 0;
};

struct Point {
  std::string series;
  double x = 0;
  std::string label;
  Spread wall;
};

// Scaling series: the still frame against face count, layer count and resolution (o.series), with
// CSV files in o.csvDir.
int runSeries(Device& d, const Table1Options& o, std::vector<Point>* series) {
  std::printf("\nScaling series (still camera, whole frame ms, median):\n");
  auto point = [&](const std::string& name, double x, const std::string& label, uint64_t faces, uint32_t w, uint32_t h,
                   const std::string& layout) -> Status {
    Bench b(d, o);
    CANOPY_TRY(b.init(faces, w, h));
    CANOPY_TRY(b.set(layout));
    Measured m;
    CANOPY_TRY(b.frame(0.0f, o.frames, &m));
    series->push_back({name, x, label, m.wall});
    std::printf("  %-11s %-12s %9.2f ms\n", name.c_str(), label.c_str(), m.wall.median);
    return Status();
  };
  Status s;
  for (uint64_t f : o.seriesFaces)
    if (s.ok()) s = point("faces", double(f), std::to_string(f), f, o.width, o.height, "5(3-1-1)");
  for (uint32_t l = 1; l <= 9 && s.ok(); ++l) s = point("layers", l, layoutFor(l), o.faces.front(), o.width, o.height, layoutFor(l));
  const uint32_t res[][2] = {{512, 384}, {1024, 768}, {1280, 720}, {1920, 1080}};
  for (const auto& r : res)
    if (s.ok())
      s = point("resolution", double(r[0]) * r[1], std::to_string(r[0]) + "x" + std::to_string(r[1]), o.faces.front(), r[0],
                r[1], "5(3-1-1)");
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
    return 1;
  }
  if (!o.csvDir.empty())
    for (const char* name : {"faces", "layers", "resolution"}) {
      const std::string path = o.csvDir + "/series_" + name + ".csv";
      std::ofstream f(path);
      f << "x,label,median_ms,p95_ms,max_ms\n";
      for (const Point& p : *series)
        if (p.series == name) f << p.x << "," << p.label << "," << p.wall.median << "," << p.wall.p95 << "," << p.wall.max << "\n";
      if (!f) {
        std::fprintf(stderr, "canopy-bench: cannot write %s\n", path.c_str());
        return 1;
      }
      std::printf("  wrote %s\n", path.c_str());
    }
  return 0;
}

// The run as JSON (Table1Options.json): the rows, the baselines, the face-count ratios and the series.
int writeTable1Json(const Device& d, const Table1Options& o, const std::vector<Row>& rows, const std::vector<Baseline>& baselines,
                    const std::vector<FaceRatio>& faceRatios, const std::vector<Point>& series) {
  const bool cpuDevice = d.properties.deviceType == VK_PHYSICAL_DEVICE_TYPE_CPU;
  std::ostringstream j;
  j << "{\n  \"device\": " << jsonString(d.properties.deviceName) << ",\n  \"deviceType\": "
    << (cpuDevice ? "\"cpu\"" : "\"gpu\"") << ",\n  \"driverVersion\": " << d.properties.driverVersion
    << ",\n  \"apiVersion\": " << d.properties.apiVersion << ",\n  \"timestampsTrusted\": " << (cpuDevice ? "false" : "true")
    << ",\n  \"figureOfRecord\": \"wall clock, submit-to-fence of one frame minus the host's clear, frames without timestamp queries\""
    << ",\n  \"params\": {\"width\": " << o.width << ", \"height\": " << o.height << ", \"scene\": " << jsonString(o.scene)
    << ", \"frames\": " << o.frames << ", \"orbitDegreesPerFrame\": " << o.orbitDegrees
    << ", \"simulation\": {\"gridSize\": 64, \"dt\": 0.0333333}, \"defaults\": \"CanopyParams defaults unless the row says\"},\n"
    << "  \"rows\": [\n";
  for (size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    j << "    {\"faces\": " << r.faces << ", \"layout\": " << jsonString(r.layout) << ", \"camera\": " << jsonString(r.camera)
      << ", \"width\": " << r.width << ", \"height\": " << r.height << ", \"frameMs\": " << jsonSpread(r.m.wall)
      << ", \"fps\": " << 1000.0 / std::max(r.m.wall.median, 1e-9) << ", \"paperFps\": " << r.paperFps
      << ", \"coverage\": " << r.coverage << ", \"passes\": {";
    size_t k = 0;
    for (const auto& [name, sp] : r.m.passes) j << (k++ ? ", " : "") << jsonString(name) << ": " << jsonSpread(sp);
    j << "}}" << (i + 1 < rows.size() ? "," : "") << "\n";
  }
  j << "  ],\n  \"baselines\": [\n";
  for (size_t i = 0; i < baselines.size(); ++i) {
    const Baseline& x = baselines[i];
    j << "    {\"name\": " << jsonString(x.name) << ", \"first\": " << jsonString(x.a) << ", \"firstMs\": " << x.aMs
      << ", \"second\": " << jsonString(x.b) << ", \"secondMs\": " << x.bMs
      << ", \"ratio\": " << x.bMs / std::max(x.aMs, 1e-9) << "}" << (i + 1 < baselines.size() ? "," : "") << "\n";
  }
  j << "  ],\n  \"faceRatios\": [\n";
  for (size_t i = 0; i < faceRatios.size(); ++i) {
    const FaceRatio& x = faceRatios[i];
    j << "    {\"layout\": " << jsonString(x.layout) << ", \"smallFaces\": " << o.faces.front() << ", \"smallMs\": " << x.smallMs
      << ", \"largeFaces\": " << o.faces.back() << ", \"largeMs\": " << x.largeMs
      << ", \"ratio\": " << x.largeMs / std::max(x.smallMs, 1e-9) << ", \"pairRatioMedian\": " << x.pairMedian
      << ", \"frames\": " << o.pairFrames << ", \"method\": \"frames alternated\"}"
      << (i + 1 < faceRatios.size() ? "," : "") << "\n";
  }
  j << "  ],\n  \"series\": [\n";
  for (size_t i = 0; i < series.size(); ++i)
    j << "    {\"series\": " << jsonString(series[i].series) << ", \"x\": " << series[i].x << ", \"label\": "
      << jsonString(series[i].label) << ", \"frameMs\": " << jsonSpread(series[i].wall) << "}"
      << (i + 1 < series.size() ? "," : "") << "\n";
  j << "  ]\n}\n";
  std::ofstream f(o.json);
  f << j.str();
  if (!f) {
    std::fprintf(stderr, "canopy-bench: cannot write %s\n", o.json.c_str());
    return 1;
  }
  std::printf("\nwrote %s\n", o.json.c_str());
  return 0;
}

}  // namespace

int runTable1Bench(Device& d, const Table1Options& o) {
  std::printf("\nTable 1 (paper: GTX 275, simulation on the CPU) at %ux%u, generated scene '%s'; whole frame =\n"
              "simulation step (N = 64, dt = 1/30 s) + dynamics + warp + composite, wall clock minus the host's clear;\n"
              "median / p95 / max of %d frames recorded without timestamp queries (per-pass figures come from as many\n"
              "other frames with them). Orbit, the moving camera: it turns %.2f degrees per frame and the layers are\n"
              "reprojected between re-slices chosen by their error (LayerSettings defaults: at once when the estimated\n"
              "error passes %.2g px); every-frame: the same orbit re-sliced every frame,\n"
              "the paper's measurement as we read it, the only rows its FPS is printed beside (at its 80K and 50M faces).\n"
              "Coverage: share of pixels the vegetation changes.\n\n",
              o.width, o.height, o.scene.c_str(), o.frames, o.orbitDegrees, double(LayerSettings{}.errorThresholdPixels));
  std::printf("  %-10s %-9s %-11s %9s %8s %8s %7s %9s %9s\n", "faces", "layers", "camera", "frame ms", "p95", "max", "FPS",
              "paper FPS", "coverage");
  std::vector<Row> rows;
  std::vector<Baseline> baselines;
  std::vector<FaceRatio> faceRatios;  // still frame, largest / smallest face count, frames alternated
  std::unique_ptr<Bench> smallest;    // the first face count's context, kept for the paired comparison
  for (uint64_t faces : o.faces) {
    const double g0 = nowMs();
    auto bench = std::make_unique<Bench>(d, o);
    Bench& b = *bench;
    Status s = b.init(faces, o.width, o.height);
    const double prepMs = nowMs() - g0;
    for (const char* layout : {"3(1-1-1)", "5(3-1-1)"}) {
      // Still; orbiting with the re-slicing policy; orbiting with a re-slice every frame (the
      // paper's segmentation in every measured frame).
      for (const char* camera : {"still", "orbit", "every-frame"}) {
        if (!s.ok()) break;
        const float orbit = std::string(camera) == "still" ? 0.0f : o.orbitDegrees;
        Row r;
        r.faces = faces;
        r.layout = layout;
        r.camera = camera;
        r.width = o.width;
        r.height = o.height;
        s = b.set(layout, CompositePath::Compute, LayerDrawMode::Auto,
                  r.camera == "every-frame" ? ReslicePolicy::EveryFrame : ReslicePolicy::OnViewChange);
        const int frames = orbit == 0.0f || faces <= 1000000 ? o.frames : std::max(3, o.frames / 5);
        if (s.ok()) s = b.frame(orbit, frames, &r.m);
        if (s.ok() && orbit == 0.0f) s = coverage(d, b.host, o.width, o.height, &r.coverage);
        if (!s.ok()) break;
        r.paperFps = paperFps(faces, layout[0] == '3' ? 3 : 5, r.camera);
        char cover[16] = "        -", paper[16] = "        -";
        if (r.coverage >= 0) std::snprintf(cover, sizeof cover, "%8.1f%%", 100.0 * r.coverage);
        if (r.paperFps > 0) std::snprintf(paper, sizeof paper, "%9.0f", r.paperFps);
        std::printf("  %-10llu %-9s %-11s %9.2f %8.2f %8.2f %7.1f %9s %s\n", (unsigned long long)faces, layout,
                    r.camera.c_str(), r.m.wall.median, r.m.wall.p95, r.m.wall.max, 1000.0 / r.m.wall.median, paper, cover);
        rows.push_back(r);
      }
    }
    // Baselines at the first (smallest) face count, 5(3-1-1), in this run.
    if (s.ok() && faces == o.faces.front()) {
      Measured gpuAll, frag, anim, orbitSingle, orbitPer;
      s = b.set("5(3-1-1)");
      if (s.ok()) s = b.frame(0.0f, o.frames, &gpuAll);
      if (s.ok()) s = b.set("5(3-1-1)", CompositePath::Fragment);
      if (s.ok()) s = b.frame(0.0f, o.frames, &frag);
      if (s.ok()) s = b.set("5(3-1-1)");
      if (s.ok()) s = b.frame(0.0f, o.frames, &anim, 0.0f);
      double cpuStep = 0, upload = 0;
      if (s.ok()) s = cpuSplitMs(d, o.frames, &cpuStep, &upload);
      // The draw paths compared where they are paid: re-slicing every frame (an orbit re-sliced by
      // its error may not re-slice at all in these frames).
      if (s.ok()) s = b.set("5(3-1-1)", CompositePath::Compute, LayerDrawMode::SinglePass, ReslicePolicy::EveryFrame);
      if (s.ok()) s = b.frame(o.orbitDegrees, o.frames, &orbitSingle);
      if (s.ok()) s = b.set("5(3-1-1)", CompositePath::Compute, LayerDrawMode::PerLayer, ReslicePolicy::EveryFrame);
      if (s.ok()) s = b.frame(o.orbitDegrees, o.frames, &orbitPer);
      if (s.ok()) {
        const double split = cpuStep + upload + anim.wall.median;
        baselines.push_back({"CPU simulation + upload (paper's split) vs all-GPU frame", "all-GPU", "CPU split",
                             gpuAll.wall.median, split});
        baselines.push_back({"fragment vs compute compositing (whole frame)", "compute", "fragment", gpuAll.wall.median,
                             frag.wall.median});
        baselines.push_back({"one draw per layer vs one layered draw (re-sliced every frame)", "layered draw", "per layer",
                             orbitSingle.wall.median, orbitPer.wall.median});
        double orbitMs = 0, everyMs = 0;
        for (const Row& r : rows)
          if (r.faces == faces && r.layout == "5(3-1-1)") {
            if (r.camera == "orbit") orbitMs = r.m.wall.median;
            if (r.camera == "every-frame") everyMs = r.m.wall.median;
          }
        baselines.push_back({"orbiting vs still camera", "still", "orbit", gpuAll.wall.median, orbitMs});
        baselines.push_back({"re-slicing every frame vs still camera", "still", "every-frame", gpuAll.wall.median, everyMs});
        std::printf("  (CPU split at %llu faces: CPU step %.3f ms + upload %.3f ms + GPU animation %.2f ms)\n",
                    (unsigned long long)faces, cpuStep, upload, anim.wall.median);
      }
    }
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
      return 1;
    }
    std::printf("  (%llu faces: scene generated and context created in %.0f ms; host clear %.2f ms, subtracted)\n",
                (unsigned long long)faces, prepMs, b.clearMs);
    if (o.faces.size() > 1 && faces == o.faces.front()) {
      smallest = std::move(bench);
    } else if (smallest && faces == o.faces.back()) {
      for (const char* layout : {"3(1-1-1)", "5(3-1-1)"}) {
        FaceRatio fr;
        fr.layout = layout;
        if (s.ok()) s = pairedStill(*smallest, b, layout, o.pairFrames, &fr.smallMs, &fr.largeMs, &fr.pairMedian);
        if (s.ok()) faceRatios.push_back(fr);
      }
      if (!s.ok()) {
        std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
        return 1;
      }
    }
  }
  std::printf("\nBaselines, same run, %llu faces, 5(3-1-1), ms (ratio = second / first):\n\n",
              (unsigned long long)o.faces.front());
  for (const Baseline& x : baselines)
    std::printf("  %-58s %-13s %8.2f   %-10s %8.2f   %6.2fx\n", x.name.c_str(), x.a.c_str(), x.aMs, x.b.c_str(), x.bMs,
                x.bMs / std::max(x.aMs, 1e-9));
  if (!faceRatios.empty()) {
    std::printf("\nStill-camera frame, %llu faces / %llu faces, the two contexts' frames alternated (%d each), ms;\n"
                "ratio of the medians, and the median of each frame's ratio to the one before it:\n\n",
                (unsigned long long)o.faces.back(), (unsigned long long)o.faces.front(), o.pairFrames);
    for (const FaceRatio& x : faceRatios)
      std::printf("  %-9s %10llu: %7.2f   %10llu: %7.2f   ratio %.3f   pairs %.3f\n", x.layout.c_str(),
                  (unsigned long long)o.faces.front(), x.smallMs, (unsigned long long)o.faces.back(), x.largeMs,
                  x.largeMs / std::max(x.smallMs, 1e-9), x.pairMedian);
  }

  std::vector<Point> series;
  if (o.series && runSeries(d, o, &series) != 0) return 1;

  if (!o.json.empty() && writeTable1Json(d, o, rows, baselines, faceRatios, series) != 0) return 1;
  return 0;
}

}  // namespace canopy::bench
