#include "compute/simulation.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include "engine/device.h"
#include "engine/pass_slots.h"
#include "engine/transfer.h"

namespace canopy {
namespace {

std::string fmt(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

Status checkPositive(const char* name, double v, double hi, const char* unit) {
  if (std::isfinite(v) && v > 0 && v <= hi) return Status();
  return Status::error(std::string(name) + " = " + fmt(v) + ": must be a finite number in (0, " + fmt(hi) + "] (" + unit + ")");
}

const rg::State kPersistent = rg::stateOf(rg::Use::ComputeStorageReadWrite);
const rg::State kFrameRest = rg::stateOf(rg::Use::ComputeStorageRead);
const rg::State kReadbackRest = rg::stateOf(rg::Use::HostRead);

// Every simulation kernel binds the same seven buffers (shaders/sim_common.glsl), in this order.
// A pass's slots name what its kernels read and write (`uses`); the others are bound untouched. A
// buffer that is not a resource of the graph (kInvalidResource in `r`) is bound outside it.
rg::Slots simSlots(const Simulation& s, const SimulationResources& r,
                   std::initializer_list<std::pair<rg::ResourceId, rg::Use>> uses) {
  const std::pair<rg::ResourceId, const Buffer*> all[] = {{r.frame, &s.frame}, {r.velocity, &s.velocity},
                                                          {r.multigrid, &s.multigrid}, {r.wave, &s.wave},
                                                          {r.tiled, &s.tiled}, {r.ring, &s.ring},
                                                          {r.ringTimes, &s.ringTimes}};
  rg::Slots slots;
  for (const auto& [id, buffer] : all) {
    rg::Slot x = id == rg::kInvalidResource ? rg::outsideGraph(bindBuffer(buffer->buffer)) : rg::untouched(id);
    for (const auto& [used, use] : uses)
      if (used == id && id != rg::kInvalidResource) x = rg::slot(id, use);
    slots.push_back(x);
  }
  return slots;
}

Status simDispatch(rg::PassContext& c, const rg::Slots& slots, const ComputePipeline& p, uint32_t tx, uint32_t ty,
                   uint32_t phase) {
  const gpu::SimPush push{phase, 0, 0, 0};
  return rg::dispatchSlots(c, p, slots, tx, ty, 1, push);
}

}  // namespace

rg::State windImageRest() {
  // Any shader stage of the host may sample it after recordCanopy (docs/embedding.md "The wind and pushers").
  return {VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT,
          VK_ACCESS_2_SHADER_SAMPLED_READ_BIT, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
}

const WindSlot* completedWindSlot(const Simulation& s, uint64_t completedFrame, uint32_t* index) {
  const WindSlot* best = nullptr;
  for (size_t i = 0; i < s.windSlots.size(); ++i) {
    const WindSlot& w = s.windSlots[i];
    if (w.valid && w.frame <= completedFrame && (!best || w.frame > best->frame || (w.frame == best->frame && w.time > best->time))) {
      best = &w;
      if (index) *index = uint32_t(i);
    }
  }
  return best;
}

Status validateSimulationDesc(const SimulationDesc& d) {
  // SIM_MAX_GROUP_SIZE is the schema's groupSize bound (<canopy/canopy.h>, CANOPY_SIMULATION_DESC).
  static_assert(SIM_MAX_GROUP_SIZE == 1024u, "CANOPY_SIMULATION_DESC's groupSize range");
  return checkParams(d, "SimulationDesc.");
}

Status validateSimulationParams(const SimulationParams& p, float dt) {
  static_assert(SIM_MAX_MOTORS == kMaxMotors + kMaxPushers, "the host's motors and the pushers share SimFrame.motors");
  CANOPY_TRY(checkPositive("dt", dt, 10, "s"));
  return checkParams(p, "SimulationParams.");
}

float maxStableWaveDt(const WaveParams& w, uint32_t n) {
  // Damped position Verlet V+ = (2 - zeta dt) V - (1 - zeta dt) V- - dt^2 omega^2 V is stable for
  // omega^2 dt^2 + 2 zeta dt <= 4; the stiffest mode has omega^2 = k + 8 c^2 / h^2 (2D Laplacian).
  // With a 0.9 safety factor on dt: omega^2 dt^2 + 2 zeta dt <= 3.24.
  const double om2 = double(w.stiffness) + 8.0 * double(w.speed) * w.speed * double(n) * n;
  const double z = w.damping;
  if (om2 <= 0.0) return z > 0 ? float(1.62 / z) : 1e9f;
  return float((-z + std::sqrt(z * z + 3.24 * om2)) / om2);
}

double estimateLoopTrips(const gpu::SimFrame& f) {
  // Upper bound of the loop iterations one invocation of each single-workgroup kernel runs (the
  // serial multigrid tail runs in invocation 0). Mirrors the loops of shaders/sim_*.comp.
  if (f.n < 4 || f.n > 1024 || f.mgLevels < 1 || f.mgLevels > 11 || f.groupSize < 1) return 1e300;  // not a valid frame
  const double G = f.groupSize, n = f.n, hn = n / 2;
  auto par = [G](double count) { return std::ceil(count / G); };
  const double reduce = std::log2(G) + 2;
  const double diffuse = par(4 * n) + par(gpu::macFloats(f.n)) + f.diffuseSweeps * 2.0 * (par(n * hn + (n - 1) * hn) + 1);
  double cycle = 0;
  uint32_t parLevels = 0;
  while (parLevels + 1 < f.mgLevels && (f.n >> parLevels) > f.mgSerialSize) ++parLevels;
  for (uint32_t l = 0; l + 1 < f.mgLevels; ++l) {
    const double m = f.n >> l, mc = m / 2;
    if (l < parLevels)
      cycle += (SIM_MG_PRE_SWEEPS + SIM_MG_POST_SWEEPS) * 2.0 * (par(m * m / 2) + 1) + par(mc * mc) + par(m * m) +
               2 * par(mc * mc) + reduce;
    else
      cycle += (SIM_MG_PRE_SWEEPS + SIM_MG_POST_SWEEPS) * 2.0 * (m * m + 1) + 3 * mc * mc + m * m + 4;
  }
  const double mL = f.n >> (f.mgLevels - 1);
  cycle += SIM_MG_COARSE_SWEEPS * 2.0 * (mL * mL + 1) + f.mgLevels * 2;
  const double project = par(4 * n) + 3 * par(n * n) + 2 * reduce + f.mgCycles * (cycle + 1) + 2 * par(n * n) + par(n);
  const double solve = 2 * (par(n * hn) + 1) + 2 * par(n) + 2;
  const double stam = par((n + 2) * (n + 2)) + 4 * f.iterations * solve + 2 * (par(n * n) + 2 * par(n) + 2) +
                      2 * (3 * par(n * n) + reduce + 4 * par(n) + 2 * f.iterations * solve / 4);
  const double wave = 2 * par(n * n) + f.waveSubsteps * (par(n * n) + 1);
  const double fluid = f.scheme == SIM_SCHEME_STAM ? stam : std::max(diffuse, project);
  return std::max(fluid, wave);
}

namespace {
// The lane-blocked projection's register levels: at least `lanes` wide (never the coarsest).
uint32_t laneRegisterLevels(uint32_t n, uint32_t mgLevels, uint32_t lanes) {
  uint32_t par = 0;
  while (par + 1 < mgLevels && (n >> par) >= lanes) ++par;
  return par;
}
}  // namespace

double estimateLaneProjectTrips(const gpu::SimFrame& f, uint32_t lanes) {
  if (f.n < 4 || f.n > 1024 || f.mgLevels < 1 || f.mgLevels > 11 || lanes < 1) return 1e300;
  // Mirrors the loops of shaders/sim_fluid_project_lanes.comp: boundary, right-hand side, load,
  // per V-cycle the register levels (sweeps, restriction, mean, prolongation: segment loops over the
  // rows) and the tail (every lane), then the gradient; both pure-Neumann means counted.
  const double n = f.n, W = lanes, sweeps = SIM_MG_PRE_SWEEPS + SIM_MG_POST_SWEEPS;
  const uint32_t par = laneRegisterLevels(f.n, f.mgLevels, lanes);
  double cycle = 0;
  for (uint32_t l = 0; l + 1 < f.mgLevels; ++l) {
    const double m = f.n >> l, mc = m / 2, segs = std::max(1.0, m / W);
    // Restriction: into registers a loop over coarse segments and rows; into the tail a loop over
    // fine segments and rows with W/2 broadcasts each.
    const double restriction = l + 1 < par ? (mc / W) * (mc + 2) : segs * (mc + 1) + segs * mc * (W / 2);
    if (l < par)
      cycle += sweeps * 2.0 * segs * (m + 1) + restriction + 2 * mc * mc / W + segs * (m + 1) + 2 * segs;
    else
      cycle += sweeps * 2.0 * (m * m + 1) + 3 * mc * mc + m * m + 4;
  }
  const double mL = f.n >> (f.mgLevels - 1), mP = f.n >> par;
  cycle += SIM_MG_COARSE_SWEEPS * 2.0 * (mL * mL + 1) + f.mgLevels * 2 + 2 * mP * mP;
  const double segs = std::max(1.0, n / W);
  // Velocity loaded into registers and stored back: two segment loops over u and v rows, column n twice.
  const double velocity = 2 * segs * (2 * n + 1) + 2 * n;
  return std::ceil(4 * n / W) + 3 * segs * (n + 1) + 4 * n * n / W + std::log2(W) + 2 + velocity + f.mgCycles * (cycle + 1);
}

double estimateLaneDiffuseTrips(const gpu::SimFrame& f, uint32_t lanes) {
  if (f.n < 4 || f.n > 1024 || lanes < 1) return 1e300;
  // Sources and boundary over 4n faces (twice), loads, the Jacobi sweep, the red-black sweeps and
  // the stores, each a segment loop over the rows of u and v.
  const double n = f.n, W = lanes, segs = std::max(1.0, n / W), rows = segs * (2 * n + 3);
  return 2 * std::ceil(4 * n / W) + 3 * rows + 2 * n + f.diffuseSweeps * 2.0 * rows;
}

double estimateLaneOscillatorTrips(const gpu::SimFrame& f, uint32_t lanes) {
  if (f.n < 4 || f.n > 1024 || lanes < 1) return 1e300;
  const double n = f.n, segs = std::max(1.0, n / lanes);  // load, substeps, store: segment loops over n rows
  return (2.0 + f.waveSubsteps) * segs * (n + 1) + f.waveSubsteps;
}

namespace {
// The projection kernel for the step `f` describes and its thread count: the lane-blocked one where it
// was created and its loops fit lavapipe's budget, else the workgroup kernel at the step's width.
const ComputePipeline& projectionKernel(const Simulation& s, const gpu::SimFrame& f, uint32_t* threads) {
  if (s.laneWidth != 0 && estimateLaneProjectTrips(f, s.laneWidth) <= kMaxLoopTrips) {
    *threads = s.laneWidth;
    return s.laneProject;
  }
  *threads = f.groupSize;
  return s.wideGroupSize != 0 && f.groupSize == s.wideGroupSize ? s.wideProject : s.project;
}
}  // namespace

Status makeSimFrame(const SimulationParams& p, uint32_t n, float time, float dt, uint32_t ringSlot, uint32_t ringSize,
                    gpu::SimFrame* out, const std::vector<gpu::SimMotor>& pushers) {
  if (p.motors.size() > kMaxMotors || pushers.size() > kMaxPushers)
    return Status::error("makeSimFrame: " + std::to_string(p.motors.size()) + " motors and " + std::to_string(pushers.size()) +
                         " pushers (at most " + std::to_string(kMaxMotors) + " and " + std::to_string(kMaxPushers) + ")");
  // The parameters were checked when they were given (validateSimulationParams; setCanopyParams),
  // not every frame; the step's dt is this frame's.
  CANOPY_TRY(checkPositive("dt", dt, 10, "s"));
  gpu::SimFrame f{};
  f.n = n;
  f.scheme = uint32_t(p.fluid.scheme);
  f.boundary = uint32_t(p.fluid.boundary);
  f.windSides = p.wind.sides;
  f.dt = dt;
  f.time = time;
  f.viscosity = p.fluid.viscosity;
  // Implicit diffusion: one Jacobi sweep (contraction rho = 4a/(1+4a)), then red-black
  // Gauss-Seidel sweeps (rho^2 each) until the error is 1e-3 of the diffusion correction (itself
  // O(a) of the field); capped by `iterations`.
  const double a = double(dt) * p.fluid.viscosity * double(n) * n;
  const double rho = 4 * a / (1 + 4 * a);
  if (rho <= 1e-3) f.diffuseSweeps = 0;
  else {
    const double need = std::ceil(std::log(1e-3 / rho) / std::log(rho * rho));
    f.diffuseSweeps = uint32_t(std::clamp(need, 0.0, double(p.fluid.iterations)));
  }
  f.iterations = p.fluid.iterations;
  f.mgCycles = p.fluid.multigridCycles;
  f.mgLevels = gpu::mgLevelCount(n);
  f.mgSerialSize = 8;  // prepareSimulationStep applies the simulation's own settings (createSimulation)
  f.groupSize = SIM_MAX_GROUP_SIZE;
  f.motorCount = uint32_t(p.motors.size() + pushers.size());
  f.strength = p.wind.strength;
  f.frequency = p.wind.frequency;
  f.baseline = p.wind.baseline;
  f.modulation = p.wind.modulation;
  f.gust = p.wind.gust;
  f.gustScale = p.wind.gustScale;
  f.gustSpeed = p.wind.gustSpeed;
  f.seed = p.wind.seed;
  f.waveK = p.wave.stiffness;
  f.waveC = p.wave.speed;
  f.waveZeta = p.wave.damping;
  f.waveGain = p.wave.gain;
  const float maxDt = maxStableWaveDt(p.wave, n);
  const double sub = std::ceil(double(dt) / maxDt);
  if (sub > p.wave.maxSubsteps) {
    f.waveSubsteps = p.wave.maxSubsteps;
    f.waveDt = maxDt;  // clamped: the oscillator advances maxSubsteps * maxDt < dt (reported in stats)
  } else {
    f.waveSubsteps = uint32_t(std::max(1.0, sub));
    f.waveDt = dt / float(f.waveSubsteps);
  }
  f.ringSlot = ringSlot;
  f.ringSize = ringSize;
  for (size_t i = 0; i < p.motors.size(); ++i) {
    const Motor& m = p.motors[i];
    f.motors[i] = {glm::vec4(m.x, m.y, m.x, m.y), glm::vec4(m.radius, m.strength, 0.0f, 0.0f), glm::vec4(0.0f)};
  }
  for (size_t i = 0; i < pushers.size(); ++i) f.motors[p.motors.size() + i] = pushers[i];
  f.bendK = p.push.stiffness;
  f.bendZeta = p.push.damping;
  CANOPY_TRY(checkLoopBudget(f));
  *out = f;
  return Status();
}

Status checkLoopBudget(const gpu::SimFrame& f) {
  // lavapipe (llvmpipe) silently ends a shader loop after 65535 iterations per invocation, which
  // would truncate a solve without any error; refuse configurations that could get near it.
  const double trips = estimateLoopTrips(f);
  if (trips <= kMaxLoopTrips) return Status();
  std::ostringstream o;
  o << "gridSize " << f.n << " with fluid.iterations = " << f.iterations << ", fluid.multigridCycles = " << f.mgCycles
    << ", " << f.diffuseSweeps << " diffusion sweeps and " << f.waveSubsteps << " wave substeps needs ~" << uint64_t(trips)
    << " loop iterations per shader invocation; at most " << uint64_t(kMaxLoopTrips)
    << " are allowed (lavapipe silently stops longer loops): lower fluid.iterations, fluid.multigridCycles, "
       "fluid.viscosity, wave.maxSubsteps or the grid size";
  return Status::error(o.str());
}

Status createSimulation(Device& d, const SimulationDesc& desc, Simulation* out, PreparedList* deferred) {
  CANOPY_TRY(validateSimulationDesc(desc));
  Simulation& s = *out;
  s.device = &d;
  s.n = desc.gridSize;
  s.nominalDt = desc.nominalDt;
  s.ringSize = desc.historySize ? desc.historySize
                                : uint32_t(std::ceil(desc.historySeconds / desc.nominalDt)) + 2;
  s.ringSize = std::max<uint32_t>(s.ringSize, 2);
  // Multigrid levels at most 8 cells a side run in one invocation without barriers: there a
  // barrier costs more than the work. Larger serial levels were measured on lavapipe (4, 8, 32):
  // no gain beyond noise, since one invocation uses one SIMD lane of eight; on GPUs serial work is
  // slower still.
  s.mgSerialSize = 8;
  // Single-workgroup width (SimulationDesc.groupSize): lavapipe runs one workgroup on one core in
  // 8-lane steps, so a wide group only adds lanes to every barrier; measured with `canopy-bench sim
  // --groups` (docs/performance.md): 64 is fastest there. GPUs take the widest group the device allows.
  if (desc.groupSize) s.groupSize = desc.groupSize;
  else if (cpuClass(d)) s.groupSize = 64;
  else s.groupSize = std::min<uint32_t>(SIM_MAX_GROUP_SIZE, d.properties.limits.maxComputeWorkGroupInvocations);
  if (s.groupSize > d.properties.limits.maxComputeWorkGroupInvocations || s.groupSize > d.properties.limits.maxComputeWorkGroupSize[0])
    return Status::error(Result::UnsupportedDevice, "simulation groupSize = " + std::to_string(s.groupSize) +
                         " exceeds the device's workgroup limit of " +
                         std::to_string(d.properties.limits.maxComputeWorkGroupInvocations));
  const uint32_t n = s.n;
  const VkBufferUsageFlags use =
      VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  const VkDeviceSize F = sizeof(float);
  CANOPY_TRY(createBuffer(d, sizeof(gpu::SimFrame), use, MemoryUsage::DeviceLocal, &s.frame, "sim frame"));
  CANOPY_TRY(createBuffer(d, 2 * gpu::velocityFloats(n) * F, use, MemoryUsage::DeviceLocal, &s.velocity, "sim velocity"));
  CANOPY_TRY(createBuffer(d, gpu::mgFloats(n, gpu::mgLevelCount(n)) * F, use, MemoryUsage::DeviceLocal, &s.multigrid, "sim multigrid"));
  CANOPY_TRY(createBuffer(d, 6ull * n * n * F, use, MemoryUsage::DeviceLocal, &s.wave, "sim wave"));
  CANOPY_TRY(createBuffer(d, 2ull * gpu::tiledVec2s(n) * F, use, MemoryUsage::DeviceLocal, &s.tiled, "sim tiled"));
  CANOPY_TRY(createBuffer(d, uint64_t(s.ringSize) * 2 * n * n * F, use, MemoryUsage::DeviceLocal, &s.ring, "sim history ring"));
  CANOPY_TRY(createBuffer(d, s.ringSize * F, use, MemoryUsage::DeviceLocal, &s.ringTimes, "sim ring times"));
  ImageDesc wind;
  wind.format = kWindImageFormat;
  wind.width = wind.height = n;
  wind.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, wind, &s.windImage, "sim wind image"));
  // The host frame F reads the copy of frame F - framesInFlight while F's is written: one more slot.
  s.windSlots.assign(d.framesInFlight + 1, WindSlot{});
  CANOPY_TRY(createBuffer(d, s.windSlots.size() * 2ull * n * n * F, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUsage::Readback,
                          &s.windReadback, "sim wind readback"));

