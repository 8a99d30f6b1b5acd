// canopy-layers: loads a glTF/GLB vegetation model, splits rigid parts from foliage, finds the
// leaf roots, slices the foliage into depth layers for one view and writes what it made:
// layer_NN.png (each layer, straight alpha), background.png (rigid parts), layers_false_colour.png
// (which layer each pixel comes from, like Figure 3c of the paper) and composite.png (the layers
// over the background by depth, no animation). `canopy-layers --help` lists the options.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <string>

#include "demo/cache_cli.h"
#include "demo/cli.h"
#include "engine/device.h"
#include "tools/own_device.h"
#include "tools/image_io.h"
#include "render/gltf_loader.h"
#include "render/layers.h"

using namespace canopy;

namespace {

int usage(const std::string& why) {
  if (!why.empty()) {
    std::fprintf(stderr, "canopy-layers: %s (see --help)\n", why.c_str());
    return 2;
  }
  std::printf(
      "usage: canopy-layers MODEL.gltf|MODEL.glb [options]\n"
      "  --layers L             layer layout N(near-mid-far) or N, 1..32 layers (default 5(3-1-1))\n"
      "  --regions A,B          near region ends / far region starts, fractions of the foliage depth range,\n"
      "                         0 <= A <= B <= 1 (default 0.333,0.667)\n"
      "  --region-distances A,B the same as view distances from the camera, world units\n"
      "  --size WxH             image size, 1..16384 each (default 1024x768)\n"
      "  --out DIR              output folder, created if missing (default layers_out)\n"
      "  --yaw D                camera yaw about +Y, degrees; 0 looks at the model's +Z side (default 0)\n"
      "  --pitch D              camera pitch, degrees, [-89, 89] (default 10)\n"
      "  --fov D                vertical field of view, degrees, [1, 170] (default 40)\n"
      "  --distance S           camera distance, multiple of the framing distance, (0, 100] (default 0.8)\n"
      "  --rigid M1,M2          materials (names or #index) forced to be rigid background\n"
      "  --foliage M1,M2        materials forced to be foliage\n"
      "  --slice roots|geometry leaf-root slicing (default) or the simple per-triangle segmentation\n"
      "  --per-layer            draw one pass per layer even when gl_Layer is available\n"
      "  --no-weld              leaves only through shared indices, not equal positions\n"
      "  --device NAME          substring of the Vulkan device name\n"
      "Leaf-root cache:\n%s", cli::cacheHelp());
  return 0;
}

bool parsePair(const char* s, float* a, float* b) {
  if (!s) return false;
  const std::vector<std::string> p = cli::splitList(s);
  return p.size() == 2 && cli::parseFloat(p[0].c_str(), a) && cli::parseFloat(p[1].c_str(), b);
}

float toSrgb(float x) {
  x = std::clamp(x, 0.0f, 1.0f);
  return x <= 0.0031308f ? 12.92f * x : 1.055f * std::pow(x, 1.0f / 2.4f) - 0.055f;
}

// Premultiplied linear RGBA -> straight-alpha sRGB bytes.
void toBytes(const glm::vec4& c, uint8_t* out) {
  const float a = std::clamp(c.a, 0.0f, 1.0f);
  const glm::vec3 rgb = a > 0 ? glm::vec3(c) / a : glm::vec3(0);
  for (int k = 0; k < 3; ++k) out[k] = uint8_t(std::lround(toSrgb(rgb[k]) * 255.0f));
  out[3] = uint8_t(std::lround(a * 255.0f));
}

const glm::vec3 kPalette[] = {{0.95f, 0.25f, 0.2f}, {0.2f, 0.75f, 0.25f}, {0.2f, 0.45f, 0.95f}, {0.95f, 0.8f, 0.15f},
                              {0.75f, 0.3f, 0.85f}, {0.15f, 0.85f, 0.85f}, {0.95f, 0.55f, 0.15f}, {0.6f, 0.6f, 0.6f}};

// canopy-layers' command line.
struct LayersOptions {
  std::string model, out = "layers_out";
  LayeredVegetationDesc desc;
  float yaw = 0, pitch = 10, fov = 40, distance = 0.8f;
  DeviceDesc device;
  cli::CacheOptions cache;
};

// Reads the options into *o: -1 to go on, else the exit code (usage printed).
int parseArgs(int argc, char** argv, LayersOptions* o) {
  std::string& model = o->model;
  std::string& out = o->out;
  LayeredVegetationDesc& desc = o->desc;
  desc.settings.regions = RegionSplit{};
  float &yaw = o->yaw, &pitch = o->pitch, &fov = o->fov, &distance = o->distance;
  DeviceDesc& dd = o->device;
  cli::CacheOptions& cache = o->cache;
  std::string why;
  dd.applicationName = "canopy-layers";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--help" || a == "-h") return usage("");
    else if (a == "--layers") {
      if (!(v = next())) return usage("--layers needs a layout such as 5(3-1-1)");
      Status s = parseLayerLayout(v, &desc.settings.layout);
      if (!s.ok()) return usage(s.message());
    } else if (a == "--regions" || a == "--region-distances") {
      RegionSplit& r = desc.settings.regions;
      if (!parsePair(next(), &r.nearEnd, &r.farStart)) return usage(a + " needs two numbers A,B");
      r.absolute = a == "--region-distances";
      Status s = validateRegionSplit(r);
      if (!s.ok()) return usage(s.message());
    } else if (a == "--size") {
      if (!(v = next())) return usage("--size needs WxH");
      const std::string s = v;
      const size_t x = s.find('x');
      if (x == std::string::npos || !cli::parseUint(s.substr(0, x).c_str(), 1, 16384, &desc.width) ||
          !cli::parseUint(s.substr(x + 1).c_str(), 1, 16384, &desc.height))
        return usage("--size needs WxH with 1..16384 each, got '" + s + "'");
    } else if (a == "--out") {
      if (!(v = next())) return usage("--out needs a folder");
      out = v;
    } else if (a == "--yaw") {
      if (!cli::parseFloat(next(), &yaw) || !std::isfinite(yaw)) return usage("--yaw needs degrees");
    } else if (a == "--pitch") {
      if (!cli::parseFloat(next(), &pitch) || !(pitch >= -89 && pitch <= 89)) return usage("--pitch needs degrees in [-89, 89]");
    } else if (a == "--fov") {
      if (!cli::parseFloat(next(), &fov) || !(fov >= 1 && fov <= 170)) return usage("--fov needs degrees in [1, 170]");
    } else if (a == "--distance") {
      if (!cli::parseFloat(next(), &distance) || !(distance > 0 && distance <= 100)) return usage("--distance needs a number in (0, 100]");
    } else if (a == "--rigid" || a == "--foliage") {
      if (!(v = next())) return usage(a + " needs material names or #indices");
      (a == "--rigid" ? desc.split.rigid : desc.split.foliage) = cli::splitList(v);
    } else if (a == "--slice") {
      if (!(v = next())) return usage("--slice needs roots or geometry");
      const std::string s = v;
      if (s == "roots") desc.settings.slice = SliceMode::LeafRoots;
      else if (s == "geometry") desc.settings.slice = SliceMode::Geometry;
      else return usage("--slice needs roots or geometry, got '" + s + "'");
    } else if (a == "--per-layer") {
      desc.settings.draw = LayerDrawMode::PerLayer;
    } else if (a == "--no-weld") {
      desc.roots.weldPositions = false;
    } else if (const int c = cli::parseCacheOption(argc, argv, &i, &cache, &why)) {
      if (c < 0) return usage(why);
    } else if (a == "--device") {
      if (!(v = next())) return usage("--device needs a name");
      dd.preferredDevice = v;
    } else if (!a.empty() && a[0] == '-') {
      return usage("unknown option " + a);
    } else if (model.empty()) {
      model = a;
    } else {
      return usage("more than one model given ('" + model + "' and '" + a + "')");
    }
  }
  return -1;
}

