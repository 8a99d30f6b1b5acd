#pragma once
// The layer passes in a render graph (paper 3.2; docs/design.md "Per-frame data flow"): the frame constants, the foliage and
// background draws of a re-slice at once, a spread re-slice's slice and cross-fade; each records
// only in the frames updateLayerView planned that work for.
#include "engine/render_graph.h"
#include "engine/status.h"

namespace canopy {
struct Device;
struct LayeredVegetation;

struct LayerResources {
  rg::ResourceId color = rg::kInvalidResource, depth = rg::kInvalidResource, ids = rg::kInvalidResource;
  rg::ResourceId backgroundColor = rg::kInvalidResource, backgroundDepth = rg::kInvalidResource;
  // The next set's colour (spread re-slicing only): the composite's occupancy unites it in.
  rg::ResourceId nextColor = rg::kInvalidResource, nextBackgroundColor = rg::kInvalidResource;
  // The chunked mesh as imported (render/layer_mesh.h MeshResources), for the other passes that draw it.
  rg::ResourceId meshVertices = rg::kInvalidResource, meshIndices = rg::kInvalidResource, meshRoots = rg::kInvalidResource;
};
// Adds "layers: frame constants", "layers: foliage" and "layers: background" with the layer
// images imported (and bound) in desc.restUse, and with spread re-slicing "layers: spread slice"
// and "layers: cross-fade" (the next set imported in FragmentSampled). The passes draw only when
// updateLayerView planned that work for this frame.
Status addLayerPasses(LayeredVegetation& lv, rg::RenderGraph& graph, LayerResources* out);

}  // namespace canopy
