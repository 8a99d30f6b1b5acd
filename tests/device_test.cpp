// Device selection, the sub-allocator on a real device, and staging upload/readback.
#include <cstring>
#include <numeric>

#include "engine/memory.h"
#include "engine/transfer.h"
#include "tests/gpu_test.h"
#include "tools/own_device.h"

using namespace canopy;

namespace {
class DeviceCore : public test::GpuTest {};
}

TEST(DeviceSelection, UnknownNameIsAClearError) {
  DeviceDesc desc;
  desc.preferredDevice = "no-such-gpu-xyz";
  Device d;
  Status s = createDevice(desc, &d);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("no-such-gpu-xyz"), std::string::npos) << s.message();
  destroyDevice(d);
}

TEST_F(DeviceCore, ManyBuffersShareOneMemoryBlock) {
  const size_t before = dev.allocator->blocks.size();
  std::vector<Buffer> bufs(200);
  for (auto& b : bufs)
    ASSERT_TRUE(createBuffer(dev, 4096, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, MemoryUsage::DeviceLocal, &b).ok());
  EXPECT_LE(dev.allocator->blocks.size(), before + 1) << "sub-allocation should not allocate memory per buffer";
  EXPECT_EQ(dev.allocator->allocationCount, bufs.size());
  // Issue 16's memory statistics: the live bytes are the sub-allocations' sizes, the peak keeps
  // their highest total, the blocks cover them.
  uint64_t sum = 0;
  for (auto& b : bufs) sum += b.allocation.size;
  EXPECT_EQ(dev.allocator->liveBytes, sum);
  EXPECT_GE(dev.allocator->peakLiveBytes, sum);
  EXPECT_GE(dev.allocator->blockBytes, sum);
  for (auto& b : bufs) destroyBuffer(dev, b);
  EXPECT_EQ(dev.allocator->allocationCount, 0u);
  EXPECT_EQ(dev.allocator->liveBytes, 0u);
  EXPECT_GE(dev.allocator->peakLiveBytes, sum);
}

TEST_F(DeviceCore, UploadReadbackRoundTrip) {
  std::vector<uint32_t> data(10000);
  std::iota(data.begin(), data.end(), 17u);
  Buffer b;
  ASSERT_TRUE(createBuffer(dev, data.size() * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_DST_BIT |
                           VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUsage::DeviceLocal, &b).ok());
  const rg::State st = rg::stateOf(rg::Use::ComputeStorageRead);
  ASSERT_TRUE(uploadBuffer(dev, nullptr, b, data.data(), data.size() * 4, st).ok());
  std::vector<uint32_t> back(data.size(), 0);
  ASSERT_TRUE(readbackBuffer(dev, b, back.data(), back.size() * 4, st).ok());
  EXPECT_EQ(back, data);
  Status s = uploadBuffer(dev, nullptr, b, data.data(), data.size() * 4, st, 8);
  EXPECT_FALSE(s.ok()) << "an upload past the end must be refused";
  destroyBuffer(dev, b);
}
