#include "render/layer_instances.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "engine/device.h"
#include <memory>

namespace canopy {
namespace {

void corners(const glm::mat4& m, const glm::vec3& lo, const glm::vec3& hi, glm::vec4 out[8]) {
  for (int k = 0; k < 8; ++k)
    out[k] = m * glm::vec4((k & 1) ? hi.x : lo.x, (k & 2) ? hi.y : lo.y, (k & 4) ? hi.z : lo.z, 1.0f);
}

}  // namespace

Status setInstances(Device& d, PreparedList* uploads, const InstanceInputs& in, const std::vector<MeshSpecies>& species,
                    LayerInstances* out) {
  const std::vector<glm::mat4>& models = in.models;
  const std::vector<glm::vec3>& tints = in.tints;
  const std::vector<float>& windPhases = in.windPhases;
  if (models.empty()) return Status::error(Result::InvalidArgument, "instances: at least one instance is needed");
  if (species.empty()) return Status::error("instances: no species");
  auto sizeOf = [&](size_t n, const char* what) -> Status {
    if (n == 0 || n == models.size()) return Status();
    return Status::error(Result::InvalidArgument, "instances: " + std::to_string(n) + " " + what + " for " +
                                                      std::to_string(models.size()) + " instances");
  };
  CANOPY_TRY(sizeOf(tints.size(), "tints"));
  CANOPY_TRY(sizeOf(windPhases.size(), "wind phases"));
  CANOPY_TRY(sizeOf(in.species.size(), "species indices"));
  // Grouped by species, each group in the host's order (a stable counting sort).
  std::vector<uint32_t> first(species.size() + 1, 0);
  for (size_t i = 0; i < in.species.size(); ++i) {
    if (in.species[i] >= species.size())
      return Status::error(Result::InvalidArgument, "CanopyInstance #" + std::to_string(i) + ".species = " +
                                                        std::to_string(in.species[i]) + " names no species (0.." +
                                                        std::to_string(species.size() - 1) + ")");
    first[in.species[i] + 1]++;
  }
  if (in.species.empty()) first[1] = uint32_t(models.size());
  for (size_t s = 1; s < first.size(); ++s) first[s] += first[s - 1];
  LayerInstances next;
  next.models.resize(models.size());
  next.table.resize(models.size());
  next.species.resize(models.size());
  next.hostIndex.resize(models.size());
  for (size_t s = 0; s < species.size(); ++s) next.speciesCopies.push_back({first[s], first[s + 1] - first[s]});
  next.boundsMin = glm::vec3(INFINITY);
  next.boundsMax = glm::vec3(-INFINITY);
  for (size_t i = 0; i < models.size(); ++i) {
    const glm::mat4& m = models[i];
    bool finite = true;
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) finite = finite && std::isfinite(m[c][r]);
    const float det = glm::determinant(glm::mat3(m));
    if (!finite || !(std::abs(det) > 1e-12f) || m[0][3] != 0.0f || m[1][3] != 0.0f || m[2][3] != 0.0f || m[3][3] != 1.0f)
      return Status::error(Result::InvalidArgument,
                           "CanopyInstance #" + std::to_string(i) + ".transform: not a finite, invertible affine matrix (determinant of "
                           "its linear part " + std::to_string(det) + ", bottom row must be 0 0 0 1)");
    const glm::vec3 tint = tints.empty() ? glm::vec3(1.0f) : tints[i];
    if (!std::isfinite(tint.x) || !std::isfinite(tint.y) || !std::isfinite(tint.z) || glm::min(tint.x, glm::min(tint.y, tint.z)) < 0.0f ||
        glm::max(tint.x, glm::max(tint.y, tint.z)) > 16.0f)
      return Status::error(Result::InvalidArgument, "CanopyInstance #" + std::to_string(i) + ".tint is outside [0, 16] per channel");
    const float phase = windPhases.empty() ? 0.0f : windPhases[i];
    if (!std::isfinite(phase) || std::abs(phase) > 3600.0f)
      return Status::error(Result::InvalidArgument, "CanopyInstance #" + std::to_string(i) + ".windPhase = " + std::to_string(phase) +
                                                        " s is outside [-3600, 3600]");
    const uint32_t sp = in.species.empty() ? 0u : in.species[i];
    const uint32_t at = first[sp]++;
    const glm::mat3 normal = glm::transpose(glm::inverse(glm::mat3(m)));
    gpu::LayerInstance& t = next.table[at];
    next.models[at] = m;
    next.species[at] = sp;
    next.hostIndex[at] = uint32_t(i);
    t.model = m;
    t.normalColumn0 = glm::vec4(normal[0], 0.0f);
    t.normalColumn1 = glm::vec4(normal[1], 0.0f);
    t.normalColumn2 = glm::vec4(normal[2], 0.0f);
    t.tint = glm::vec4(tint, phase);
    glm::vec4 c[8];
    corners(m, species[sp].boundsMin, species[sp].boundsMax, c);
    for (const glm::vec4& p : c) {
      next.boundsMin = glm::min(next.boundsMin, glm::vec3(p));
      next.boundsMax = glm::max(next.boundsMax, glm::vec3(p));
    }
  }
  next.identity = models.size() == 1 && models[0] == glm::mat4(1.0f) && glm::vec3(next.table[0].tint) == glm::vec3(1.0f);
  const VkDeviceSize bytes = VkDeviceSize(next.table.size()) * sizeof(gpu::LayerInstance);
  CANOPY_TRY(createBuffer(d, bytes, VK_BUFFER_USAGE_VERTEX_BUFFER_BIT | VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT,
                          MemoryUsage::DeviceLocal,
                          &next.buffer, "layers: instances"));
  // A new buffer each time: frames in flight keep reading the old one, released after them.
  if (void* direct = hostCoherentPointer(d, next.buffer.allocation)) {
    std::memcpy(direct, next.table.data(), bytes);
  } else {
    // Read as the layer and per-vertex draws' instance stream, by the per-vertex motion kernel and by
    // the impostor draws' both stages.
    const rg::State readers{VK_PIPELINE_STAGE_2_VERTEX_ATTRIBUTE_INPUT_BIT | VK_PIPELINE_STAGE_2_COMPUTE_SHADER_BIT |
                                VK_PIPELINE_STAGE_2_VERTEX_SHADER_BIT | VK_PIPELINE_STAGE_2_FRAGMENT_SHADER_BIT,
                            VK_ACCESS_2_VERTEX_ATTRIBUTE_READ_BIT | VK_ACCESS_2_SHADER_STORAGE_READ_BIT, VK_IMAGE_LAYOUT_UNDEFINED};
    Status s = uploadBuffer(d, uploads, next.buffer, next.table.data(), bytes, readers);
    if (!s.ok()) {
      destroyBuffer(d, next.buffer);
      return s;
    }
  }
  *out = std::move(next);
  return Status();
}

