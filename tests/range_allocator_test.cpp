#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "engine/range_allocator.h"

using canopy::RangeAllocator;

TEST(RangeAllocator, AlignsAndCoalesces) {
  RangeAllocator a(1024);
  uint64_t x = a.allocate(10, 1);
  uint64_t y = a.allocate(100, 256);
  uint64_t z = a.allocate(50, 16);
  EXPECT_EQ(x, 0u);
  EXPECT_EQ(y % 256, 0u);
  EXPECT_EQ(z % 16, 0u);
  EXPECT_EQ(a.allocate(2000, 1), RangeAllocator::kInvalid);
  a.free(y);
  a.free(x);
  a.free(z);
  EXPECT_TRUE(a.empty());
  EXPECT_EQ(a.freeRangeCount(), 1u);
  EXPECT_EQ(a.allocate(1024, 1), 0u);
}

TEST(RangeAllocator, RejectsBadAlignment) {
  RangeAllocator a(1024);
  EXPECT_EQ(a.allocate(8, 3), RangeAllocator::kInvalid);
  EXPECT_EQ(a.allocate(0, 4), RangeAllocator::kInvalid);
}

// Random allocate/free never yields overlapping live ranges and always returns to one range.
TEST(RangeAllocator, RandomisedNoOverlap) {
  RangeAllocator a(1 << 20);
  std::mt19937 rng(42);
  struct Live { uint64_t off, size; };
  std::vector<Live> live;
  for (int it = 0; it < 5000; ++it) {
    if (live.empty() || rng() % 3) {
      uint64_t size = 1 + rng() % 5000, align = uint64_t(1) << (rng() % 9);
      uint64_t off = a.allocate(size, align);
      if (off == RangeAllocator::kInvalid) continue;
      ASSERT_EQ(off % align, 0u);
      ASSERT_LE(off + size, a.capacity());
      for (const Live& l : live) ASSERT_TRUE(off + size <= l.off || l.off + l.size <= off) << "overlap";
      live.push_back({off, size});
    } else {
      size_t i = rng() % live.size();
      a.free(live[i].off);
      live.erase(live.begin() + long(i));
    }
  }
  for (const Live& l : live) a.free(l.off);
  EXPECT_TRUE(a.empty());
  EXPECT_EQ(a.freeRangeCount(), 1u);
}
