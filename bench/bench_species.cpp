// canopy-bench species (issue 53; docs/design.md "Species"): six species in one vegetation against
// one species at equal placed faces (the same copies, each of the six models or all of one), for the
// still frame, a reprojected frame (a slowly orbiting camera between re-slices) and a re-slice at
// once; the mesh's memory against the number of copies; the first frame after recordCanopyLoad
// against the first frame without it and the median frame.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include <glm/gtc/matrix_transform.hpp>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "engine/device.h"
#include "engine/timing.h"
#include "engine/transfer.h"
#include "tools/scene_generator.h"

namespace canopy::bench {
namespace {


// A context on `species` with `copies`, its host targets and frame graph.
struct SpeciesRun {
  Device& d;
  CanopyContext* ctx = nullptr;
  HostTargets targets;
  rg::RenderGraph graph;
  GpuTimer timer;
  explicit SpeciesRun(Device& device) : d(device) {}
  ~SpeciesRun() {
    if (ctx) {
      vkDeviceWaitIdle(d.device);
      destroyCanopy(ctx);
      graph.release(d);
      destroyHostTargets(d, targets);
    }
  }
  Status init(const std::vector<SpeciesModel>& species, const std::vector<CanopyInstance>& copies, uint32_t w, uint32_t h,
              const LayerSettings& layers, bool impostors = false) {
    CanopyDesc desc;
    desc.impostors.enable = impostors;
    desc.width = w;
    desc.height = h;
    desc.colorFormat = VK_FORMAT_R8G8B8A8_UNORM;
    desc.instances = copies;
    desc.params.layers = layers;
    CANOPY_TRY(createCanopy(d, species, desc, &ctx));
    CANOPY_TRY(createHostTargets(d, w, h, VK_FORMAT_R8G8B8A8_UNORM, &targets));
    CANOPY_TRY(timer.init(d, 64));
    return buildHostGraph(d, ctx, targets, true, rg::stateOf(rg::Use::TransferSrc), &graph);
  }
  // One frame at `view`, submit to fence, ms; `passes`: with timestamps, the passes' GPU ms.
  // `recordMs`: of it, the CPU's recording of the command buffer.
  Status frame(const LayerView& view, double* ms, std::vector<PassTiming>* passes = nullptr, double* recordMs = nullptr) {
    CanopyFrame f;
    f.camera = toCamera(view);
    f.dt = 1.0f / 30.0f;
    CANOPY_TRY(beginCanopyFrame(ctx, f));
    const double t0 = nowMs();
    CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) {
      if (passes) timer.reset(cmd);
      const double r0 = nowMs();
      Status st = graph.record(cmd, passes ? &timer : nullptr);
      if (recordMs) *recordMs = nowMs() - r0;
      return st;
    }));
    *ms = nowMs() - t0;
    return passes ? timer.read(d, passes) : Status();
  }
};

struct Kinds {
  std::vector<VegetationModel> models;
  std::vector<SpeciesModel> six, same;
  std::vector<std::vector<SpeciesModel>> alone;  // each of the six models as the only species
  std::vector<CanopyInstance> copies;
  glm::vec3 lo{INFINITY}, hi{-INFINITY};
  uint64_t sixFaces = 0, oneFaces = 0;
};

