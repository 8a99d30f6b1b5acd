#include <algorithm>

#include "render/canopy_context.h"
#include "render/host_images.h"

namespace canopy {

void retireRecordGraphs(CanopyContext& c, std::vector<RecordGraph> graphs) {
  if (graphs.empty()) return;
  Device* d = c.device;
  auto old = std::make_shared<std::vector<RecordGraph>>(std::move(graphs));
  deferRelease(*d, [d, old] {
    for (RecordGraph& g : *old) g.graph->release(*d);
  });
}

RecordGraph* findRecordGraph(CanopyContext& c, const CanopyFrameInputs& in) {
  for (RecordGraph& g : c.recordGraphs)
    if (g.generation == c.generation && sameHostImage(g.inputs.color, in.color) && sameHostImage(g.inputs.depth, in.depth) &&
        sameHostImage(g.inputs.motion, in.motion))
      return &g;
  return nullptr;
}

Status buildRecordGraph(CanopyContext& c, const CanopyFrameInputs& in, RecordGraph** out) {
  const bool motion = c.desc.motionFormat != VK_FORMAT_UNDEFINED;
  // Graphs of replaced resources, and the least recently used beyond the cache size, may still be
  // executing: they are released frames later.
  std::vector<RecordGraph> keep, drop;
  for (RecordGraph& g : c.recordGraphs) (g.generation == c.generation ? keep : drop).push_back(std::move(g));
  if (keep.size() >= kMaxRecordGraphs) {
    auto lru = std::min_element(keep.begin(), keep.end(),
                                [](const RecordGraph& a, const RecordGraph& b) { return a.lastUse < b.lastUse; });
    drop.push_back(std::move(*lru));
    keep.erase(lru);
  }
  c.recordGraphs = std::move(keep);
  retireRecordGraphs(c, std::move(drop));
  auto graph = std::make_shared<rg::RenderGraph>();
  const uint32_t w = c.desc.width, h = c.desc.height;
  auto import = [&](const char* name, const CanopyImage& img, VkFormat format, rg::ResourceId* id) -> Status {
    ImageDesc d;
    d.format = format;
    d.width = w;
    d.height = h;
    *id = graph->importImage(name, d, img.current, img.final);
    return graph->bindImage(*id, hostImage(img, format, w, h));
  };
  CompositeTargets t;
  CANOPY_TRY(import("host: colour", in.color, c.desc.colorFormat, &t.color));
  CANOPY_TRY(import("host: depth", in.depth, c.desc.depthFormat, &t.depth));
  if (motion) CANOPY_TRY(import("host: motion", in.motion, c.desc.motionFormat, &t.motion));
  CANOPY_TRY(addCanopyPasses(&c, *graph, t));
  CANOPY_TRY(graph->compile());
  CANOPY_TRY(graph->realize(*c.device));
  RecordGraph r;
  r.graph = std::move(graph);
  r.inputs = in;
  r.generation = c.generation;
  c.recordGraphs.push_back(std::move(r));
  c.recordGraphBuilds++;
  *out = &c.recordGraphs.back();
  return Status();
}

}  // namespace canopy
