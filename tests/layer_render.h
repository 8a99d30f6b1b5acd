#pragma once
// One layer frame for the layer tests: the view update (a re-slice when due), then the layer
// passes in a graph of their own, recorded, submitted and waited for.
#include "engine/device.h"
#include "render/layers.h"

namespace canopy::test {

inline Status renderLayersOnce(Device& dev, LayeredVegetation& lv, const LayerView& view) {
  bool rebuild = false;
  CANOPY_TRY(updateLayerView(lv, view, &rebuild));
  rg::RenderGraph g;
  CANOPY_TRY(addLayerPasses(lv, g, nullptr));
  CANOPY_TRY(g.compile());
  CANOPY_TRY(g.realize(dev));
  Status s = submitAndWait(dev, [&](VkCommandBuffer cmd) { return g.record(cmd); });
  g.release(dev);
  return s;
}

}  // namespace canopy::test