// Six generated species of about `faces` faces each (shrubs and trees, different seeds), `perSpecies`
// copies each on a grid; the one-species variant places its first model at every copy.
Status makeKinds(uint64_t faces, uint32_t perSpecies, Kinds* k) {
  k->models.resize(6);
  for (uint32_t s = 0; s < 6; ++s) {
    SceneDesc sd;
    sd.kind = s % 2 ? SceneKind::TreeCrown : SceneKind::Shrub;
    sd.faces = faces;
    sd.seed = 11 + s;
    SceneStats st;
    CANOPY_TRY(generateScene(sd, &k->models[s], &st));
  }
  glm::vec3 size(0.0f);
  for (const VegetationModel& m : k->models) size = glm::max(size, m.boundsMax - m.boundsMin);
  const float spacing = 1.1f * std::max(size.x, size.z);
  const uint32_t total = 6 * perSpecies, side = uint32_t(std::ceil(std::sqrt(double(total))));
  for (uint32_t i = 0; i < total; ++i) {
    CanopyInstance c;
    const glm::vec3 at(spacing * float(i % side), 0.0f, -spacing * float(i / side));
    c.transform = toFloat4x4(glm::translate(glm::mat4(1.0f), at) * glm::rotate(glm::mat4(1.0f), float(i) * 2.4f, glm::vec3(0, 1, 0)));
    c.species = i % 6;
    k->copies.push_back(c);
    k->lo = glm::min(k->lo, at - 0.5f * size);
    k->hi = glm::max(k->hi, at + 0.5f * size);
    k->sixFaces += k->models[i % 6].triangleCount();
    k->oneFaces += k->models[0].triangleCount();
  }
  for (uint32_t s = 0; s < 6; ++s) k->six.push_back({&k->models[s], 0.6f + 0.2f * float(s), 1.0f});
  for (uint32_t s = 0; s < 6; ++s) k->same.push_back({&k->models[0], 0.6f + 0.2f * float(s), 1.0f});
  for (uint32_t s = 0; s < 6; ++s) k->alone.push_back({{&k->models[s]}});
  return Status();
}

struct Costs {
  double still = 0, reprojected = 0, reslice = 0;
};

// The layers' settings: with impostors, far copies switch by projected size (the defaults).
LayerSettings layersFor(bool impostors) {
  LayerSettings s;
  if (impostors) s.impostors.mode = ImpostorMode::ByProjectedSize;
  return s;
}

Status measure(Device& d, const std::vector<SpeciesModel>& species, const std::vector<CanopyInstance>& copies, const Kinds& k,
               uint32_t w, uint32_t h, int frames, Costs* out, uint64_t* meshBytes, bool impostors = false,
               uint32_t* impostorCopies = nullptr) {
  const LayerView still = orbitView(k.lo, k.hi, 20.0f, 25.0f, 40.0f, float(w) / float(h), 0.8f);
  std::vector<double> ms;
  {
    SpeciesRun r(d);
    CANOPY_TRY(r.init(species, copies, w, h, layersFor(impostors), impostors));
    double t = 0;
    for (int i = 0; i < frames + 2; ++i) {
      CANOPY_TRY(r.frame(still, &t));
      if (i >= 2) ms.push_back(t);
    }
    out->still = median(ms);
    if (impostorCopies) *impostorCopies = canopyStats(r.ctx).layers.lastImpostorCopies;
    *meshBytes = canopyStats(r.ctx).layers.meshBytes;
    // Reprojected: a slow orbit whose error never asks for a re-slice (threshold at its maximum).
    CanopyParams p = canopyParams(r.ctx);
    p.layers.errorThresholdPixels = 1000.0f;
    p.layers.turnThresholdDegrees = 180.0f;
    CANOPY_TRY(setCanopyParams(r.ctx, p));
    CANOPY_TRY(r.frame(still, &t));  // the settings' re-slice
    ms.clear();
    for (int i = 0; i < frames; ++i) {
      CANOPY_TRY(r.frame(orbitView(k.lo, k.hi, 20.0f + 0.05f * float(i + 1), 25.0f, 40.0f, float(w) / float(h), 0.8f), &t));
      ms.push_back(t);
    }
    out->reprojected = median(ms);
  }
  LayerSettings every = layersFor(impostors);
  every.policy = ReslicePolicy::EveryFrame;
  SpeciesRun r(d);
  CANOPY_TRY(r.init(species, copies, w, h, every, impostors));
  ms.clear();
  double t = 0;
  for (int i = 0; i < frames + 1; ++i) {
    CANOPY_TRY(r.frame(still, &t));
    if (i >= 1) ms.push_back(t);
  }
  out->reslice = median(ms);
  return Status();
}

}  // namespace

