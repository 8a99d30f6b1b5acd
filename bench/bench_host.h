#pragma once
// The benchmark's host: a colour and a depth target, and a frame graph that clears them and adds
// Canopy's passes (the render-graph path), shared by the animation and soak benchmarks.
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "engine/render_graph.h"
#include "render/canopy.h"

namespace canopy::bench {

// The host's clear colour, and the same in RGBA8 (what a covered pixel differs from). Alpha 0: after
// Canopy's premultiplied "over" the target's alpha is the vegetation's coverage (canopy-bench camera's
// cross-fade column reads it).
constexpr float kHostClear[4] = {0.45f, 0.6f, 0.8f, 0.0f};
constexpr uint8_t kHostClearRgba8[3] = {115, 153, 204};

struct HostTargets {
  Image color, depth;  // `format` colour (also a transfer source), D32 depth
};
Status createHostTargets(Device& d, uint32_t w, uint32_t h, VkFormat format, HostTargets* t);
void destroyHostTargets(Device& d, HostTargets& t);
// The host's frame: clear its targets (contents are not carried over), then Canopy's passes (or
// only the clear); the colour is left in `colorFinal`.
Status buildHostGraph(Device& d, CanopyContext* ctx, HostTargets& t, bool withCanopy, rg::State colorFinal, rg::RenderGraph* g);

// Per-frame samples of `frames` frames after one warm-up: wall clock (submit-to-fence of the whole
// graph) and each pass's GPU timestamps, ms. `viewOf(i)` is frame i's camera; ctx null: the graph
// alone (e.g. the host's clear).
struct FrameSamples {
  std::vector<double> wallMs;
  std::map<std::string, std::vector<double>> passMs;
};
Status sampleFrames(Device& d, CanopyContext* ctx, rg::RenderGraph& g, GpuTimer& timer,
                    const std::function<LayerView(int)>& viewOf, float dt, int frames, FrameSamples* out);

}  // namespace canopy::bench