  const uint32_t push = sizeof(gpu::SimPush);
  const ComputePipelineDesc one{nullptr, push, {s.groupSize}, true}, grid{nullptr, push};
  auto make = [&](const char* shader, const ComputePipelineDesc& base, ComputePipeline* p) {
    ComputePipelineDesc pd = base;
    pd.shader = shader;
    return createComputePipeline(d, pd, p);
  };
  CANOPY_TRY(make("sim_fluid_diffuse.comp", one, &s.diffuse));
  CANOPY_TRY(make("sim_fluid_project.comp", one, &s.project));
  CANOPY_TRY(make("sim_fluid_advect.comp", grid, &s.advect));
  CANOPY_TRY(make("sim_stam_step.comp", one, &s.stam));
  CANOPY_TRY(make("sim_wave.comp", one, &s.oscillator));
  CANOPY_TRY(make("sim_tile.comp", grid, &s.tile));
  // CPU devices: diffusion, projection and oscillator as one subgroup with the fields in registers
  // (shaders/sim_fluid_project_lanes.comp says why). Register levels are the multigrid levels at
  // least W wide; the narrower ones (the tail, at most 8 a side) fit its fixed private copy for W <= 16,
  // and W >= 8 keeps the coarsest level (at most 4 wide) in the tail.
  const uint32_t W = d.subgroupSize;
  if (!desc.groupSize && cpuClass(d) && d.computeSubgroupShuffle &&
      (W == 8 || W == 16) && n >= W && n <= 128) {
    uint32_t floats = 0;  // register floats per lane of each kernel (see the shaders)
    for (uint32_t l = 0; l < laneRegisterLevels(n, gpu::mgLevelCount(n), W); ++l) floats += (n >> l) * (n >> l) / W;
    const uint32_t laneVelocityFloats = (n / W) * n + (n / W) * (n + 1) + n;  // u, v, u column n (one field)
    const uint32_t diffuseFloats = 2 * (n / W) * n + 2 * (n / W) * (n + 1) + n;
    s.laneWidth = W;
    CANOPY_TRY(make("sim_fluid_project_lanes.comp", ComputePipelineDesc{nullptr, push, {W, floats, laneVelocityFloats}, true},
                    &s.laneProject));
    CANOPY_TRY(make("sim_fluid_diffuse_lanes.comp", ComputePipelineDesc{nullptr, push, {W, diffuseFloats}, true}, &s.laneDiffuse));
    CANOPY_TRY(make("sim_wave_lanes.comp", ComputePipelineDesc{nullptr, push, {W, 3 * (n / W) * n}, true}, &s.laneOscillator));
  }
  const uint32_t widest = std::min<uint32_t>({SIM_MAX_GROUP_SIZE, d.properties.limits.maxComputeWorkGroupInvocations,
                                              d.properties.limits.maxComputeWorkGroupSize[0]});
  if (s.groupSize < widest) {
    s.wideGroupSize = uint32_t(1) << (31 - __builtin_clz(widest));  // a power of two for the reductions
    const ComputePipelineDesc wide{nullptr, push, {s.wideGroupSize}, true};
    CANOPY_TRY(make("sim_fluid_diffuse.comp", wide, &s.wideDiffuse));
    CANOPY_TRY(make("sim_fluid_project.comp", wide, &s.wideProject));
    CANOPY_TRY(make("sim_stam_step.comp", wide, &s.wideStam));
    CANOPY_TRY(make("sim_wave.comp", wide, &s.wideOscillator));
  }