// What the split and the leaf roots made of the model.
void printSplit(const Device& dev, const VegetationModel& m, const LayeredVegetation& lv, const LayeredVegetationDesc& desc) {
  std::printf("Device: %s\n", dev.properties.deviceName);
  std::vector<uint64_t> used(lv.mesh.materials.size(), 0);
  for (uint32_t mat : m.triangleMaterial) used[mat]++;
  for (size_t i = 0; i < lv.mesh.materials.size(); ++i) {
    if (!used[i]) continue;
    std::printf("  material #%zu '%s': %s (%s), %llu triangles\n", i, lv.mesh.materials[i].name.c_str(),
                lv.mesh.split.role[i] == MaterialRole::Rigid ? "rigid" : "foliage", lv.mesh.split.reason[i].c_str(),
                (unsigned long long)used[i]);
    // Its parts where its role is only a hint (render/part_split.h): where each went and why.
    uint32_t shown = 0, rigid = 0, parts = 0;
    for (const PartReport& p : lv.mesh.split.parts) {
      if (p.material != i) continue;
      ++parts;
      rigid += p.rigid;
      if (shown < 12 && (p.rigid || shown < 4)) {
        std::printf("    part of %u triangles: %s (%s)\n", p.triangles, p.rigid ? "rigid" : "foliage", p.reason.c_str());
        ++shown;
      }
    }
    if (parts) std::printf("    %u parts by their geometry: %u rigid, %u foliage\n", parts, rigid, parts - rigid);
  }
  std::printf("Split: %llu foliage triangles, %llu rigid triangles\n", (unsigned long long)lv.stats.foliageTriangles,
              (unsigned long long)lv.stats.rigidTriangles);
  std::printf("Leaves: %u (%s), preprocessing %.1f ms (%s)\n", lv.stats.leafCount,
              desc.roots.weldPositions ? "welded by position" : "shared indices only", lv.stats.preprocessMs,
              lv.stats.rootCacheNote.c_str());
}

