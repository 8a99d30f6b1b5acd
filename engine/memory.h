#pragma once
// Buffers and images backed by the host's DeviceMemoryAllocator when it gave one, else by a small
// sub-allocator: memory comes in large blocks (one
// vkAllocateMemory per block, not per resource), split by a RangeAllocator. Linear (buffers) and
// optimal-tiling (images) resources never share a block, so bufferImageGranularity cannot bite.
#include <memory>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/range_allocator.h"
#include "engine/status.h"

namespace canopy {

struct Device;

struct MemoryBlock {
  VkDeviceMemory memory = VK_NULL_HANDLE;
  uint32_t typeIndex = 0;
  bool linear = true;
  void* mapped = nullptr;  // persistently mapped when host-visible
  RangeAllocator ranges;
};

struct Allocator {
  std::vector<std::unique_ptr<MemoryBlock>> blocks;
  VkDeviceSize blockSize = 64ull << 20;  // a larger request gets a block of its own size
  uint64_t allocationCount = 0;          // live sub-allocations (for stats/tests)
  // Bytes of the live sub-allocations (the host's allocator included) and of Canopy's own blocks,
  // now and at their highest since the device was created (issue 16: peak device memory).
  uint64_t liveBytes = 0, peakLiveBytes = 0;
  uint64_t blockBytes = 0, peakBlockBytes = 0;
};

struct Allocation {
  MemoryBlock* block = nullptr;            // Canopy's sub-allocator; null for a host allocation
  VkDeviceMemory memory = VK_NULL_HANDLE;  // what the resource is bound to
  VkDeviceSize offset = 0;
  VkDeviceSize size = 0;
  void* mapped = nullptr;  // host pointer when the memory is host-visible, else nullptr
  uint32_t typeIndex = 0;
  bool host = false;       // from the host's DeviceMemoryAllocator
  uint64_t hostHandle = 0;
};

enum class MemoryUsage {
  DeviceLocal,  // GPU-only data; may still be host-visible on UMA/CPU devices
  Upload,       // host writes, GPU reads (staging, per-frame constants)
  Readback,     // GPU writes, host reads
};

struct Buffer {
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceSize size = 0;
  Allocation allocation;
};

struct Image {
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;  // 2D, or 2D array when layers > 1
  VkFormat format = VK_FORMAT_UNDEFINED;
  VkExtent3D extent{};
  uint32_t layers = 1;
  VkImageAspectFlags aspect = VK_IMAGE_ASPECT_COLOR_BIT;
  Allocation allocation;
};

struct ImageDesc {
  VkFormat format = VK_FORMAT_R8G8B8A8_UNORM;
  uint32_t width = 1, height = 1, layers = 1;
  VkImageUsageFlags usage = VK_IMAGE_USAGE_STORAGE_BIT;
  bool arrayView = false;  // create a 2D_ARRAY view even for one layer
};

Status initAllocator(Device& device, Allocator* allocator);
void destroyAllocator(Device& device, Allocator& allocator);

Status createBuffer(Device& device, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUsage memory, Buffer* out,
                    const char* debugName = nullptr);
void destroyBuffer(Device& device, Buffer& buffer);
// Destroys `buffer` once no frame in flight can read it (engine/device.h deferRelease) and empties it.
void destroyBufferLater(Device& device, Buffer& buffer);

Status createImage(Device& device, const ImageDesc& desc, Image* out, const char* debugName = nullptr);
void destroyImage(Device& device, Image& image);

// The allocation's host pointer when its memory is HOST_VISIBLE and HOST_COHERENT (a CPU driver,
// UMA or ReBAR memory), so data can be written in place without a staging copy; else nullptr.
void* hostCoherentPointer(const Device& device, const Allocation& allocation);

// The description an existing image would be created from (format, extent, layers), e.g. to import
// it into a render graph.
ImageDesc descOf(const Image& image);

// Bytes per texel of the uncompressed formats Canopy uses (0 for any other format).
uint32_t texelBytes(VkFormat format);

// Aspect flags implied by a format (depth/stencil formats vs colour).
VkImageAspectFlags aspectOf(VkFormat format);

}  // namespace canopy