  // Zero all state once (a one-pass graph: the fills' barriers come from the graph too).
  PreparedWork work;
  work.graph = std::make_shared<rg::RenderGraph>();
  rg::RenderGraph& g = *work.graph;
  Buffer* bufs[] = {&s.frame, &s.velocity, &s.multigrid, &s.wave, &s.tiled, &s.ring, &s.ringTimes};
  std::vector<rg::ResourceId> ids;
  for (Buffer* x : bufs) ids.push_back(g.importBuffer("sim state", x->size, {}, x == &s.frame ? kFrameRest : kPersistent));
  auto pass = g.addPass("sim: clear", [ids](rg::PassContext& c) {
    for (rg::ResourceId id : ids) c.device->vk.CmdFillBuffer(c.cmd, c.buffer(id), 0, VK_WHOLE_SIZE, 0);
    return Status();
  });
  for (size_t i = 0; i < ids.size(); ++i) {
    pass.write(ids[i], rg::Use::TransferDst);
    CANOPY_TRY(g.bindBuffer(ids[i], bufs[i]->buffer));
  }
  const rg::ResourceId windImage = g.importImage("sim wind image", descOf(s.windImage), {}, windImageRest());
  CANOPY_TRY(g.bindImage(windImage, s.windImage));
  g.addPass("sim: clear wind image", [windImage](rg::PassContext& c) {
     const VkClearColorValue zero{};
     const VkImageSubresourceRange all{VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, 1};
     c.device->vk.CmdClearColorImage(c.cmd, c.image(windImage).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &zero, 1, &all);
     return Status();
   }).write(windImage, rg::Use::TransferDst);
  CANOPY_TRY(submitOrDefer(d, std::move(work), deferred));  // the host's first frame records it on its device

