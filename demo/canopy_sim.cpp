// canopy-sim: runs the wind + wave simulation on the GPU and writes its fields for inspection:
// wind.npy / vs.npy / tiled.npy (float32, shape [N, N, 2], row 0 at the bottom, x then y) and a
// PNG of each (hue = direction, brightness = magnitude). `canopy-sim --help` lists the options.
#include <sys/stat.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <string>

#include "compute/simulation.h"
#include "engine/device.h"
#include "tools/own_device.h"
#include "tools/image_io.h"
#include "demo/cli.h"

using namespace canopy;
using cli::parseFloat;
using cli::parseUint;

namespace {

int usage(const std::string& why) {
  if (!why.empty()) {
    std::fprintf(stderr, "canopy-sim: %s (see --help)\n", why.c_str());
    return 2;
  }
  std::printf(
      "usage: canopy-sim [options]\n"
      "  --out DIR              output folder (default sim_out)\n"
      "  --steps K              steps to run, 1..1000000 (default 90)\n"
      "  --dt DT                step, s, (0, 10] (default 0.0333)\n"
      "  --size N               grid, power of two in [4, 1024] (default 64)\n"
      "  --wind SIDES           left,right,top,bottom combined with commas, or none (default left)\n"
      "  --strength S           inflow speed, domain units/s, [0, 1000] (default 0.5)\n"
      "  --frequency F          temporal modulation, Hz, [0, 1000] (default 0.25)\n"
      "  --gust G               relative gust amplitude, [0, 1] (default 0.3)\n"
      "  --viscosity V          domain units^2/s, [0, 10] (default 1e-4)\n"
      "  --scheme mac|stam      fluid scheme (default mac: staggered grid + multigrid)\n"
      "  --boundary tunnel|walls  MAC boundary (default tunnel)\n"
      "  --iterations I         relaxation sweeps, [1, 10000] (default 20)\n"
      "  --cycles C             multigrid V-cycles per projection, [1, 64] (default 2)\n"
      "  --motor X,Y,R,S        point motor (domain units; S: outward speed at the rim), repeatable, at most 8\n"
      "  --stiffness K          oscillator k, 1/s^2 (default 40)\n"
      "  --wave-speed C         oscillator c, domain units/s (default 0.5)\n"
      "  --damping Z            oscillator zeta, 1/s (default 2)\n"
      "  --gain G               oscillator drive gain g (default 1)\n"
      "  --zoom Z               PNG pixels per cell, 1..64 (default 4)\n"
      "  --device NAME          substring of the Vulkan device name\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string out = "sim_out";
  uint32_t steps = 90, zoom = 4;
  float dt = 1.0f / 30.0f;
  SimulationDesc desc;
  SimulationParams p;
  DeviceDesc dd;
  dd.applicationName = "canopy-sim";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--help" || a == "-h") return usage("");
    else if (a == "--out") { if (!(v = next())) return usage("--out needs a folder"); out = v; }
    else if (a == "--steps") { if (!parseUint(next(), 1, 1000000, &steps)) return usage("--steps needs an integer in [1, 1000000]"); }
    else if (a == "--dt") { if (!parseFloat(next(), &dt)) return usage("--dt needs a number"); }
    else if (a == "--size") { if (!parseUint(next(), 1, 1u << 30, &desc.gridSize)) return usage("--size needs an integer"); }
    else if (a == "--wind") {
      if (!(v = next())) return usage("--wind needs sides");
      p.wind.sides = 0;
      std::stringstream ss(v);
      std::string side;
      while (std::getline(ss, side, ',')) {
        if (side == "left") p.wind.sides |= kWindFromLeft;
        else if (side == "right") p.wind.sides |= kWindFromRight;
        else if (side == "top" || side == "up") p.wind.sides |= kWindFromTop;
        else if (side == "bottom" || side == "down") p.wind.sides |= kWindFromBottom;
        else if (side != "none") return usage("--wind: unknown side '" + side + "' (left, right, top, bottom, none)");
      }
    } else if (a == "--strength") { if (!parseFloat(next(), &p.wind.strength)) return usage("--strength needs a number"); }
    else if (a == "--frequency") { if (!parseFloat(next(), &p.wind.frequency)) return usage("--frequency needs a number"); }
    else if (a == "--gust") { if (!parseFloat(next(), &p.wind.gust)) return usage("--gust needs a number"); }
    else if (a == "--viscosity") { if (!parseFloat(next(), &p.fluid.viscosity)) return usage("--viscosity needs a number"); }
    else if (a == "--scheme") {
      v = next();
      if (v && !std::strcmp(v, "mac")) p.fluid.scheme = FluidScheme::MacMultigrid;
      else if (v && !std::strcmp(v, "stam")) p.fluid.scheme = FluidScheme::Stam;
      else return usage("--scheme must be mac or stam");
    } else if (a == "--boundary") {
      v = next();
      if (v && !std::strcmp(v, "tunnel")) p.fluid.boundary = FluidBoundary::WindTunnel;
      else if (v && !std::strcmp(v, "walls")) p.fluid.boundary = FluidBoundary::Walls;
      else return usage("--boundary must be tunnel or walls");
    } else if (a == "--iterations") { if (!parseUint(next(), 0, 1u << 30, &p.fluid.iterations)) return usage("--iterations needs an integer"); }
    else if (a == "--cycles") { if (!parseUint(next(), 0, 1u << 30, &p.fluid.multigridCycles)) return usage("--cycles needs an integer"); }
    else if (a == "--motor") {
      Motor m;
      if (!(v = next()) || std::sscanf(v, "%f,%f,%f,%f", &m.x, &m.y, &m.radius, &m.strength) != 4)
        return usage("--motor needs X,Y,R,S");
      p.motors.push_back(m);
    } else if (a == "--stiffness") { if (!parseFloat(next(), &p.wave.stiffness)) return usage("--stiffness needs a number"); }
    else if (a == "--wave-speed") { if (!parseFloat(next(), &p.wave.speed)) return usage("--wave-speed needs a number"); }
    else if (a == "--damping") { if (!parseFloat(next(), &p.wave.damping)) return usage("--damping needs a number"); }
    else if (a == "--gain") { if (!parseFloat(next(), &p.wave.gain)) return usage("--gain needs a number"); }
    else if (a == "--zoom") { if (!parseUint(next(), 1, 64, &zoom)) return usage("--zoom needs an integer in [1, 64]"); }
    else if (a == "--device") { if (!(v = next())) return usage("--device needs a name"); dd.preferredDevice = v; }
    else return usage("unknown option '" + a + "'");
  }
  // Refuse bad values before touching the GPU, with the parameter's name and range.
  Status s = validateSimulationDesc(desc);
  if (s.ok()) s = validateSimulationParams(p, dt);
  if (!s.ok()) return usage(s.message());
  if (mkdir(out.c_str(), 0755) != 0 && errno != EEXIST) {
    std::fprintf(stderr, "canopy-sim: cannot create '%s': %s\n", out.c_str(), std::strerror(errno));
    return 1;
  }
  Device dev;
  if (!(s = createDevice(dd, &dev)).ok()) {
    std::fprintf(stderr, "canopy-sim: %s\n", s.message().c_str());
    return 1;
  }
  Simulation sim;
  SimulationFields f;
  s = createSimulation(dev, desc, &sim);
  if (s.ok()) s = runSimulationSteps(sim, p, dt, steps);
  if (s.ok()) s = readSimulationFields(sim, &f);
  const uint32_t n = desc.gridSize;
  // The tiled buffer holds the tiled V_s, then the tiled V_wind and the pushers' bend fields
  // (shared/sim.h tiledVec2s): the plants' field is its first N^2 vectors.
  const std::vector<float> tiledVs(f.tiled.begin(), f.tiled.begin() + std::min<size_t>(f.tiled.size(), 2 * size_t(n) * n));
  struct Field { const char* name; const std::vector<float>* data; } fields[] = {
      {"wind", &f.wind}, {"vs", &f.vs}, {"tiled", &tiledVs}};
  if (s.ok()) {
    std::printf("canopy-sim: %u steps of %.4f s on %s, N = %u, t = %.3f s\n", steps, dt, dev.properties.deviceName, n, sim.time);
    for (const Field& x : fields) {
      double maxMag = 0, mx = 0, my = 0;
      for (size_t c = 0; c < x.data->size(); c += 2) {
        maxMag = std::max(maxMag, std::hypot(double((*x.data)[c]), double((*x.data)[c + 1])));
        mx += (*x.data)[c];
        my += (*x.data)[c + 1];
      }
      mx /= n * n;
      my /= n * n;
      const std::string base = out + "/" + x.name;
      if (s.ok()) s = writeNpy(base + ".npy", *x.data, {n, n, 2});
      if (s.ok()) s = writePng(base + ".png", n * zoom, n * zoom, vectorFieldToRgba(*x.data, n, 0.0f, zoom));
      std::printf("  %-6s mean (%+.4f, %+.4f), max |v| %.4f  -> %s.npy, %s.png (brightness 1 = %.4f)\n", x.name, mx, my,
                  maxMag, base.c_str(), base.c_str(), maxMag);
    }
  }
  int rc = 0;
  if (!s.ok()) {
    std::fprintf(stderr, "canopy-sim: %s\n", s.message().c_str());
    rc = 1;
  }
  destroySimulation(sim);
  destroyDevice(dev);
  return rc;
}
