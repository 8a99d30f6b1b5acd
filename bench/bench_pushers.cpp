// canopy-bench pushers (issue 55; docs/design.md "Pushers"): what 32 pushers cost against none
// on the field scene — 32 capsules walking circles through it, each a motor of the fluid and a
// source of the bend field — the frame's wall clock (submit to fence) and the GPU time of the
// passes they touch (the projections' sources, the tile pass's bend field, the dynamics' lookup),
// the two variants alternated frame by frame, medians.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "compute/simulation.h"
#include "engine/device.h"
#include "engine/timing.h"
#include "engine/transfer.h"
#include "tools/scene_generator.h"

namespace canopy::bench {
namespace {

// 32 capsules (a character's height, a twentieth of the field's width thick) walking circles of
// different radii and phases through the field at walking pace.
std::vector<CanopyPusher> walkers(const VegetationModel& m, uint32_t count, float t) {
  const glm::vec3 c = 0.5f * (m.boundsMin + m.boundsMax), ext = m.boundsMax - m.boundsMin;
  const float extent = std::max(ext.x, ext.z), R = extent / 40.0f;
  std::vector<CanopyPusher> out(count);
  for (uint32_t i = 0; i < count; ++i) {
    const float orbit = extent * (0.1f + 0.35f * float(i) / float(count)), speed = extent / 8.0f;
    const float a = float(i) * 0.7f + t * speed / orbit;
    const glm::vec3 p(c.x + orbit * std::cos(a), m.boundsMin.y + R, c.z + orbit * std::sin(a));
    out[i].a = toFloat3(p);
    out[i].b = toFloat3(p + glm::vec3(0.0f, 3.0f * R, 0.0f));
    out[i].radius = R;
    out[i].velocity = toFloat3(speed * glm::vec3(-std::sin(a), 0.0f, std::cos(a)));
  }
  return out;
}

}  // namespace

int runPusherBench(Device& d, uint64_t faces, int frames, uint32_t w, uint32_t h) {
  VegetationModel m;
  SceneDesc sd;
  sd.kind = SceneKind::Field;
  sd.faces = faces;
  Status s = generateScene(sd, &m);
  CanopyContext* ctx = nullptr;
  HostTargets targets;
  rg::RenderGraph graph;
  GpuTimer timer;
  std::vector<double> wall[2];
  std::map<std::string, std::vector<double>> passes[2];
  CanopyStats stats;
  if (s.ok()) {
    CanopyDesc desc;
    desc.width = w;
    desc.height = h;
    desc.colorFormat = VK_FORMAT_R8G8B8A8_UNORM;
    s = createCanopy(d, m, desc, &ctx);
  }
  if (s.ok()) s = createHostTargets(d, w, h, VK_FORMAT_R8G8B8A8_UNORM, &targets);
  if (s.ok()) s = timer.init(d, 128);
  if (s.ok()) s = buildHostGraph(d, ctx, targets, true, rg::stateOf(rg::Use::TransferSrc), &graph);
  if (s.ok()) {
    const LayerView view = orbitView(m.boundsMin, m.boundsMax, 0.0f, 22.0f, 40.0f, float(w) / float(h), 0.8f);
    uint64_t number = 0;
    for (int i = -6; s.ok() && i < 2 * frames; ++i) {
      const int v = i < 0 ? 1 : i % 2;  // 0: none, 1: 32 pushers; alternated
      s = setCanopyPushers(ctx, v ? walkers(m, kMaxPushers, float(i + 6) / 30.0f) : std::vector<CanopyPusher>{});
      CanopyFrame f;
      f.camera = toCamera(view);
      f.dt = 1.0f / 30.0f;
      f.frameNumber = ++number;
      if (s.ok()) s = beginCanopyFrame(ctx, f);
      const double t0 = nowMs();
      if (s.ok()) s = submitAndWait(d, [&](VkCommandBuffer cmd) {
        timer.reset(cmd);
        return graph.record(cmd, &timer);
      });
      const double ms = nowMs() - t0;
      std::vector<PassTiming> t;
      if (s.ok()) s = timer.read(d, &t);
      if (v == 1) stats = canopyStats(ctx);
      if (i < 0 || !s.ok()) continue;
      wall[v].push_back(ms);
      std::map<std::string, double> sum;
      for (const PassTiming& p : t) sum[p.name] += p.milliseconds;
      for (const auto& [name, msPass] : sum) passes[v][name].push_back(msPass);
    }
  }
  vkDeviceWaitIdle(d.device);
  graph.release(d);
  destroyHostTargets(d, targets);
  timer.destroy(d);
  if (ctx) destroyCanopy(ctx);
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-bench pushers: %s\n", s.message().c_str());
    return 1;
  }
  std::printf("\nPushers (issue 55) at %ux%u, the field scene (%llu faces), still camera: no pusher against %u capsules\n"
              "walking circles through it (%u mapped in the last frame), %d frames of each alternated, medians; the\n"
              "passes' GPU times from timestamps (on lavapipe they read near zero for compute after a draw:\n"
              "docs/design.md), the simulation alone by wall clock over 200 steps.\n\n",
              w, h, static_cast<unsigned long long>(m.triangleCount()), kMaxPushers, stats.pushersMapped, frames);
  // The simulation alone (runSimulationSteps, the same steps without the layers): the motors'
  // sources in both projections and the bend field in the tile pass, by wall clock (lavapipe's
  // timestamps read near zero for compute after a draw: docs/design.md).
  double simMs[2] = {};
  {
    Simulation sim;
    SimulationDesc sdesc;
    Status ss = createSimulation(d, sdesc, &sim);
    SimulationParams sp;
    std::vector<gpu::SimMotor> motors(kMaxPushers);
    for (uint32_t i = 0; i < kMaxPushers; ++i) {
      const float x = 0.1f + 0.8f * float(i) / float(kMaxPushers), y = 0.5f + 0.3f * std::sin(float(i));
      motors[i].segment = glm::vec4(x, y, x, y + 0.05f);
      motors[i].flow = glm::vec4(0.03f, 0.0f, 0.05f, 0.0f);
      motors[i].bend = glm::vec4(0.5f, 0.03f, 1.0f, 0.1f);
      motors[i].ground = glm::vec4(2.0f * x, 2.0f * y, 2.0f * x, 2.0f * y + 0.05f);
    }
    for (int rep = 0; ss.ok() && rep < 3; ++rep)
      for (int v = 0; ss.ok() && v < 2; ++v) {
        sim.pushers = v ? motors : std::vector<gpu::SimMotor>{};
        const double t0 = nowMs();
        ss = runSimulationSteps(sim, sp, 1.0f / 30.0f, 100);
        if (rep > 0) simMs[v] += (nowMs() - t0) / 200.0;  // two timed repetitions of 100 steps
      }
    destroySimulation(sim);
    if (!ss.ok()) std::fprintf(stderr, "canopy-bench pushers: the simulation alone: %s\n", ss.message().c_str());
  }
  std::printf("  %-36s %12s %12s %10s\n", "", "none", "32 pushers", "added");
  std::printf("  %-36s %9.3f ms %9.3f ms %7.3f ms\n", "simulation step alone (wall, mean)", simMs[0], simMs[1], simMs[1] - simMs[0]);
  std::printf("  %-36s %9.3f ms %9.3f ms %7.3f ms\n", "frame (submit to fence)", median(wall[0]), median(wall[1]),
              median(wall[1]) - median(wall[0]));
  for (const char* name : {"sim: project", "sim: project again", "sim: tile + history", "dynamics: displacement"}) {
    if (!passes[0].count(name) || !passes[1].count(name)) continue;
    const double a = median(passes[0][name]), b = median(passes[1][name]);
    std::printf("  %-36s %9.3f ms %9.3f ms %7.3f ms\n", (std::string(name) + " (GPU)").c_str(), a, b, b - a);
  }
  return 0;
}

}  // namespace canopy::bench
