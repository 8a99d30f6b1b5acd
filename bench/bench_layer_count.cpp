// The layer-count study (issue 36; docs/lab/performance-notebook.md "How many layers"): the paper reports that
// three to five layers suffice and that more add little. For 1, 2, 3, 5, 7 and 9 equal layers (and
// the paper's 3(1-1-1) and 5(3-1-1)), the animated frames against the same wind drawn with 16
// layers, frame by frame, still camera: the 2D method's own limit of finer slicing (delays nearly
// continuous in depth, every leaf in a thin slab) is the reference, because the per-vertex baseline
// moves the mesh by another model (hierarchical bending) and its difference would measure that
// model's gap, not the layer count's.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "bench/bench.h"
#include "bench/bench_host.h"
#include "engine/camera.h"
#include "engine/device.h"
#include "engine/transfer.h"
#include "render/gltf_loader.h"
#include "render/layer_layout.h"
#include "tools/scene_generator.h"
#include "tools/world_lock.h"

namespace canopy::bench {
namespace {

// One context drawing `frames` frames of the model under the wind at a still camera; each frame's
// RGBA8 pixels go to `each`.
Status runFrames(Device& d, const VegetationModel& model, const std::string& layout, const LayerCountOptions& o, float strength,
                 const std::function<void(int, const std::vector<uint8_t>&)>& each) {
  CanopyDesc desc;
  desc.width = o.width;
  desc.height = o.height;
  LayerLayout parsed;
  CANOPY_TRY(parseLayerLayout(layout, &parsed));
  desc.maxLayers = std::max(parsed.count(), LayerLayout{}.count());  // room for the default layout and the reference's 16
  CanopyContext* ctx = nullptr;
  CANOPY_TRY(createCanopy(d, model, desc, &ctx));
  HostTargets host;
  rg::RenderGraph graph;
  Status s = [&]() -> Status {
    CanopyParams p = canopyParams(ctx);
    CANOPY_TRY(parseLayerLayout(layout, &p.layers.layout));
    p.windMode = WindMode::PlaneSides;  // the wind as the plane's sides (domain units/s)
    p.simulation.wind.strength = strength;
    CANOPY_TRY(setCanopyParams(ctx, p));
    CANOPY_TRY(createHostTargets(d, o.width, o.height, VK_FORMAT_R8G8B8A8_UNORM, &host));
    CANOPY_TRY(buildHostGraph(d, ctx, host, true, rg::stateOf(rg::Use::ColorAttachmentReadWrite), &graph));
    const LayerView view = orbitView(model.boundsMin, model.boundsMax, 20.0f, 10.0f, 40.0f, float(o.width) / float(o.height), 1.05f);
    std::vector<uint8_t> pixels(size_t(o.width) * o.height * 4);
    for (int i = 0; i < o.frames; ++i) {
      CanopyFrame f;
      f.camera = toCamera(view);
      f.dt = 1.0f / 30.0f;
      CANOPY_TRY(beginCanopyFrame(ctx, f));
      CANOPY_TRY(submitAndWait(d, [&](VkCommandBuffer cmd) { return graph.record(cmd, nullptr); }));
      CANOPY_TRY(readbackImage(d, host.color, 0, 4, pixels.data(), rg::stateOf(rg::Use::ColorAttachmentReadWrite)));
      each(i, pixels);
    }
    return Status();
  }();
  graph.release(d);
  destroyHostTargets(d, host);
  destroyCanopy(ctx);
  return s;
}

struct Row {
  std::string layout;
  double colour = 0, iouMean = 0, iouMin = 1, silhouette = 0;
  int frames = 0;
};

}  // namespace

int runLayerCountBench(Device& d, const LayerCountOptions& o) {
  struct Model {
    std::string name;
    VegetationModel m;
  };
  std::vector<Model> models;
  {
    SceneDesc sd;
    sd.faces = o.faces;
    Model g;
    g.name = o.scene + " (" + std::to_string(o.faces) + " faces)";
    Status s = parseSceneKind(o.scene, &sd.kind);
    if (s.ok()) s = generateScene(sd, &g.m);
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
      return 1;
    }
    models.push_back(std::move(g));
  }
  if (!o.gltf.empty()) {
    Model g;
    g.name = o.gltf.substr(o.gltf.find_last_of('/') + 1);
    const Status s = loadGltf(o.gltf, {}, &g.m);
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench: %s\n", s.message().c_str());
      return 1;
    }
    models.push_back(std::move(g));
  }
  std::printf("\nLayer count at %ux%u, still camera, wind strength %.2f domain units/s: each layout's frames %d..%d against\n"
              "the same wind drawn with %s layers (the reference), frame by frame: colour difference (mean |RGB|, 8-bit levels,\n"
              "over pixels either covers), coverage IoU, silhouette distance (px); 'motion' is the reference against\n"
              "itself without wind (how far the wind moves the picture), 'relative' the colour difference over it.\n",
              o.width, o.height, double(o.strength), o.skip, o.frames - 1, o.reference.c_str());
  FILE* csv = o.csvPath.empty() ? nullptr : std::fopen(o.csvPath.c_str(), "w");
  if (!o.csvPath.empty() && !csv) {
    std::fprintf(stderr, "canopy-bench: cannot write %s\n", o.csvPath.c_str());
    return 1;
  }
  if (csv) std::fprintf(csv, "model,layout,layers,colour,relative,iou_mean,iou_min,silhouette_px\n");
  for (const Model& mod : models) {
    // The reference's frames, and the same without wind (one frame: nothing moves).
    std::vector<std::vector<uint8_t>> ref(size_t(o.frames));
    Status s = runFrames(d, mod.m, o.reference, o, o.strength, [&](int i, const std::vector<uint8_t>& px) { ref[size_t(i)] = px; });
    std::vector<uint8_t> still;
    LayerCountOptions one = o;
    one.frames = 1;
    if (s.ok()) s = runFrames(d, mod.m, o.reference, one, 0.0f, [&](int, const std::vector<uint8_t>& px) { still = px; });
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-bench: %s: %s\n", mod.name.c_str(), s.message().c_str());
      if (csv) std::fclose(csv);
      return 1;
    }
    double motion = 0;
    for (int i = o.skip; i < o.frames; ++i) motion += compareFrames(ref[size_t(i)], still, o.width, o.height, kHostClearRgba8).colourMean;
    motion /= double(o.frames - o.skip);
    std::printf("\n%s: motion (reference with wind against without) %.3f levels\n", mod.name.c_str(), motion);
    std::printf("  %-10s %7s %9s %9s %9s %9s %10s\n", "layout", "layers", "colour", "relative", "IoU mean", "IoU min", "sil. px");
    for (const std::string& layout : o.layouts) {
      Row r;
      r.layout = layout;
      s = runFrames(d, mod.m, layout, o, o.strength, [&](int i, const std::vector<uint8_t>& px) {
        if (i < o.skip) return;
        const WorldLockError e = compareFrames(px, ref[size_t(i)], o.width, o.height, kHostClearRgba8);
        r.colour += e.colourMean;
        r.iouMean += e.coverageIoU;
        r.iouMin = std::min(r.iouMin, e.coverageIoU);
        r.silhouette += e.silhouetteMeanPx;
        r.frames++;
      });
      if (!s.ok()) {
        std::fprintf(stderr, "canopy-bench: %s %s: %s\n", mod.name.c_str(), layout.c_str(), s.message().c_str());
        if (csv) std::fclose(csv);
        return 1;
      }
      const double n = std::max(r.frames, 1);
      LayerLayout parsed;
      (void)parseLayerLayout(layout, &parsed);
      const double rel = motion > 0 ? r.colour / n / motion : 0.0;
      std::printf("  %-10s %7u %9.3f %9.3f %9.4f %9.4f %10.3f\n", layout.c_str(), parsed.count(), r.colour / n, rel, r.iouMean / n,
                  r.iouMin, r.silhouette / n);
      if (csv)
        std::fprintf(csv, "%s,%s,%u,%.4f,%.4f,%.5f,%.5f,%.4f\n", mod.name.c_str(), layout.c_str(), parsed.count(), r.colour / n, rel,
                     r.iouMean / n, r.iouMin, r.silhouette / n);
    }
  }
  if (csv) std::fclose(csv);
  return 0;
}

}  // namespace canopy::bench
