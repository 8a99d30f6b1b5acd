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
#include "shared/layers.h"

namespace canopy {
struct Device;

struct InstanceRun {
  uint32_t first = 0, count = 0;  // instances [first, first + count)
};

struct LayerInstances {
  std::vector<glm::mat4> models;              // model -> world, per instance
  std::vector<gpu::LayerInstance> table;      // what the shaders read (the draws' instance stream; the per-vertex motion kernel's binding 3)
  Buffer buffer;                              // the table on the device
  glm::vec3 boundsMin{0}, boundsMax{0};       // world bounds of every copy of the mesh's bounds
  bool identity = true;                       // one instance, the identity transform, no tint
};

// The table and world bounds for `models` (and `tints` and `windPhases`, each empty: none) of a mesh bounded by
// [meshMin, meshMax], into `out` (which holds no buffer: the caller releases an old one after the
// frames in flight); refuses a non-finite or singular transform, naming the instance.
Status setInstances(Device& device, PreparedList* uploads, const std::vector<glm::mat4>& models,
                    const std::vector<glm::vec3>& tints, const std::vector<float>& windPhases, const glm::vec3& meshMin,
                    const glm::vec3& meshMax, LayerInstances* out);
void destroyInstances(Device& device, LayerInstances& instances);

// The instances whose transformed mesh bounds meet the frustum of `viewProj` (clip space, Vulkan
// depth 0..1), as runs of consecutive indices.
std::vector<InstanceRun> visibleInstanceRuns(const LayerInstances& instances, const glm::vec3& meshMin, const glm::vec3& meshMax,
                                             const glm::mat4& viewProj);

}  // namespace canopy