// Each layer read back and written as layer_NN.png (straight-alpha sRGB), with its placement.
Status writeLayers(LayeredVegetation& lv, const std::string& out, std::vector<std::vector<glm::vec4>>* colors,
                   std::vector<std::vector<float>>* depths) {
  Status s;
  const uint32_t w = lv.desc.width, h = lv.desc.height, n = lv.settings.layout.count();
  const size_t px = size_t(w) * h;
  colors->assign(n, {});
  depths->assign(n, {});
  for (uint32_t l = 0; l < n && s.ok(); ++l) {
    s = readLayerColor(lv, l, &(*colors)[l]);
    if (s.ok()) s = readLayerDepth(lv, l, &(*depths)[l]);
    std::vector<uint8_t> bytes(px * 4);
    for (size_t i = 0; i < px && s.ok(); ++i) toBytes((*colors)[l][i], &bytes[i * 4]);
    char name[64];
    std::snprintf(name, sizeof name, "/layer_%02u.png", l);
    if (s.ok()) s = writePng(out + name, w, h, bytes);
    if (s.ok()) {
      size_t covered = 0;
      for (const glm::vec4& c : (*colors)[l]) covered += c.a > 0;
      const LayerInfo& li = lv.visible.layers[l];
      std::printf("  layer %u: depth %.3f..%.3f (L = %.3f), %u leaves, %llu triangles, %.1f%% of pixels, "
                  "root line y=%.0f, height %.0f px\n",
                  l, li.slab.zNear, li.slab.zFar, li.slab.distance, li.leaves, (unsigned long long)li.triangles,
                  100.0 * double(covered) / double(px), li.rootLineY, li.height);
    }
  }
  return s;
}

