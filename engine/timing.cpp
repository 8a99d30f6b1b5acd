#include "engine/timing.h"

#include <algorithm>

#include "engine/device.h"

namespace canopy {

Status GpuTimer::init(Device& d, uint32_t maxPasses) {
  VkQueryPoolCreateInfo ci{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
  ci.queryType = VK_QUERY_TYPE_TIMESTAMP;
  ci.queryCount = maxPasses * 2;
  CANOPY_VK(d.vk.CreateQueryPool(d.device, &ci, d.allocationCallbacks, &pool_));
  capacity_ = maxPasses;
  vk_ = &d.vk;
  periodNs_ = d.properties.limits.timestampPeriod;
  mask_ = d.timestampValidBits >= 64 ? ~0ull : ((1ull << d.timestampValidBits) - 1);
  return Status();
}

void GpuTimer::destroy(Device& d) {
  if (pool_) d.vk.DestroyQueryPool(d.device, pool_, d.allocationCallbacks);
  pool_ = VK_NULL_HANDLE;
}

void GpuTimer::reset(VkCommandBuffer cmd) {
  vk_->CmdResetQueryPool(cmd, pool_, 0, capacity_ * 2);
  used_ = 0;
  open_ = ~0u;
  names_.clear();
}

void GpuTimer::begin(VkCommandBuffer cmd, const std::string& name) {
  if (used_ >= capacity_ || open_ != ~0u) return;  // over capacity: the pass is simply not timed
  open_ = used_++;
  names_.push_back(name);
  vk_->CmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, pool_, open_ * 2);
}

void GpuTimer::end(VkCommandBuffer cmd) {
  if (open_ == ~0u) return;
  vk_->CmdWriteTimestamp(cmd, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, pool_, open_ * 2 + 1);
  open_ = ~0u;
}

Status GpuTimer::read(Device& d, std::vector<PassTiming>* out) {
  out->clear();
  if (used_ == 0) return Status();
  std::vector<uint64_t> ts(used_ * 2);
  CANOPY_VK(d.vk.GetQueryPoolResults(d.device, pool_, 0, used_ * 2, ts.size() * sizeof(uint64_t), ts.data(),
                                  sizeof(uint64_t), VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT));
  for (uint32_t i = 0; i < used_; ++i) {
    uint64_t dt = (ts[2 * i + 1] - ts[2 * i]) & mask_;
    out->push_back({names_[i], double(dt) * periodNs_ * 1e-6});
  }
  return Status();
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace canopy