  CANOPY_TRY(addSimulationPasses(s, s.graph, &s.graphIds));
  CANOPY_TRY(s.graph.compile());
  CANOPY_TRY(s.graph.realize(d));
  s.graphReady = true;
  return Status();
}

void destroySimulation(Simulation& s) {
  if (!s.device) return;
  Device& d = *s.device;  // the caller made sure no frame in flight uses it (destroyCanopy defers)
  s.graph.release(d);
  for (ComputePipeline* p : {&s.diffuse, &s.project, &s.advect, &s.stam, &s.oscillator, &s.tile, &s.wideDiffuse, &s.wideProject,
                             &s.wideStam, &s.wideOscillator, &s.laneProject, &s.laneDiffuse,
                             &s.laneOscillator})
    destroyComputePipeline(d, *p);
  for (Buffer* b : {&s.frame, &s.velocity, &s.multigrid, &s.wave, &s.tiled, &s.ring, &s.ringTimes, &s.windReadback}) destroyBuffer(d, *b);
  destroyImage(d, s.windImage);
  s.device = nullptr;
}

Status addSimulationPasses(Simulation& s, rg::RenderGraph& g, SimulationResources* out, const bool* hold) {
  if (!hold) hold = &s.paused;
  SimulationResources r;
  r.frame = g.importBuffer("sim frame", s.frame.size, kFrameRest, kFrameRest);
  r.velocity = g.importBuffer("sim velocity", s.velocity.size, kPersistent, kPersistent);
  r.multigrid = g.importBuffer("sim multigrid", s.multigrid.size, kPersistent, kPersistent);
  r.wave = g.importBuffer("sim wave", s.wave.size, kPersistent, kPersistent);
  r.tiled = g.importBuffer("sim tiled", s.tiled.size, kPersistent, kPersistent);
  r.ring = g.importBuffer("sim history ring", s.ring.size, kPersistent, kPersistent);
  r.ringTimes = g.importBuffer("sim ring times", s.ringTimes.size, kPersistent, kPersistent);
  CANOPY_TRY(g.bindBuffer(r.frame, s.frame.buffer));
  CANOPY_TRY(g.bindBuffer(r.velocity, s.velocity.buffer));
  CANOPY_TRY(g.bindBuffer(r.multigrid, s.multigrid.buffer));
  CANOPY_TRY(g.bindBuffer(r.wave, s.wave.buffer));
  CANOPY_TRY(g.bindBuffer(r.tiled, s.tiled.buffer));
  CANOPY_TRY(g.bindBuffer(r.ring, s.ring.buffer));
  CANOPY_TRY(g.bindBuffer(r.ringTimes, s.ringTimes.buffer));
  r.windImage = g.importImage("sim wind image", descOf(s.windImage), windImageRest(), windImageRest());
  CANOPY_TRY(g.bindImage(r.windImage, s.windImage));
  r.windReadback = g.importBuffer("sim wind readback", s.windReadback.size, kReadbackRest, kReadbackRest);
  CANOPY_TRY(g.bindBuffer(r.windReadback, s.windReadback.buffer));
  Simulation* sp = &s;
  auto mac = [sp] { return sp->next.scheme == SIM_SCHEME_MAC_MULTIGRID; };
  // Which passes run this frame is the graph's to know (when): none while held, the MAC passes or
  // Stam's step by the scheme of this step; a pass left out records neither work nor barriers.
  auto stepping = [hold] { return !*hold; };
  auto stepMac = [hold, mac] { return !*hold && mac(); };
  auto stepStam = [hold, mac] { return !*hold && !mac(); };
  // Single-workgroup kernels: the width prepareSimulationStep chose for this step.
  auto wide = [sp] { return sp->wideGroupSize != 0 && sp->next.groupSize == sp->wideGroupSize; };
  auto one = [sp] { return sp->next.groupSize; };
  auto project = [sp](rg::PassContext& c, const rg::Slots& slots, uint32_t phase) {
    uint32_t threads = 0;
    const ComputePipeline& kernel = projectionKernel(*sp, sp->next, &threads);
    return simDispatch(c, slots, kernel, threads, 1, phase);
  };
  using rg::Use;
  const Use read = Use::ComputeStorageRead, readWrite = Use::ComputeStorageReadWrite, write = Use::ComputeStorageWrite;
  const rg::Slots velocityStep = simSlots(s, r, {{r.frame, read}, {r.velocity, readWrite}});
  const rg::Slots projection = simSlots(s, r, {{r.frame, read}, {r.velocity, readWrite}, {r.multigrid, readWrite}});
  g.addPass("sim: upload step parameters", [sp](rg::PassContext& c) {
     c.device->vk.CmdUpdateBuffer(c.cmd, sp->frame.buffer, 0, sizeof(gpu::SimFrame), &sp->next);
     return Status();
   })
      .write(r.frame, rg::Use::TransferDst)
      .when(stepping);
  rg::addSlotPass(g, "sim: sources + diffuse", velocityStep, [=](rg::PassContext& c, const rg::Slots& slots) {
    if (sp->laneDiffuseNext) return simDispatch(c, slots, sp->laneDiffuse, sp->laneWidth, 1, 0);
    return simDispatch(c, slots, wide() ? sp->wideDiffuse : sp->diffuse, one(), 1, 0);
  }).when(stepMac);
  rg::addSlotPass(g, "sim: project", projection, [=](rg::PassContext& c, const rg::Slots& slots) {
    return project(c, slots, 0);
  }).when(stepMac);
  rg::addSlotPass(g, "sim: advect", velocityStep, [=](rg::PassContext& c, const rg::Slots& slots) {
    return simDispatch(c, slots, sp->advect, sp->n + 1, sp->n + 1, 0);
  }).when(stepMac);
  rg::addSlotPass(g, "sim: project again", projection, [=](rg::PassContext& c, const rg::Slots& slots) {
    return project(c, slots, 1);
  }).when(stepMac);
  rg::addSlotPass(g, "sim: stam velocity step", velocityStep, [=](rg::PassContext& c, const rg::Slots& slots) {
    return simDispatch(c, slots, wide() ? sp->wideStam : sp->stam, one(), 1, 0);
  }).when(stepStam);
  rg::addSlotPass(g, "sim: wave oscillator", simSlots(s, r, {{r.frame, read}, {r.velocity, read}, {r.wave, readWrite}}),
                  [=](rg::PassContext& c, const rg::Slots& slots) {
                    if (sp->laneOscillatorNext) return simDispatch(c, slots, sp->laneOscillator, sp->laneWidth, 1, 0);
                    return simDispatch(c, slots, wide() ? sp->wideOscillator : sp->oscillator, one(), 1, 0);
                  })
      .when(stepping);
  rg::addSlotPass(g, "sim: tile + history",
                  simSlots(s, r, {{r.frame, read}, {r.wave, read}, {r.tiled, readWrite}, {r.ring, write}, {r.ringTimes, write}}),
                  [=](rg::PassContext& c, const rg::Slots& slots) {
                    return simDispatch(c, slots, sp->tile, SIM_BEND_SCALE * sp->n, SIM_BEND_SCALE * sp->n, 0);
                  })
      .when(stepping);
  // The wind a host reads: the tiled V_wind into the image any of its shaders may sample, and into
  // this step's readback slot for sampleCanopyWind.
  const VkDeviceSize windBytes = 2ull * s.n * s.n * sizeof(float), windOffset = 2ull * gpu::tiledWindOffset(s.n) * sizeof(float);
  g.addPass("sim: wind image", [sp, r, windOffset](rg::PassContext& c) {
     VkBufferImageCopy copy{};
     copy.bufferOffset = windOffset;
     copy.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 0, 1};
     copy.imageExtent = {sp->n, sp->n, 1};
     c.device->vk.CmdCopyBufferToImage(c.cmd, c.buffer(r.tiled), c.image(r.windImage).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                                       1, &copy);
     return Status();
   })
      .read(r.tiled, Use::TransferSrc)
      .write(r.windImage, Use::TransferDst)
      .when(stepping);
  g.addPass("sim: wind readback", [sp, r, windOffset, windBytes](rg::PassContext& c) {
     const VkBufferCopy copy{windOffset, sp->windSlotNext * windBytes, windBytes};
     c.device->vk.CmdCopyBuffer(c.cmd, c.buffer(r.tiled), c.buffer(r.windReadback), 1, &copy);
     return Status();
   })
      .read(r.tiled, Use::TransferSrc)
      .write(r.windReadback, Use::TransferDst)
      .when(stepping);
  *out = r;
  return Status();
}

