// canopy-bench shadows (issue 54; docs/design.md "Shadows"): what the vegetation's shadow costs
// beside the frame it belongs to — a shrub of 80K and of 1M faces and a forest of six species —
// the update's own GPU time (timestamps around recordCanopyShadow) and the whole frame's wall
// clock without a shadow, with an update every frame, every 2 and every 4 frames (the map's
// update interval, CanopyShadowInputs.updateInterval), the variants alternated.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <glm/gtc/matrix_transform.hpp>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "engine/device.h"
#include "engine/timing.h"
#include "engine/transfer.h"
#include "tools/scene_generator.h"

namespace canopy::bench {
namespace {

double mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? 0.0 : s / double(v.size());
}

// The sun's orthographic view around world bounds (Vulkan clip, depth 0 near the sun).
glm::mat4 sunAround(glm::vec3 lo, glm::vec3 hi) {
  const glm::vec3 l = glm::normalize(glm::vec3(0.35f, 0.8f, 0.5f)), c = 0.5f * (lo + hi);
  const float r = 0.5f * glm::length(hi - lo);
  return glm::orthoRH_ZO(-r, r, -r, r, 0.5f * r, 3.5f * r) * glm::lookAt(c + 2.0f * r * l, c, glm::vec3(0, 1, 0));
}

struct Scene {
  std::vector<VegetationModel> models;
  std::vector<SpeciesModel> species;
  std::vector<CanopyInstance> copies;
  glm::vec3 lo{INFINITY}, hi{-INFINITY};
  uint64_t faces = 0;
  std::string name;
};

Status shrubScene(uint64_t faces, Scene* s) {
  s->models.resize(1);
  SceneDesc sd;
  sd.kind = SceneKind::Shrub;
  sd.faces = faces;
  CANOPY_TRY(generateScene(sd, &s->models[0]));
  s->species = {{&s->models[0]}};
  s->lo = s->models[0].boundsMin;
  s->hi = s->models[0].boundsMax;
  s->faces = s->models[0].triangleCount();
  s->name = "shrub, " + std::to_string(s->faces) + " faces";
  return Status();
}

// Six generated species (shrubs and tree crowns of 8K faces), ten copies each on a grid.
Status forestScene(Scene* s) {
  s->models.resize(6);
  for (uint32_t k = 0; k < 6; ++k) {
    SceneDesc sd;
    sd.kind = k % 2 ? SceneKind::TreeCrown : SceneKind::Shrub;
    sd.faces = 8000;
    sd.seed = 11 + k;
    CANOPY_TRY(generateScene(sd, &s->models[k]));
    s->species.push_back({&s->models[k]});
  }
  glm::vec3 size(0.0f);
  for (const VegetationModel& m : s->models) size = glm::max(size, m.boundsMax - m.boundsMin);
  const float spacing = 1.1f * std::max(size.x, size.z);
  for (uint32_t i = 0; i < 60; ++i) {
    CanopyInstance c;
    const glm::vec3 at(spacing * float(i % 8), 0.0f, -spacing * float(i / 8));
    c.transform = toFloat4x4(glm::translate(glm::mat4(1.0f), at) * glm::rotate(glm::mat4(1.0f), float(i) * 2.4f, glm::vec3(0, 1, 0)));
    c.species = i % 6;
    s->copies.push_back(c);
    s->lo = glm::min(s->lo, at - 0.5f * size);
    s->hi = glm::max(s->hi, at + 0.5f * size);
    s->faces += s->models[i % 6].triangleCount();
  }
  s->name = "forest, six species, 60 copies, " + std::to_string(s->faces) + " faces";
  return Status();
}

struct Costs {
  double frameMs[4] = {};   // mean wall clock per frame: no shadow, every 1, 2, 4 frames
  double updateMs = 0;      // the update's own GPU time (median over the frames that drew)
  double updateWallMs = 0;  // the frame with an update minus the frame without (medians)
};

Status measure(Device& d, const Scene& sc, uint32_t w, uint32_t h, uint32_t mapSize, int frames, Costs* out) {
  CanopyDesc desc;
  desc.width = w;
  desc.height = h;
  desc.colorFormat = VK_FORMAT_R8G8B8A8_UNORM;
  desc.instances = sc.copies;
  CanopyContext* ctx = nullptr;
  CANOPY_TRY(createCanopy(d, sc.species, desc, &ctx));
  HostTargets targets;
  rg::RenderGraph graph;
  GpuTimer timer;
  Image map;
  Status s = [&]() -> Status {
    CANOPY_TRY(createHostTargets(d, w, h, VK_FORMAT_R8G8B8A8_UNORM, &targets));
    CANOPY_TRY(timer.init(d, 64));
    CANOPY_TRY(buildHostGraph(d, ctx, targets, true, rg::stateOf(rg::Use::TransferSrc), &graph));
    ImageDesc md;
    md.format = VK_FORMAT_D32_SFLOAT;
    md.width = md.height = mapSize;
    md.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
    CANOPY_TRY(createImage(d, md, &map, "bench: shadow map"));
    const LayerView view = orbitView(sc.lo, sc.hi, 20.0f, 15.0f, 40.0f, float(w) / float(h), 0.9f);
    const glm::mat4 light = sunAround(sc.lo, sc.hi);
    bool first = true;
    static uint64_t number = 0;  // the device's frame numbers never decrease, across contexts
    // interval 0: no shadow. Warm-up frames first, then the variants alternated frame by frame.
    std::vector<double> wall[4], drawn, skipped;
    const uint32_t intervals[4] = {0, 1, 2, 4};
    for (int i = -4; i < 4 * frames; ++i) {
      const int v = i < 0 ? 1 : (i / 4) % 4;  // blocks of 4 frames per variant, so every 2nd / 4th lands in its block
      const uint32_t interval = intervals[v];
      CanopyFrame f;
      f.camera = toCamera(view);
      f.dt = 1.0f / 30.0f;
      f.frameNumber = ++number;
      CANOPY_TRY(beginCanopyFrame(ctx, f));
      bool updated = false;
      const double t0 = nowMs();
      CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) -> Status {
        timer.reset(cmd);
        CANOPY_TRY(graph.record(cmd));
        if (!interval) return Status();
        CanopyShadowInputs in;
        const rg::State sampled = rg::stateOf(rg::Use::FragmentSampled);
        in.depth = canopyImage(map.image, map.view, VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT,
                               VK_FORMAT_D32_SFLOAT, first ? rg::State{} : sampled, sampled);
        first = false;
        in.width = in.height = mapSize;
        in.lightViewProj = toFloat4x4(light);
        in.cascade = v;
        in.updateInterval = interval;
        timer.begin(cmd, "shadow");
        const Status st = recordCanopyShadow(ctx, cmd, in, &updated);
        timer.end(cmd);
        return st;
      }));
      const double ms = nowMs() - t0;
      std::vector<PassTiming> t;
      CANOPY_TRY(timer.read(d, &t));
      if (i < 0) continue;
      wall[v].push_back(ms);
      if (interval == 1) {
        drawn.push_back(ms);
        for (const PassTiming& p : t)
          if (p.name == "shadow") out->updateMs += p.milliseconds / double(frames);
      }
      if (interval == 0) skipped.push_back(ms);
    }
    for (int v = 0; v < 4; ++v) out->frameMs[v] = mean(wall[v]);
    out->updateWallMs = median(drawn) - median(skipped);
    return Status();
  }();
  vkDeviceWaitIdle(d.device);
  destroyImage(d, map);
  graph.release(d);
  destroyHostTargets(d, targets);
  timer.destroy(d);
  destroyCanopy(ctx);
  return s;
}

}  // namespace

