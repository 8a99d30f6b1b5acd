#pragma once
// First-fit free-list allocator over one memory block's byte range, with coalescing on free.
// Pure CPU bookkeeping (tested without a device); engine/memory.cpp puts one over each VkDeviceMemory.
#include <cstddef>
#include <cstdint>
#include <map>

namespace canopy {

class RangeAllocator {
 public:
  static constexpr uint64_t kInvalid = ~uint64_t(0);
  explicit RangeAllocator(uint64_t size = 0);
  // Returns the offset of `size` bytes aligned to `alignment` (a power of two), or kInvalid.
  uint64_t allocate(uint64_t size, uint64_t alignment);
  // Frees a range returned by allocate(); neighbouring free ranges merge.
  void free(uint64_t offset);
  uint64_t capacity() const { return capacity_; }
  uint64_t used() const { return used_; }
  size_t freeRangeCount() const { return free_.size(); }
  bool empty() const { return used_ == 0; }

 private:
  uint64_t capacity_;
  uint64_t used_ = 0;
  std::map<uint64_t, uint64_t> free_;       // offset -> size
  std::map<uint64_t, uint64_t> allocated_;  // aligned offset -> (start of the taken range)
  std::map<uint64_t, uint64_t> taken_;      // start -> size (includes alignment padding)
};

}  // namespace canopy