// The background, the layers in false colour by the frontmost layer, and the static composite
// (far to near, the background inserted by its depth) over a sky colour.
Status writeComposites(LayeredVegetation& lv, const std::string& out, const std::vector<std::vector<glm::vec4>>& colors,
                       const std::vector<std::vector<float>>& depths) {
  const uint32_t w = lv.desc.width, h = lv.desc.height, n = lv.settings.layout.count();
  const size_t px = size_t(w) * h;
  std::vector<glm::vec4> bg;
  std::vector<float> bgDepth;
  Status s = readBackground(lv, &bg, &bgDepth);
  if (s.ok()) {
    std::vector<uint8_t> bytes(px * 4), falseColour(px * 4), composite(px * 4);
    for (size_t i = 0; i < px; ++i) {
      toBytes(bg[i], &bytes[i * 4]);
      // Far to near, the background inserted by its depth (docs/design.md "Conventions where the paper is silent", compositing).
      glm::vec4 acc(0.0f);
      bool bgDone = false;
      int front = -1;
      float frontDepth = 2.0f;
      for (int l = int(n) - 1; l >= 0; --l) {
        const float d = depths[l][i];
        if (!bgDone && bgDepth[i] >= d) {
          acc = bg[i] + (1.0f - bg[i].a) * acc;
          bgDone = true;
        }
        const glm::vec4 c = colors[l][i];
        acc = c + (1.0f - c.a) * acc;
        if (c.a > 0 && d < frontDepth) front = l, frontDepth = d;
      }
      if (!bgDone) acc = bg[i] + (1.0f - bg[i].a) * acc;
      const glm::vec4 sky(0.55f, 0.7f, 0.9f, 1.0f);
      acc = acc + (1.0f - acc.a) * sky;
      toBytes(acc, &composite[i * 4]);
      glm::vec3 fc(0.08f);
      if (bg[i].a > 0 && bgDepth[i] < frontDepth) {
        fc = glm::vec3(0.35f + 0.4f * std::min(1.0f, glm::dot(glm::vec3(bg[i]), glm::vec3(0.33f))));
      } else if (front >= 0) {
        const glm::vec4 c = colors[front][i];
        const float lum = std::min(1.0f, glm::dot(glm::vec3(c) / std::max(c.a, 1e-4f), glm::vec3(0.3f, 0.59f, 0.11f)));
        fc = kPalette[front % 8] * (0.45f + 0.55f * std::sqrt(lum));
      }
      toBytes(glm::vec4(fc, 1.0f), &falseColour[i * 4]);
    }
    s = writePng(out + "/background.png", w, h, bytes);
    if (s.ok()) s = writePng(out + "/layers_false_colour.png", w, h, falseColour);
    if (s.ok()) s = writePng(out + "/composite.png", w, h, composite);
  }
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  LayersOptions opt;
  if (const int code = parseArgs(argc, argv, &opt); code >= 0) return code;
  const std::string& model = opt.model;
  const std::string& out = opt.out;
  LayeredVegetationDesc& desc = opt.desc;
  cli::CacheOptions& cache = opt.cache;
  if (cache.clear) return cli::clearCacheCommand("canopy-layers", cache, model);
  if (model.empty()) return usage("no model given");
  auto fail = [](const Status& s) {
    std::fprintf(stderr, "canopy-layers: %s\n", s.message().c_str());
    return 1;
  };
  // The caches go to the user's cache folder unless the options say otherwise (docs/design.md
  // "Files"); a folder that cannot be used means no cache, said on one line.
  const Status where = cli::resolveCacheFolder(cache, model, &desc.rootCacheDir);
  if (!where.ok()) std::printf("No cache: %s\n", where.message().c_str());
  desc.cacheMaxBytes = uint64_t(cache.maxMiB) << 20;
  VegetationModel m;
  const auto t0 = std::chrono::steady_clock::now();
  Status s = loadGltf(model, GltfLoadOptions{}, &m);
  if (!s.ok()) return fail(s);
  const double loadMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("Model: %s: %zu triangles, %zu vertices, %zu materials, loaded in %.1f ms\n", model.c_str(),
              m.triangleCount(), m.positions.size(), m.materials.size() - 1, loadMs);
  for (const std::string& w : m.warnings) std::printf("  warning: %s\n", w.c_str());

  Device dev;
  s = createDevice(opt.device, &dev);
  if (!s.ok()) return fail(s);
  LayeredVegetation lv;
  s = createLayeredVegetation(dev, m, desc, &lv);
  if (!s.ok()) {
    destroyDevice(dev);
    return fail(s);
  }
  printSplit(dev, m, lv, desc);

  const LayerView view = orbitView(m.boundsMin, m.boundsMax, opt.yaw, opt.pitch, opt.fov, float(desc.width) / float(desc.height), opt.distance);
  bool rebuild = false;
  rg::RenderGraph g;
  s = updateLayerView(lv, view, &rebuild);
  if (s.ok()) s = addLayerPasses(lv, g, nullptr);
  if (s.ok()) s = g.compile();
  if (s.ok()) s = g.realize(dev);
  const auto t1 = std::chrono::steady_clock::now();
  if (s.ok()) s = submitAndWait(dev, [&](VkCommandBuffer cmd) { return g.record(cmd); });
  const double rasterMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t1).count();
  std::printf("Layers: %s, %s, %s slicing, drawn in %.1f ms (wall, incl. submit)\n", toString(lv.settings.layout).c_str(),
              lv.pipelines.singlePass ? "single pass (gl_Layer)" : "one draw per layer",
              lv.settings.slice == SliceMode::LeafRoots ? "leaf-root" : "geometric", rasterMs);

  std::error_code ec;
  std::filesystem::create_directories(out, ec);
  if (ec) s = Status::error("cannot create " + out + ": " + ec.message());
  std::vector<std::vector<glm::vec4>> colors;
  std::vector<std::vector<float>> depths;
  if (s.ok()) s = writeLayers(lv, out, &colors, &depths);
  if (s.ok()) s = writeComposites(lv, out, colors, depths);
  if (s.ok()) std::printf("Wrote %u layer PNGs, background.png, layers_false_colour.png, composite.png to %s\n", lv.settings.layout.count(), out.c_str());
  g.release(dev);
  destroyLayeredVegetation(lv);
  destroyDevice(dev);
  if (!s.ok()) return fail(s);
  return 0;
}