Status chooseGroupSize(const Simulation& s, gpu::SimFrame* f) {
  f->groupSize = s.groupSize;
  Status fits = checkLoopBudget(*f);
  if (fits.ok() || s.wideGroupSize == 0) return fits;
  f->groupSize = s.wideGroupSize;
  return checkLoopBudget(*f);
}

Status prepareSimulationStep(Simulation& s, const SimulationParams& p, float dt) {
  const uint32_t slot = uint32_t(s.stats.steps % s.ringSize);
  gpu::SimFrame f;
  CANOPY_TRY(makeSimFrame(p, s.n, float(s.time), dt, slot, s.ringSize, &f, s.pushers));
  f.mgSerialSize = s.mgSerialSize;
  CANOPY_TRY(chooseGroupSize(s, &f));
  s.next = f;
  uint32_t projectThreads = 0;
  s.laneProjectNext = &projectionKernel(s, f, &projectThreads) == &s.laneProject;
  s.laneDiffuseNext = s.laneWidth != 0 && estimateLaneDiffuseTrips(f, s.laneWidth) <= kMaxLoopTrips;
  s.laneOscillatorNext = s.laneWidth != 0 && estimateLaneOscillatorTrips(f, s.laneWidth) <= kMaxLoopTrips;
  for (const gpu::SimMotor& m : s.pushers) s.bendUsed = s.bendUsed || m.bend.x != 0.0f;
  // This step's readback slot (the caller names its host frame and plane: WindSlot).
  s.windSlotNext = uint32_t(s.stats.steps % s.windSlots.size());
  s.time += dt;
  s.windSlots[s.windSlotNext] = {true, s.stats.steps + 1, s.time, SimulationPlane{}};
  s.stats.steps++;
  s.stats.lastWaveSubsteps = s.next.waveSubsteps;
  s.stats.lastDiffuseSweeps = s.next.diffuseSweeps;
  s.stats.dispatchesPerStep = s.next.scheme == SIM_SCHEME_STAM ? 3 : 6;
  s.stats.clampedSeconds += std::max(0.0, double(dt) - double(s.next.waveSubsteps) * s.next.waveDt);
  return Status();
}