void destroyInstances(Device& d, LayerInstances& instances) {
  destroyBuffer(d, instances.buffer);
  instances = LayerInstances{};
}

std::vector<InstanceRun> visibleInstanceRuns(const LayerInstances& in, const std::vector<MeshSpecies>& species,
                                             const glm::mat4& viewProj) {
  std::vector<InstanceRun> runs;
  for (uint32_t i = 0; i < in.models.size(); ++i) {
    const uint32_t sp = i < in.species.size() ? in.species[i] : 0u;
    glm::vec4 c[8];
    corners(viewProj * in.models[i], species[sp].boundsMin, species[sp].boundsMax, c);
    // Outside when every corner is beyond one of the planes -w <= x, y <= w, 0 <= z <= w.
    bool outside = false;
    for (int plane = 0; plane < 6 && !outside; ++plane) {
      bool all = true;
      for (const glm::vec4& p : c) {
        const float v = plane == 0 ? p.x + p.w : plane == 1 ? p.w - p.x : plane == 2 ? p.y + p.w : plane == 3 ? p.w - p.y
                        : plane == 4 ? p.z : p.w - p.z;
        all = all && v < 0.0f;
      }
      outside = all;
    }
    if (outside) continue;
    const bool sameSpecies = i == 0 || (i - 1 < in.species.size() ? in.species[i - 1] : 0u) == sp;
    if (!runs.empty() && runs.back().first + runs.back().count == i && sameSpecies) runs.back().count++;
    else runs.push_back({i, 1});
  }
  return runs;
}

void clipRuns(const std::vector<InstanceRun>& runs, const InstanceRun& range, std::vector<InstanceRun>* out) {
  out->clear();
  const uint64_t lo = range.first, hi = uint64_t(range.first) + range.count;
  for (const InstanceRun& r : runs) {
    const uint64_t a = std::max<uint64_t>(r.first, lo), b = std::min<uint64_t>(uint64_t(r.first) + r.count, hi);
    if (a < b) out->push_back({uint32_t(a), uint32_t(b - a)});
  }
}

}  // namespace canopy
