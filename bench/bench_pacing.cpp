// canopy-bench pacing (issue 79): how evenly a moving camera's frames come, with the settings a game
// ships (CanopyParams' defaults, wind off so that the sides differ only by the method). Per path, a
// long run of the policy's frames, each timed (submit to fence) and counted (pipeline statistics
// around every pass), beside the same scene's still frame drawn alternately; and, frame by frame,
// the same path re-sliced every frame (the reference): the world-lock error (coverage IoU,
// silhouette distance) and the pop, the temporal-derivative error mean |(I_t - I_t-1) - (R_t - R_t-1)|
// at the frames that re-slice or cross-fade beside its 95th percentile over the other frames.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>

#include <glm/gtc/matrix_transform.hpp>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "demo/demo_app.h"
#include "engine/device.h"
#include "engine/pass_counters.h"
#include "engine/transfer.h"
#include "tools/scene_generator.h"
#include "tools/world_lock.h"

namespace canopy::bench {
namespace {

double quantileOf(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(std::floor(q * double(v.size() - 1) + 0.5)))];
}

// One context with its host targets and frame graph; `counted`: pipeline statistics every frame.
struct PacingSide {
  Device& d;
  CanopyContext* ctx = nullptr;
  HostTargets host;
  rg::RenderGraph graph;
  PassCounters counters;
  bool counted = false;
  uint32_t w = 0, h = 0;
  explicit PacingSide(Device& dev) : d(dev) {}
  ~PacingSide() {
    vkDeviceWaitIdle(d.device);
    graph.release(d);
    if (counted) counters.destroy(d);
    destroyHostTargets(d, host);
    destroyCanopy(ctx);
  }
  Status init(const VegetationModel& model, const demo::SceneCopies* copies, uint32_t width, uint32_t height, bool everyFrame,
              float budgetMs, bool count, uint32_t predictFrames = 0, bool paced = false) {
    w = width;
    h = height;
    CanopyDesc desc;
    desc.width = w;
    desc.height = h;
    desc.colorFormat = VK_FORMAT_R8G8B8A8_UNORM;
    desc.params.windMode = WindMode::PlaneSides;
    desc.params.simulation.wind.strength = 0.0f;
    if (everyFrame) desc.params.layers.policy = ReslicePolicy::EveryFrame;
    if (budgetMs >= 0.0f) desc.params.layers.rebuildBudgetMs = everyFrame ? 0.0f : budgetMs;
    desc.params.layers.predictFrames = predictFrames;
    if (!everyFrame) desc.params.layers.pacedReslices = paced;
    if (copies) desc.instances = copies->instances;
    CANOPY_TRY(copies ? createCanopy(d, copies->species, desc, &ctx) : createCanopy(d, model, desc, &ctx));
    CANOPY_TRY(createHostTargets(d, w, h, VK_FORMAT_R8G8B8A8_UNORM, &host));
    if (count) CANOPY_TRY(counters.init(d, 128));
    counted = count;
    return buildHostGraph(d, ctx, host, true, rg::stateOf(rg::Use::ColorAttachmentReadWrite), &graph);
  }
  // One frame: wall clock, and when asked its pixels and its counted primitives and fragments.
  Status frame(const LayerView& view, double* ms, std::vector<uint8_t>* pixels = nullptr, uint64_t* primitives = nullptr,
               uint64_t* fragments = nullptr) {
    static uint64_t number = 0;  // the device's frame numbers never decrease
    CanopyFrame f;
    f.camera = toCamera(view);
    f.dt = 1.0f / 30.0f;
    f.frameNumber = ++number;
    CANOPY_TRY(beginCanopyFrame(ctx, f));
    const double t0 = nowMs();
    CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) {
      if (counted) counters.reset(cmd);
      return graph.record(cmd, nullptr, counted ? &counters : nullptr);
    }));
    *ms = nowMs() - t0;
    if (counted && primitives && fragments) {
      std::vector<PassCounts> passes;
      CANOPY_TRY(counters.read(d, &passes));
      *primitives = *fragments = 0;
      for (const PassCounts& p : passes) {
        *primitives += p.clippingPrimitives;
        *fragments += p.fragmentInvocations;
      }
    }
    if (!pixels) return Status();
    pixels->resize(size_t(w) * h * 4);
    return readbackImage(d, host.color, 0, 4, pixels->data(), rg::stateOf(rg::Use::ColorAttachmentReadWrite));
  }
};