Status runSimulationSteps(Simulation& s, const SimulationParams& p, float dt, uint32_t count) {
  CANOPY_TRY(validateSimulationParams(p, dt));  // this call is where these parameters are given
  gpu::SimFrame probe;  // every check, before anything is recorded
  CANOPY_TRY(makeSimFrame(p, s.n, float(s.time), dt, 0, s.ringSize, &probe));
  probe.mgSerialSize = s.mgSerialSize;
  CANOPY_TRY(chooseGroupSize(s, &probe));
  if (!s.graphReady) return Status::error("runSimulationSteps: simulation not created");
  while (count > 0) {
    const uint32_t batch = std::min<uint32_t>(count, 256);
    CANOPY_TRY(submitAndWait(*s.device, [&](VkCommandBuffer cmd) {
      for (uint32_t i = 0; i < batch; ++i) {
        CANOPY_TRY(prepareSimulationStep(s, p, dt));
        CANOPY_TRY(s.graph.record(cmd));
      }
      return Status();
    }));
    count -= batch;
  }
  return Status();
}

Status runProjectionOnly(Simulation& s, const SimulationParams& p) {
  gpu::SimFrame f;
  CANOPY_TRY(makeSimFrame(p, s.n, float(s.time), 1.0f / 30.0f, 0, s.ringSize, &f));
  f.scheme = SIM_SCHEME_MAC_MULTIGRID;
  f.mgSerialSize = s.mgSerialSize;
  CANOPY_TRY(chooseGroupSize(s, &f));
  rg::RenderGraph g;
  auto frame = g.importBuffer("sim frame", s.frame.size, kFrameRest, kFrameRest);
  auto vel = g.importBuffer("sim velocity", s.velocity.size, kPersistent, kPersistent);
  auto mg = g.importBuffer("sim multigrid", s.multigrid.size, kPersistent, kPersistent);
  Simulation* sp = &s;
  g.addPass("sim: upload", [&](rg::PassContext& c) {
     c.device->vk.CmdUpdateBuffer(c.cmd, c.buffer(frame), 0, sizeof f, &f);
     c.device->vk.CmdFillBuffer(c.cmd, c.buffer(mg), 0, VK_WHOLE_SIZE, 0);
     return Status();
   })
      .write(frame, rg::Use::TransferDst)
      .write(mg, rg::Use::TransferDst);
  SimulationResources ids{frame, vel, mg, rg::kInvalidResource, rg::kInvalidResource, rg::kInvalidResource,
                          rg::kInvalidResource};
  rg::addSlotPass(g, "sim: project",
                  simSlots(s, ids, {{frame, rg::Use::ComputeStorageRead}, {vel, rg::Use::ComputeStorageReadWrite},
                                    {mg, rg::Use::ComputeStorageReadWrite}}),
                  [sp, &f](rg::PassContext& c, const rg::Slots& slots) {
                    uint32_t threads = 0;
                    const ComputePipeline& kernel = projectionKernel(*sp, f, &threads);
                    return simDispatch(c, slots, kernel, threads, 1, 0);
                  });
  CANOPY_TRY(g.bindBuffer(frame, s.frame.buffer));
  CANOPY_TRY(g.bindBuffer(vel, s.velocity.buffer));
  CANOPY_TRY(g.bindBuffer(mg, s.multigrid.buffer));
  CANOPY_TRY(g.compile());
  CANOPY_TRY(g.realize(*s.device));
  return submitAndWait(*s.device, [&](VkCommandBuffer cmd) { return g.record(cmd); });
}

