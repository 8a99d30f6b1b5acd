#include "engine/range_allocator.h"

namespace canopy {

RangeAllocator::RangeAllocator(uint64_t size) : capacity_(size) {
  if (size) free_[0] = size;
}

uint64_t RangeAllocator::allocate(uint64_t size, uint64_t alignment) {
  if (size == 0 || alignment == 0 || (alignment & (alignment - 1))) return kInvalid;
  for (auto it = free_.begin(); it != free_.end(); ++it) {
    const uint64_t start = it->first, len = it->second;
    const uint64_t aligned = (start + alignment - 1) & ~(alignment - 1);
    if (aligned < start || aligned - start > len || len - (aligned - start) < size) continue;
    const uint64_t end = aligned + size;
    free_.erase(it);
    // Alignment padding stays with the allocation (freed together); the tail returns to the list.
    if (end < start + len) free_[end] = start + len - end;
    taken_[start] = end - start;
    allocated_[aligned] = start;
    used_ += end - start;
    return aligned;
  }
  return kInvalid;
}

void RangeAllocator::free(uint64_t offset) {
  auto a = allocated_.find(offset);
  if (a == allocated_.end()) return;
  uint64_t start = a->second;
  allocated_.erase(a);
  auto t = taken_.find(start);
  uint64_t len = t->second;
  taken_.erase(t);
  used_ -= len;
  auto next = free_.lower_bound(start);
  if (next != free_.end() && next->first == start + len) {
    len += next->second;
    next = free_.erase(next);
  }
  if (next != free_.begin()) {
    auto prev = std::prev(next);
    if (prev->first + prev->second == start) {
      prev->second += len;
      return;
    }
  }
  free_[start] = len;
}

}  // namespace canopy