// mean |(a - aPrev) - (b - bPrev)| over the colour channels, 8-bit levels.
double popError(const std::vector<uint8_t>& a, const std::vector<uint8_t>& aPrev, const std::vector<uint8_t>& b,
                const std::vector<uint8_t>& bPrev) {
  double sum = 0;
  size_t n = 0;
  for (size_t i = 0; i + 3 < a.size(); i += 4)
    for (size_t c = 0; c < 3; ++c, ++n)
      sum += std::abs((int(a[i + c]) - int(aPrev[i + c])) - (int(b[i + c]) - int(bPrev[i + c])));
  return n ? sum / double(n) : 0.0;
}

// The third-person path: a character walking (1.4 m/s at 30 frames a second, times `pace`) into the
// scene from z = 2 m towards -Z and back (12 m), turning ±30 degrees over 8 s; the camera 3 m behind
// it and 2 m high, looking at its head (1.6 m). Metres are world units (the scene files' convention).
LayerView thirdPersonView(uint32_t frame, float pace, float aspect) {
  const float t = float(frame), walked = std::fabs(pingPong(t, 1.4f / 30.0f * pace, 12.0f));
  const float heading = glm::radians(30.0f * std::sin(6.2831853f * t / 240.0f));
  const glm::vec3 forward(std::sin(heading), 0.0f, -std::cos(heading));
  const glm::vec3 character = glm::vec3(0.0f, 0.0f, 2.0f) + glm::vec3(0.0f, 0.0f, -walked);
  LayerView v;
  v.view = glm::lookAtRH(character - 3.0f * forward + glm::vec3(0.0f, 2.0f, 0.0f), character + glm::vec3(0.0f, 1.6f, 0.0f), glm::vec3(0, 1, 0));
  v.proj = perspectiveVulkan(glm::radians(60.0f), aspect, 0.05f, 60.0f);
  return v;
}

struct PacingRun {
  std::string path;
  uint64_t faces = 0;
  float degreesPerFrame = 0;
  std::vector<double> ms, stillMs, primitives, fragments, silhouette, iou, popAt, popElse;
  uint32_t reslices = 0;
};

}  // namespace

