#pragma once
// The vegetation's placed copies (CanopyInstance; docs/design.md "Instances"): one mesh, drawn
// instanced into the layers, each copy with its model -> world transform and tint; the world
// bounds they span; which copies a camera sees, as runs of consecutive instances (one instanced
// draw per chunk and run).
#include <cstdint>
#include <vector>
#include <glm/glm.hpp>

#include "engine/memory.h"
#include "engine/status.h"
#include "engine/transfer.h"
#include "render/species.h"
#include "shared/layers.h"

namespace canopy {
struct Device;

struct InstanceRun {
  uint32_t first = 0, count = 0;  // instances [first, first + count)
};

// The copies as the host gives them (CanopyInstance): each its species' model -> world transform,
// tint and wind phase. Empty tints, windPhases, species: none (1, 0, species 0).
struct InstanceInputs {
  std::vector<glm::mat4> models;
  std::vector<glm::vec3> tints;
  std::vector<float> windPhases;
  std::vector<uint32_t> species;
};

// The copies grouped by species (docs/design.md "Species"): the table holds species 0's copies,
// then species 1's, ..., each group in the host's order, so a chunk (one species) draws the
// visible runs inside its species' range.
struct LayerInstances {
  std::vector<glm::mat4> models;              // model -> world, per instance
  std::vector<gpu::LayerInstance> table;      // what the shaders read (the draws' instance stream; the per-vertex motion kernel's binding 3)
  Buffer buffer;                              // the table on the device
  glm::vec3 boundsMin{0}, boundsMax{0};       // world bounds of every copy of the mesh's bounds
  bool identity = true;                       // one instance, the identity transform, no tint
  std::vector<uint32_t> species;              // per instance: its species
  std::vector<InstanceRun> speciesCopies;     // per species: its instances (count 0: none)
  std::vector<uint32_t> hostIndex;            // per instance: its index in the host's list
};

// The table and world bounds of the copies `in` of `species` (their model-space bounds), grouped
// by species, into `out` (which holds no buffer: the caller releases an old one after the frames in
// flight); refuses a non-finite or singular transform, a tint or phase out of range or a species
// past the list, naming the instance.
Status setInstances(Device& device, PreparedList* uploads, const InstanceInputs& in, const std::vector<MeshSpecies>& species,
                    LayerInstances* out);
void destroyInstances(Device& device, LayerInstances& instances);

// The instances whose transformed species bounds meet the frustum of `viewProj` (clip space, Vulkan
// depth 0..1), as runs of consecutive indices (a run never spans two species).
std::vector<InstanceRun> visibleInstanceRuns(const LayerInstances& instances, const std::vector<MeshSpecies>& species,
                                             const glm::mat4& viewProj);
// The part of `runs` inside `range` (a species' copies).
void clipRuns(const std::vector<InstanceRun>& runs, const InstanceRun& range, std::vector<InstanceRun>* out);

}  // namespace canopy