Status readSimulationFields(Simulation& s, SimulationFields* out) {
  Device& d = *s.device;
  const uint32_t n = s.n, nn = n * n;
  out->n = n;
  auto read = [&](const Buffer& b, std::vector<float>& v) {
    v.resize(b.size / sizeof(float));
    return readbackBuffer(d, b, v.data(), b.size, kPersistent);
  };
  CANOPY_TRY(read(s.velocity, out->velocity));
  std::vector<float> wave;
  CANOPY_TRY(read(s.wave, wave));
  out->vs.assign(wave.begin(), wave.begin() + 2 * nn);
  out->vsPrev.assign(wave.begin() + 2 * nn, wave.begin() + 4 * nn);
  out->wind.assign(wave.begin() + 4 * nn, wave.end());
  CANOPY_TRY(read(s.tiled, out->tiled));
  CANOPY_TRY(read(s.ring, out->ring));
  CANOPY_TRY(read(s.ringTimes, out->ringTimes));
  CANOPY_TRY(read(s.multigrid, out->multigrid));
  return Status();
}

Status writeSimulationState(Simulation& s, const std::vector<float>& velocity, const std::vector<float>& wave) {
  Device& d = *s.device;
  if (!velocity.empty()) {
    if (velocity.size() * sizeof(float) != s.velocity.size)
      return Status::error("writeSimulationState: velocity needs " + std::to_string(s.velocity.size / 4) + " floats");
    CANOPY_TRY(uploadBuffer(d, nullptr, s.velocity, velocity.data(), s.velocity.size, kPersistent));
  }
  if (!wave.empty()) {
    if (wave.size() * sizeof(float) != s.wave.size)
      return Status::error("writeSimulationState: wave needs " + std::to_string(s.wave.size / 4) + " floats");
    CANOPY_TRY(uploadBuffer(d, nullptr, s.wave, wave.data(), s.wave.size, kPersistent));
  }
  return Status();
}

}  // namespace canopy