int runPacingBench(Device& d, const PacingOptions& o) {
  if (!d.pipelineStatistics) {
    std::fprintf(stderr, "canopy-bench pacing: the device has no pipelineStatisticsQuery feature\n");
    return 1;
  }
  if (o.predictFrames) std::printf("\nLayerSettings.predictFrames %u on the policy side", o.predictFrames);
  std::printf("\nLayerSettings.pacedReslices %s on the policy side", o.paced ? "on" : "off");
  std::printf("\nPacing (issue 79): %ux%u, CanopyParams' defaults%s, wind off, %d frames a path; frame times wall clock\n"
              "(submit to fence, with pipeline statistics queries), the still frame drawn alternately; world lock and the pop\n"
              "against the same path re-sliced every frame.\n",
              o.width, o.height, o.budgetMs >= 0 ? (", rebuildBudgetMs " + std::to_string(int(o.budgetMs)) + " ms").c_str() : "", o.frames);
  std::printf("  %-7s %9s %5s %8s %8s %8s %8s %8s %7s %7s %8s %8s %8s %8s %8s %8s\n", "path", "faces", "deg", "med ms", "p95",
              "p99", "max", "still", "p99/med", "stutter", "reslices", "prim max", "frag max", "sil max", "IoU min", "pop/p95");
  std::vector<PacingRun> runs;
  const bool trace = std::getenv("CANOPY_BENCH_TRACE") != nullptr;  // a line per frame
  for (uint64_t faces : o.faces)
    for (const std::string& pathName : o.paths)
      for (float deg : o.degreesPerFrame) {
        PacingRun r;
        r.path = pathName;
        r.faces = faces;
        r.degreesPerFrame = deg;
        CameraPath path;
        // The six-species scene (a scene file: its own faces), walked or followed in the third person.
        const bool species = pathName == "species-walk" || pathName == "third-person", thirdPerson = pathName == "third-person";
        Status s = species ? Status() : parseCameraMotion(pathName, &path.motion);
        if (species) path.motion = CameraMotion::Walk;
        SceneDesc sd;
        sd.faces = faces;
        sd.kind = path.motion == CameraMotion::Walk ? SceneKind::Field : SceneKind::Shrub;  // a walk goes through the field
        path.degreesPerFrame = deg;
        path.radiiPerFrame = 0.005f * deg / 0.25f;  // dolly, strafe and walk at the same pace
        VegetationModel model;
        demo::SceneCopies copies;
        if (s.ok() && species) {
          demo::Options so;
          so.sceneFile = o.sceneFile;
          std::string label;
          s = demo::loadScene(so, &model, &label, &copies);
          uint64_t placed = 0;
          for (const CanopyInstance& in : copies.instances) placed += copies.models[in.species].triangleCount();
          r.faces = placed;
        } else if (s.ok()) {
          s = generateScene(sd, &model);
        }
        const demo::SceneCopies* scene = species ? &copies : nullptr;
        const float aspect = float(o.width) / float(o.height);
        auto viewAt = [&](uint32_t i) {
          return thirdPerson ? thirdPersonView(i, deg / 0.25f, aspect) : cameraPathView(path, model.boundsMin, model.boundsMax, aspect, i);
        };
        PacingSide policy(d), every(d), still(d);
        if (s.ok()) s = policy.init(model, scene, o.width, o.height, false, o.budgetMs, true, o.predictFrames, o.paced);
        if (s.ok() && o.reference) s = every.init(model, scene, o.width, o.height, true, 0.0f, false);
        if (s.ok()) s = still.init(model, scene, o.width, o.height, false, o.budgetMs, false, 0, o.paced);
        const LayerView first = viewAt(0);
        double ms = 0;
        for (int k = 0; k < 3 && s.ok(); ++k) {  // settled on the first view (the first frame slices)
          s = policy.frame(first, &ms);
          if (s.ok() && o.reference) s = every.frame(first, &ms);
          if (s.ok()) s = still.frame(first, &ms);
        }
        const uint64_t before = s.ok() ? canopyStats(policy.ctx).layers.rebuilds : 0;
        std::vector<uint8_t> a, b, aPrev, bPrev;
        for (int i = 1; i <= o.frames && s.ok(); ++i) {
          const LayerView v = viewAt(uint32_t(i));
          double ma = 0, mb = 0, m0 = 0;
          uint64_t prim = 0, frag = 0;
          if (o.reference) s = every.frame(v, &mb, &b);
          if (s.ok()) s = still.frame(first, &m0);
          if (s.ok()) s = policy.frame(v, &ma, o.reference ? &a : nullptr, &prim, &frag);
          if (!s.ok()) break;
          const CanopyStats st = canopyStats(policy.ctx);
          if (trace)
            std::printf("    frame %3d: %8.2f ms (still %6.2f) primitives %8llu fragments %9llu phase %u rebuilt %d\n", i, ma, m0,
                        (unsigned long long)prim, (unsigned long long)frag, st.layers.spreadPhase, int(st.layersRebuilt));
          r.ms.push_back(ma);
          r.stillMs.push_back(m0);
          r.primitives.push_back(double(prim));
          r.fragments.push_back(double(frag));
          if (!o.reference) continue;
          const WorldLockError e = compareFrames(a, b, o.width, o.height, kHostClearRgba8);
          r.silhouette.push_back(e.silhouetteMeanPx);
          r.iou.push_back(e.coverageIoU);
          if (!aPrev.empty()) {
            const double pop = popError(a, aPrev, b, bPrev);
            const bool changed = st.layersRebuilt || st.layers.spreadPhase == 3;  // new layers shown, or fading in
            (changed ? r.popAt : r.popElse).push_back(pop);
          }
          aPrev.swap(a);
          bPrev.swap(b);
        }
        if (!s.ok()) {
          std::fprintf(stderr, "canopy-bench pacing: %s: %s\n", pathName.c_str(), s.message().c_str());
          return 1;
        }
        r.reslices = uint32_t(canopyStats(policy.ctx).layers.rebuilds - before);
        const double med = quantileOf(r.ms, 0.5);
        uint32_t stutter = 0;
        for (double t : r.ms) stutter += t > 2.5 * med;
        const double primMed = std::max(quantileOf(r.primitives, 0.5), 1.0), fragMed = std::max(quantileOf(r.fragments, 0.5), 1.0);
        const double popAt = r.popAt.empty() ? 0.0 : *std::max_element(r.popAt.begin(), r.popAt.end());
        std::printf("  %-7s %9llu %5.2f %8.2f %8.2f %8.2f %8.2f %8.2f %7.2f %7u %8u %8.2f %8.2f %8.3f %8.4f %8.2f\n", r.path.c_str(),
                    (unsigned long long)r.faces, double(deg), med, quantileOf(r.ms, 0.95), quantileOf(r.ms, 0.99),
                    *std::max_element(r.ms.begin(), r.ms.end()), quantileOf(r.stillMs, 0.5), quantileOf(r.ms, 0.99) / med, stutter,
                    r.reslices, *std::max_element(r.primitives.begin(), r.primitives.end()) / primMed,
                    *std::max_element(r.fragments.begin(), r.fragments.end()) / fragMed,
                    r.silhouette.empty() ? 0.0 : *std::max_element(r.silhouette.begin(), r.silhouette.end()),
                    r.iou.empty() ? 1.0 : *std::min_element(r.iou.begin(), r.iou.end()),
                    popAt / std::max(quantileOf(r.popElse, 0.95), 1e-9));
        std::fflush(stdout);
        runs.push_back(std::move(r));
      }
  if (o.json.empty()) return 0;
  std::ofstream j(o.json);
  j << "{\n  \"device\": \"" << d.properties.deviceName << "\", \"size\": [" << o.width << ", " << o.height << "], \"frames\": "
    << o.frames << ",\n  \"runs\": [\n";
  for (size_t k = 0; k < runs.size(); ++k) {
    const PacingRun& r = runs[k];
    const double med = quantileOf(r.ms, 0.5);
    uint32_t stutter = 0;
    for (double t : r.ms) stutter += t > 2.5 * med;
    char line[1536];
    std::snprintf(line, sizeof line,
                  "    {\"path\": \"%s\", \"faces\": %llu, \"degrees_per_frame\": %.3f, \"median_ms\": %.3f, \"p95_ms\": %.3f, "
                  "\"p99_ms\": %.3f, \"max_ms\": %.3f, \"still_ms\": %.3f, \"stutter_frames\": %u, \"reslices\": %u, "
                  "\"primitives_max\": %.0f, \"primitives_median\": %.0f, \"fragments_max\": %.0f, \"fragments_median\": %.0f, "
                  "\"silhouette_mean_px_max\": %.4f, \"iou_min\": %.5f, \"pop_max\": %.4f, \"pop_other_p95\": %.4f}%s\n",
                  r.path.c_str(), (unsigned long long)r.faces, double(r.degreesPerFrame), med, quantileOf(r.ms, 0.95),
                  quantileOf(r.ms, 0.99), *std::max_element(r.ms.begin(), r.ms.end()), quantileOf(r.stillMs, 0.5), stutter,
                  r.reslices, *std::max_element(r.primitives.begin(), r.primitives.end()), quantileOf(r.primitives, 0.5),
                  *std::max_element(r.fragments.begin(), r.fragments.end()), quantileOf(r.fragments, 0.5),
                  r.silhouette.empty() ? 0.0 : *std::max_element(r.silhouette.begin(), r.silhouette.end()),
                  r.iou.empty() ? 1.0 : *std::min_element(r.iou.begin(), r.iou.end()),
                  r.popAt.empty() ? 0.0 : *std::max_element(r.popAt.begin(), r.popAt.end()), quantileOf(r.popElse, 0.95),
                  k + 1 < runs.size() ? "," : "");
    j << line;
  }
  j << "  ]\n}\n";
  std::printf("  written: %s\n", o.json.c_str());
  return 0;
}

}  // namespace canopy::bench
