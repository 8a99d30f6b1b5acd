#include "engine/pass_counters.h"

#include "engine/device.h"

namespace canopy {

namespace {
// The statistics asked for, in the order the query returns them (bit order).
const VkQueryPipelineStatisticFlags kStatistics =
    VK_QUERY_PIPELINE_STATISTIC_VERTEX_SHADER_INVOCATIONS_BIT | VK_QUERY_PIPELINE_STATISTIC_CLIPPING_PRIMITIVES_BIT |
    VK_QUERY_PIPELINE_STATISTIC_FRAGMENT_SHADER_INVOCATIONS_BIT | VK_QUERY_PIPELINE_STATISTIC_COMPUTE_SHADER_INVOCATIONS_BIT;
}  // namespace

Status PassCounters::init(Device& d, uint32_t maxPasses) {
  if (!d.pipelineStatistics)
    return Status::error(Result::UnsupportedDevice, "pass counters: the device was made without the pipelineStatisticsQuery feature");
  VkQueryPoolCreateInfo ci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  ci.queryType = VK_QUERY_TYPE_PIPELINE_STATISTICS;
  ci.queryCount = maxPasses;
  ci.pipelineStatistics = kStatistics;
  CANOPY_VK(d.vk.CreateQueryPool(d.device, &ci, d.allocationCallbacks, &pool_));
  capacity_ = maxPasses;
  vk_ = &d.vk;
  return Status();
}

void PassCounters::destroy(Device& d) {
  if (pool_) d.vk.DestroyQueryPool(d.device, pool_, d.allocationCallbacks);
  pool_ = VK_NULL_HANDLE;
}

void PassCounters::reset(VkCommandBuffer cmd) {
  vk_->CmdResetQueryPool(cmd, pool_, 0, capacity_);
  used_ = 0;
  open_ = ~0u;
  passes_.clear();
}

void PassCounters::begin(VkCommandBuffer cmd, const std::string& name, uint64_t bytesRead, uint64_t bytesWritten) {
  if (used_ >= capacity_ || open_ != ~0u) return;  // over capacity: the pass is simply not counted
  open_ = used_++;
  PassCounts p;
  p.name = name;
  p.bytesRead = bytesRead;
  p.bytesWritten = bytesWritten;
  passes_.push_back(p);
  vk_->CmdBeginQuery(cmd, pool_, open_, 0);
}

void PassCounters::end(VkCommandBuffer cmd) {
  if (open_ == ~0u) return;
  vk_->CmdEndQuery(cmd, pool_, open_);
  open_ = ~0u;
}

Status PassCounters::read(Device& d, std::vector<PassCounts>* out) {
  *out = passes_;
  if (used_ == 0) return Status();
  std::vector<uint64_t> v(size_t(used_) * 4);
  CANOPY_VK(d.vk.GetQueryPoolResults(d.device, pool_, 0, used_, v.size() * sizeof(uint64_t), v.data(), 4 * sizeof(uint64_t),
                                     VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  for (uint32_t i = 0; i < used_; ++i) {
    PassCounts& p = (*out)[i];
    p.vertexInvocations = v[4 * i];
    p.clippingPrimitives = v[4 * i + 1];
    p.fragmentInvocations = v[4 * i + 2];
    p.computeInvocations = v[4 * i + 3];
  }
  return Status();
}

}  // namespace canopy
