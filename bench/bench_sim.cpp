// canopy-bench sim: milliseconds per simulation step for N = 64, 128, 256 (or --sizes), the GPU
// design (every pass a compute dispatch, per-pass GPU timestamps) next to the CPU reference of the
// same step (the paper ran its 64x64 simulation on the CPU), and Stam's scheme beside Canopy's.
// Wall clock of the submitted step is printed with the timestamps: CPU drivers' timestamps are
// not trusted alone (docs/design.md).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "compute/sim_reference.h"
#include "compute/simulation.h"
#include "engine/device.h"
#include "engine/timing.h"

namespace canopy::bench {
namespace {

// Lowest-mode gradient energy removed by one MAC projection on the device (walls, phi = cos(pi x)).
Status macLowestModeRemoval(Device& dev, uint32_t n, uint32_t cycles, double* removed) {
  Simulation sim;
  SimulationDesc desc;
  desc.gridSize = n;
  CANOPY_TRY(createSimulation(dev, desc, &sim));
  std::vector<float> vel(2 * gpu::velocityFloats(n), 0.0f);
  const double pi = 3.14159265358979323846;
  double before = 0;
  for (uint32_t j = 0; j < n; ++j)
    for (uint32_t i = 0; i <= n; ++i) {
      float u = float(-pi * std::sin(pi * double(i) / n));
      vel[gpu::macU(n, i, j)] = u;
      before += double(u) * u;
    }
  SimulationParams p;
  p.wind.sides = 0;
  p.fluid.boundary = FluidBoundary::Walls;
  p.fluid.multigridCycles = cycles;
  Status s = writeSimulationState(sim, vel, {});
  if (s.ok()) s = runProjectionOnly(sim, p);
  SimulationFields f;
  if (s.ok()) s = readSimulationFields(sim, &f);
  if (s.ok()) {
    double after = 0;
    for (size_t k = 0; k < gpu::macFloats(n); ++k) after += double(f.velocity[k]) * f.velocity[k];
    *removed = 1.0 - after / before;
  }
  destroySimulation(sim);
  return s;
}

struct Row {
  std::string label;
  double gpuTs = 0, wall = 0, cpu = 0;
  double record = 0;  // of the wall: recording the step's command buffer on the CPU
  std::vector<PassTiming> passes;
  uint32_t dispatches = 0;
  uint32_t groupSize = 0;
  uint32_t laneWidth = 0;  // the lane-blocked projection ran, one subgroup of this width (0: not)
};

Status measure(Device& dev, uint32_t n, FluidScheme scheme, uint32_t cycles, int frames, bool cpu, Row* row,
               uint32_t groupSize = 0) {
  Simulation sim;
  SimulationDesc desc;
  desc.gridSize = n;
  desc.groupSize = groupSize;
  CANOPY_TRY(createSimulation(dev, desc, &sim));
  SimulationParams p;
  p.wind.sides = kWindFromLeft;
  p.fluid.scheme = scheme;
  p.fluid.multigridCycles = cycles;
  p.motors.push_back({0.5f, 0.5f, 0.1f, 0.5f});
  const float dt = 1.0f / 30.0f;
  GpuTimer timer;
  CANOPY_TRY(timer.init(dev, 16));
  std::vector<double> ts, wall, record;
  std::vector<std::vector<double>> perPass;
  Status s;
  // Steps alternate: one with timestamp queries around every pass (per-pass figures), one without
  // (the wall clock: on lavapipe each timestamp query waits for the work before it, ~0.08 ms each).
  for (int f = 0; f < 2 * (frames + 3) && s.ok(); ++f) {
    const bool timed = (f & 1) == 0;
    double t0 = nowMs(), recordMs = 0;
    s = submitAndWait(dev, [&](VkCommandBuffer cmd) {
      const double r0 = nowMs();
      if (timed) timer.reset(cmd);
      CANOPY_TRY(prepareSimulationStep(sim, p, dt));
      Status rs = sim.graph.record(cmd, timed ? &timer : nullptr);
      recordMs = nowMs() - r0;
      return rs;
    });
    double t1 = nowMs();
    if (f < 6 || !s.ok()) continue;
    if (!timed) {
      wall.push_back(t1 - t0);
      record.push_back(recordMs);
      continue;
    }
    std::vector<PassTiming> t;
    s = timer.read(dev, &t);
    double sum = 0;
    perPass.resize(t.size());
    for (size_t i = 0; i < t.size(); ++i) {
      sum += t[i].milliseconds;
      perPass[i].push_back(t[i].milliseconds);
    }
    ts.push_back(sum);
    row->passes = t;
  }
  for (size_t i = 0; i < row->passes.size(); ++i) row->passes[i].milliseconds = median(perPass[i]);
  row->gpuTs = median(ts);
  row->wall = median(wall);
  row->record = median(record);
  row->dispatches = sim.stats.dispatchesPerStep;
  row->groupSize = sim.groupSize;
  row->laneWidth = sim.laneProjectNext ? sim.laneWidth : 0;
  timer.destroy(dev);
  destroySimulation(sim);
  CANOPY_TRY(s);
  if (cpu) {
    ref::SimState st = ref::makeState(n, 8);
    std::vector<double> c;
    double t = 0;
    const int cpuFrames = n >= 256 ? 5 : 15;
    for (int f = 0; f < cpuFrames + 2; ++f) {
      gpu::SimFrame fr;
      CANOPY_TRY(makeSimFrame(p, n, float(t), dt, uint32_t(f % 8), 8, &fr));
      double t0 = nowMs();
      ref::step(fr, st);
      double t1 = nowMs();
      t += dt;
      if (f >= 2) c.push_back(t1 - t0);
    }
    row->cpu = median(c);
  }
  return Status();
}

}  // namespace

int runSimBench(Device& dev, const std::vector<uint32_t>& sizes, int frames, bool detail) {
  std::printf("\n== Simulation step (wind + fluid + wave + tile), dt = 1/30 s, wind from the left + 1 motor ==\n");
  std::printf("GPU: per-pass timestamps summed, median of %d steps; wall: submit-to-fence of one step alone, median\n"
              "of %d other steps recorded without timestamp queries (each query waits for the work before it).\n",
              frames, frames);
  std::printf("CPU: the reference implementation of the same step, one core, median.\n\n");
  std::printf("Quality: energy of the lowest gradient mode removed by one projection (walls; MAC measured\n"
              "on the device, Stam's scheme by its CPU reference with the same red-black sweeps).\n\n");
  std::printf("  %-5s %-26s %10s %10s %10s %11s %9s %9s\n", "N", "scheme", "GPU ts ms", "wall ms", "CPU ms", "dispatches",
              "CPU/wall", "removed");
  {
    // The floor under every wall figure: submit-to-fence of a command buffer that only resets the
    // timer queries (the same submitAndWait path as a step).
    GpuTimer timer;
    if (timer.init(dev, 16).ok()) {
      std::vector<double> wall;
      for (int f = 0; f < frames + 3; ++f) {
        const double t0 = nowMs();
        if (!submitAndWait(dev, [&](VkCommandBuffer cmd) { timer.reset(cmd); return Status(); }).ok()) break;
        if (f >= 3) wall.push_back(nowMs() - t0);
      }
      // And the same with 10 compute-to-compute memory barriers: what each pass boundary costs on
      // this driver before any work.
      std::vector<double> wallBarriers;
      for (int f = 0; f < frames + 3; ++f) {
        const double t0 = nowMs();
        Status bs = submitAndWait(dev, [&](VkCommandBuffer cmd) {
          timer.reset(cmd);
          VkMemoryBarrier2 mb{VK_STRUCTURE_TYPE_MEMORY_BARRIER_2};
          mb.srcStageMask = mb.dstStageMask = VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT;
          mb.srcAccessMask = VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT;
          mb.dstAccessMask = VK_ACCESS_2_SHADER_STORAGE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_WRITE_BIT;
          VkDependencyInfo di{VK_STRUCTURE_TYPE_DEPENDENCY_INFO};
          di.memoryBarrierCount = 1;
          di.pMemoryBarriers = &mb;
          for (int b = 0; b < 10; ++b) dev.cmdPipelineBarrier2(cmd, &di);
          return Status();
        });
        if (!bs.ok()) break;
        if (f >= 3) wallBarriers.push_back(nowMs() - t0);
      }
      timer.destroy(dev);
      if (!wall.empty() && !wallBarriers.empty())
        std::printf("  (floor: an empty submit-to-fence costs %.3f ms wall, with 10 barriers %.3f ms; medians)\n",
                    median(wall), median(wallBarriers));
    }
  }
  for (uint32_t n : sizes) {
    struct Variant { const char* name; FluidScheme scheme; uint32_t cycles; };
    const Variant variants[] = {{"MAC + multigrid (2 V)", FluidScheme::MacMultigrid, 2},
                                {"MAC + multigrid (1 V)", FluidScheme::MacMultigrid, 1},
                                {"Stam collocated, 20 RB-GS", FluidScheme::Stam, 20}};
    for (const Variant& v : variants) {
      Row r;
      Status s = measure(dev, n, v.scheme, v.cycles, frames, true, &r);
      if (!s.ok()) {
        std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
        return 1;
      }
      double removed = 0;
      if (v.scheme == FluidScheme::Stam) removed = ref::stamLowestModeRemoval(n, v.cycles, ref::GsOrder::RedBlack);
      else if (!(s = macLowestModeRemoval(dev, n, v.cycles, &removed)).ok()) {
        std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
        return 1;
      }
      std::printf("  %-5u %-26s %10.3f %10.3f %10.3f %11u %8.2fx %8.2f%%\n", n, v.name, r.gpuTs, r.wall, r.cpu, r.dispatches,
                  r.cpu / std::max(r.wall, 1e-9), 100 * removed);
      if (detail) std::printf("        %-32s %8.3f ms (of the wall)\n", "recording on the CPU", r.record);
      if (detail)
        for (const PassTiming& t : r.passes)
          if (t.milliseconds > 0.0005) std::printf("        %-32s %8.3f ms\n", t.name.c_str(), t.milliseconds);
    }
  }
  // The single-workgroup kernels' width side by side (SimulationDesc.groupSize) against the default
  // chosen by device class: on CPU devices the lane-blocked kernels (one subgroup, fields in
  // registers: shaders/sim_fluid_project_lanes.comp), which a forced groupSize turns off.
  std::printf("\nWorkgroup width of the single-workgroup kernels, MAC + multigrid (2 V), wall ms (median);\n"
              "default: chosen by device class (lanes W: the lane-blocked kernels, one subgroup of W):\n\n  %-5s", "N");
  const uint32_t widths[] = {32, 64, 128, 256, 1024};
  for (uint32_t w : widths) std::printf(" %9u", w);
  std::printf("   default\n");
  for (uint32_t n : sizes) {
    std::printf("  %-5u", n);
    for (uint32_t w : widths) {
      Row r;
      Status s = w <= dev.properties.limits.maxComputeWorkGroupInvocations
                     ? measure(dev, n, FluidScheme::MacMultigrid, 2, frames, false, &r, w)
                     : Status::error("too wide");
      if (s.ok()) std::printf(" %9.3f", r.wall);
      else std::printf(" %9s", "-");
    }
    Row r;
    Status s = measure(dev, n, FluidScheme::MacMultigrid, 2, frames, false, &r);
    if (!s.ok()) std::printf("   -\n");
    else if (r.laneWidth) std::printf("   %.3f (lanes %u)\n", r.wall, r.laneWidth);
    else std::printf("   %.3f (group %u)\n", r.wall, r.groupSize);
  }
  return 0;
}

}  // namespace canopy::bench
