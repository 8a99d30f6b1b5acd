#pragma once
// The benchmark's host: a colour and a depth target, and a frame graph that clears them and adds
// Canopy's passes (the render-graph path), shared by the animation and soak benchmarks.
#include "engine/render_graph.h"
#include "render/canopy.h"

namespace canopy::bench {

struct HostTargets {
  Image color, depth;  // `format` colour (also a transfer source), D32 depth
};
Status createHostTargets(Device& d, uint32_t w, uint32_t h, VkFormat format, HostTargets* t);
void destroyHostTargets(Device& d, HostTargets& t);
// The host's frame: clear its targets (contents are not carried over), then Canopy's passes (or
// only the clear); the colour is left in `colorFinal`.
Status buildHostGraph(Device& d, CanopyContext* ctx, HostTargets& t, bool withCanopy, rg::State colorFinal, rg::RenderGraph* g);

}  // namespace canopy::bench