int runSpeciesBench(Device& d, uint64_t faces, uint32_t perSpecies, int frames, uint32_t w, uint32_t h) {
  Kinds k;
  Status s = makeKinds(faces, perSpecies, &k);
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-bench species: %s\n", s.message().c_str());
    return 1;
  }
  std::printf("\nSpecies (issue 53) at %ux%u: %zu copies on a grid, each copy of one of six species (flexibility 0.6..1.6) or\n"
              "all of one species; the six are six generated models (shrubs and trees of about %llu faces) or the first model six\n"
              "times (the same pixels: only the species mechanism differs); one species is each of the six models alone at\n"
              "every copy, the six costs averaged (equal faces, the same content on average). Wall clock per frame (submit to\n"
              "fence), medians of %d frames; the variants alternated twice, the two medians averaged.\n\n",
              w, h, k.copies.size(), (unsigned long long)faces, frames);
  Costs six[2], same[2], one[2], forest[2];
  uint64_t sixBytes = 0, sameBytes = 0, oneBytes = 0, forestBytes = 0;
  uint32_t impostorCopies = 0;
  std::vector<CanopyInstance> allFirst = k.copies;
  for (CanopyInstance& c : allFirst) c.species = 0;
  for (int rep = 0; rep < 2 && s.ok(); ++rep) {
    s = measure(d, k.six, k.copies, k, w, h, frames, &six[rep], &sixBytes);
    if (s.ok()) s = measure(d, k.same, k.copies, k, w, h, frames, &same[rep], &sameBytes);
    // One species: each of the six models alone at every copy (the same faces and, on average, the
    // same content as the six together), the six costs averaged.
    for (uint32_t m = 0; m < 6 && s.ok(); ++m) {
      Costs c;
      uint64_t bytes = 0;
      s = measure(d, k.alone[m], allFirst, k, w, h, frames, &c, &bytes);
      one[rep].still += c.still / 6.0;
      one[rep].reprojected += c.reprojected / 6.0;
      one[rep].reslice += c.reslice / 6.0;
      if (rep == 0) oneBytes += bytes / 6;
    }
    if (s.ok()) s = measure(d, k.six, k.copies, k, w, h, frames, &forest[rep], &forestBytes, true, &impostorCopies);
  }
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-bench species: %s\n", s.message().c_str());
    return 1;
  }
  auto avg = [](const Costs c[2], double Costs::*f) { return 0.5 * (c[0].*f + c[1].*f); };
  std::printf("  %-34s %11s %11s %11s %10s %10s\n", "", "six models", "one model", "one species", "six/one", "same/one");
  std::printf("  %-34s %11s %11s %11s %10s %10s\n", "", "as species", "6 species", "(mean of 6)", "", "");
  std::printf("  %-34s %11llu %11llu %11llu %10.3f %10.3f\n", "faces placed", (unsigned long long)k.sixFaces,
              (unsigned long long)k.oneFaces, (unsigned long long)k.sixFaces, 1.0, double(k.oneFaces) / double(k.sixFaces));
  std::printf("  %-34s %11.2f %11.2f %11.2f %10.3f %10.3f\n", "mesh stored, MiB", double(sixBytes) / 1048576.0,
              double(sameBytes) / 1048576.0, double(oneBytes) / 1048576.0, double(sixBytes) / double(oneBytes),
              double(sameBytes) / double(oneBytes));
  for (const auto& [name, f] : {std::pair<const char*, double Costs::*>{"still frame, ms", &Costs::still},
                                {"reprojected frame, ms", &Costs::reprojected},
                                {"re-slice at once (every frame), ms", &Costs::reslice}})
    std::printf("  %-34s %11.2f %11.2f %11.2f %10.3f %10.3f\n", name, avg(six, f), avg(same, f), avg(one, f),
                avg(six, f) / avg(one, f), avg(same, f) / avg(one, f));
  // The same forest with far copies as impostors of their species (ImpostorMode::ByProjectedSize).
  std::printf("\n  six species, impostors (by projected size; %u copies as impostors in the still view):\n", impostorCopies);
  std::printf("  %-34s %11s %11s %10s\n", "", "without", "with", "with/without");
  for (const auto& [name, f] : {std::pair<const char*, double Costs::*>{"still frame, ms", &Costs::still},
                                {"reprojected frame, ms", &Costs::reprojected},
                                {"re-slice at once (every frame), ms", &Costs::reslice}})
    std::printf("  %-34s %11.2f %11.2f %10.3f\n", name, avg(six, f), avg(forest, f), avg(forest, f) / avg(six, f));
  // The mesh's memory against the number of copies: one species, 1 .. 1000 copies.
  std::printf("\n  copies of one species   mesh bytes   instance table bytes\n");
  for (uint32_t n : {1u, 10u, 100u, 1000u}) {
    std::vector<CanopyInstance> many;
    for (uint32_t i = 0; i < n; ++i) {
      CanopyInstance c;
      c.transform = toFloat4x4(glm::translate(glm::mat4(1.0f), glm::vec3(3.0f * float(i % 32), 0.0f, -3.0f * float(i / 32))));
      many.push_back(c);
    }
    SpeciesRun r(d);
    s = r.init(k.alone[0], many, 64, 48, LayerSettings{});
    if (!s.ok()) break;
    std::printf("  %20u %12llu %22zu\n", n, (unsigned long long)canopyStats(r.ctx).layers.meshBytes,
                size_t(n) * sizeof(gpu::LayerInstance));
  }
  // Loading without a hitch: the first frame with and without recordCanopyLoad, against the median.
  const LayerView view = orbitView(k.lo, k.hi, 20.0f, 25.0f, 40.0f, float(w) / float(h), 0.8f);
  double firstCold = 0, firstLoaded = 0, loadMs = 0, t = 0, firstColdRecord = 0, firstLoadedRecord = 0, record = 0;
  std::vector<double> rest, restRecord;
  for (int loaded = 0; loaded < 2 && s.ok(); ++loaded) {
    SpeciesRun r(d);
    s = r.init(k.six, k.copies, w, h, LayerSettings{});
    if (!s.ok()) break;
    {
      // The host's own targets touched first (its clear alone): their first use is the host's, not Canopy's.
      rg::RenderGraph clearOnly;
      s = buildHostGraph(d, r.ctx, r.targets, false, rg::stateOf(rg::Use::TransferSrc), &clearOnly);
      if (s.ok()) s = submitAndWait(d, [&](VkCommandBuffer cmd) { return clearOnly.record(cmd); });
      clearOnly.release(d);
      if (!s.ok()) break;
    }
    if (loaded) {
      const double t0 = nowMs();
      s = submitAndWait(d, [&](VkCommandBuffer cmd) { return recordCanopyLoad(r.ctx, cmd, toCamera(view)); });
      loadMs = nowMs() - t0;
      if (!s.ok()) break;
    }
    s = r.frame(view, loaded ? &firstLoaded : &firstCold, nullptr, loaded ? &firstLoadedRecord : &firstColdRecord);
    for (int i = 0; i < frames && s.ok() && loaded; ++i) {
      s = r.frame(view, &t, nullptr, &record);
      rest.push_back(t);
      restRecord.push_back(record);
    }
  }
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-bench species: %s\n", s.message().c_str());
    return 1;
  }
  const double med = median(rest), medRecord = median(restRecord);
  std::printf("\n  six species, first frame of play (submit to fence; of it the CPU's recording of the host's graph):\n"
              "    median frame                   %8.2f ms (recording %.2f ms)\n"
              "    first, without recordCanopyLoad %8.2f ms (recording %.2f ms): %.2f x the median\n"
              "    first, after recordCanopyLoad   %8.2f ms (recording %.2f ms): %.2f x the median; %.2f x without the graph's\n"
              "                                   first recording (the host's CPU, not Canopy's GPU work); the load took %.2f ms\n",
              med, medRecord, firstCold, firstColdRecord, firstCold / med, firstLoaded, firstLoadedRecord, firstLoaded / med,
              (firstLoaded - firstLoadedRecord + medRecord) / med, loadMs);
  return 0;
}

}  // namespace canopy::bench