int runShadowBench(Device& d, const std::vector<uint64_t>& faceCounts, int frames, uint32_t w, uint32_t h, uint32_t mapSize) {
  std::printf("\nShadows (issue 54) at %ux%u, a %ux%u D32 shadow map from an orthographic sun: the frame (submit to fence)\n"
              "without a shadow and with an update every frame, every 2nd and every 4th (updateInterval), blocks of 4\n"
              "frames of each alternated, %d frames each, means; the update's own GPU time (timestamps around\n"
              "recordCanopyShadow, mean over the every-frame block) and the every-frame block's median minus the\n"
              "no-shadow block's.\n\n",
              w, h, mapSize, mapSize, frames);
  std::printf("  %-44s %10s %10s %10s %10s %11s %11s\n", "", "no shadow", "every 1", "every 2", "every 4", "update GPU", "update wall");
  std::vector<Scene> scenes(faceCounts.size() + 1);
  for (size_t i = 0; i <= faceCounts.size(); ++i) {
    const Status made = i < faceCounts.size() ? shrubScene(faceCounts[i], &scenes[i]) : forestScene(&scenes[i]);
    Costs c;
    const Status s = made.ok() ? measure(d, scenes[i], w, h, mapSize, frames, &c) : made;
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench shadows: %s\n", s.message().c_str());
      return 1;
    }
    std::printf("  %-44s %7.2f ms %7.2f ms %7.2f ms %7.2f ms %8.2f ms %8.2f ms\n", scenes[i].name.c_str(), c.frameMs[0], c.frameMs[1],
                c.frameMs[2], c.frameMs[3], c.updateMs, c.updateWallMs);
    scenes[i] = Scene{};
  }
  return 0;
}

}  // namespace canopy::bench
