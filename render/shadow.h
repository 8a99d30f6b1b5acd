#pragma once
// The vegetation's shadow for the host's light (issue 54; docs/design.md "Shadows"; the contract:
// docs/embedding.md "Shadows"): recordCanopyShadow draws the foliage mesh and the trunks into the
// host's depth image from the host's light view-projection, depth only, the leaves alpha-tested and
// each displaced by the warp its layer has on screen this frame (shaders/shadow.vert), so the
// caster sways as the leaves the camera shows. One graph per set of host image and conventions, as
// recordCanopy keeps them; per cascade an update interval.
#include <array>
#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include <canopy/canopy.h>

#include "compute/dynamics.h"
#include "engine/graphics_pipeline.h"
#include "engine/memory.h"
#include "engine/render_graph.h"
#include "render/layers.h"
#include "shared/shadow.h"

namespace canopy {

constexpr uint32_t kMaxShadowCascades = 8;
constexpr uint32_t kMaxShadowInterval = 64;

struct ShadowGraph {
  std::shared_ptr<rg::RenderGraph> graph;  // compiled and realized
  CanopyShadowInputs inputs;               // the image, size and conventions it was built for
  uint64_t generation = 0;                 // the context's resource generation at build
  uint64_t lastUse = 0;
};

struct ShadowCaster {
  Device* device = nullptr;
  Buffer frame;                     // the visible placement's gpu::LayerFrame, then gpu::ShadowFrame at shadowOffset
  VkDeviceSize shadowOffset = 0;
  struct Pipeline {
    VkFormat format = VK_FORMAT_UNDEFINED;
    bool reverseZ = false;
    GraphicsPipeline pipeline;
  };
  std::deque<Pipeline> pipelines;   // per depth format and convention met (graphs hold their addresses)
  std::vector<ShadowGraph> graphs;  // least recently used first out beyond kMaxShadowGraphs
  uint64_t uses = 0;
  std::array<uint64_t, kMaxShadowCascades> calls{};  // per cascade: the calls so far (its update interval)
  // This call's, read by the graph's passes when recorded.
  gpu::LayerFrame layerFrame{};
  gpu::ShadowFrame shadowFrame{};
  std::vector<InstanceRun> runs;    // the copies the light sees
  bool drawNow = false;
  uint64_t updates = 0, skips = 0;
};

// What the caster reads of the context: the vegetation (mesh, copies, visible placement), this
// frame's dynamics (AnimFrame and displacement) and whether the layers are animated at all.
struct ShadowSources {
  LayeredVegetation* layers = nullptr;
  LayerDynamics* dynamics = nullptr;
  bool displaced = true;            // false: the still mesh (the per-vertex baseline's frames)
  uint64_t generation = 0;          // the context's resource generation (graphs of older ones are dropped)
};

// Checks the inputs (image declaration, format, size, matrix, cascade and interval ranges); the
// message names the field and what is allowed.
Status checkShadowInputs(const CanopyShadowInputs& inputs);
// Records the shadow into `cmd` (or, between updates of its cascade, only the image's transition
// from `current` to `final`); *updated: whether the vegetation was drawn.
Status recordShadow(ShadowCaster& caster, const ShadowSources& sources, VkCommandBuffer cmd, const CanopyShadowInputs& inputs,
                    bool* updated);
// Releases the caster's objects (the caller defers it past the frames in flight, as the context's
// other parts).
void destroyShadowCaster(ShadowCaster& caster);

}  // namespace canopy
