#include "engine/memory.h"

#include <algorithm>

#include "engine/device.h"

namespace canopy {
namespace {

void countLive(Allocator& a, VkDeviceSize bytes) {
  a.allocationCount++;
  a.liveBytes += bytes;
  a.peakLiveBytes = std::max(a.peakLiveBytes, a.liveBytes);
}

Status findMemoryType(const Device& d, uint32_t typeBits, MemoryUsage usage, uint32_t* out) {
  // Preference order per usage; the first memory type matching any entry wins.
  std::vector<VkMemoryPropertyFlags> prefs;
  const VkMemoryPropertyFlags HV = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT, HC = VK_MEMORY_PROPERTY_HOST_COHERENT_BIT,
                              DL = VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, CA = VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
  switch (usage) {
    case MemoryUsage::DeviceLocal: prefs = {DL, 0}; break;
    case MemoryUsage::Upload: prefs = {HV | HC | DL, HV | HC}; break;
    case MemoryUsage::Readback: prefs = {HV | HC | CA, HV | HC}; break;
  }
  for (VkMemoryPropertyFlags want : prefs)
    for (uint32_t i = 0; i < d.memoryProperties.memoryTypeCount; ++i)
      if ((typeBits & (1u << i)) && (d.memoryProperties.memoryTypes[i].propertyFlags & want) == want) {
        *out = i;
        return Status();
      }
  return Status::error("no memory type fits (type bits 0x" + std::to_string(typeBits) + ")");
}

// The host's allocator (public DeviceMemoryAllocator): Canopy says what it needs and prefers.
Status allocateFromHost(Device& d, const VkMemoryRequirements& req, MemoryUsage usage, Allocation* out) {
  const VkMemoryPropertyFlags HV = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT, HC = VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  const VkMemoryPropertyFlags required = usage == MemoryUsage::DeviceLocal ? 0 : HV | HC;
  const VkMemoryPropertyFlags preferred = usage == MemoryUsage::DeviceLocal ? VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT
                                          : usage == MemoryUsage::Readback ? VK_MEMORY_PROPERTY_HOST_CACHED_BIT
                                                                           : VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT;
  DeviceMemoryRange r;
  const VkResult vr = d.hostAllocator.allocate(d.hostAllocator.user, req, required, preferred, &r);
  if (vr != VK_SUCCESS) return vkError("DeviceMemoryAllocator::allocate", vr);
  if (!r.memory || r.size < req.size || (req.alignment && r.offset % req.alignment) ||
      r.memoryTypeIndex >= d.memoryProperties.memoryTypeCount || !(req.memoryTypeBits & (1u << r.memoryTypeIndex)) ||
      (required && !r.mapped)) {
    d.hostAllocator.free(d.hostAllocator.user, r);
    return Status::error(Result::InvalidArgument,
                         "DeviceMemoryAllocator::allocate returned a range that does not fit the request (no memory, "
                         "too small, misaligned, a memory type outside the allowed bits, or not mapped for host access)");
  }
  *out = Allocation{};
  out->memory = r.memory;
  out->offset = r.offset;
  out->size = r.size;
  out->mapped = r.mapped;
  out->typeIndex = r.memoryTypeIndex;
  out->host = true;
  out->hostHandle = r.hostHandle;
  countLive(*d.allocator, r.size);
  return Status();
}

Status allocate(Device& d, const VkMemoryRequirements& req, MemoryUsage usage, bool linear, Allocation* out) {
  if (d.hostAllocator.allocate) return allocateFromHost(d, req, usage, out);
  Allocator& a = *d.allocator;
  uint32_t type = 0;
  CANOPY_TRY(findMemoryType(d, req.memoryTypeBits, usage, &type));
  for (auto& b : a.blocks) {
    if (b->typeIndex != type || b->linear != linear) continue;
    uint64_t off = b->ranges.allocate(req.size, req.alignment);
    if (off == RangeAllocator::kInvalid) continue;
    *out = {b.get(), b->memory, off, req.size, b->mapped ? static_cast<char*>(b->mapped) + off : nullptr, type};
    countLive(a, req.size);
    return Status();
  }
  auto block = std::make_unique<MemoryBlock>();
  VkDeviceSize size = std::max(a.blockSize, req.size);
  VkMemoryAllocateInfo ai{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  ai.allocationSize = size;
  ai.memoryTypeIndex = type;
  VkResult r = d.vk.AllocateMemory(d.device, &ai, d.allocationCallbacks, &block->memory);
  if (r != VK_SUCCESS)
    return vkError("vkAllocateMemory", r).context("allocating a " + std::to_string(size >> 20) + " MiB memory block");
  block->typeIndex = type;
  block->linear = linear;
  block->ranges = RangeAllocator(size);
  if (d.memoryProperties.memoryTypes[type].propertyFlags & VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT)
    {
    r = d.vk.MapMemory(d.device, block->memory, 0, VK_WHOLE_SIZE, 0, &block->mapped);
    if (r != VK_SUCCESS) {
      d.vk.FreeMemory(d.device, block->memory, d.allocationCallbacks);
      return vkError("vkMapMemory", r);
    }
  }
  uint64_t off = block->ranges.allocate(req.size, req.alignment);
  *out = {block.get(), block->memory, off, req.size, block->mapped ? static_cast<char*>(block->mapped) + off : nullptr,
          type};
  a.blocks.push_back(std::move(block));
  a.blockBytes += size;
  a.peakBlockBytes = std::max(a.peakBlockBytes, a.blockBytes);
  countLive(a, req.size);
  return Status();
}

void release(Device& d, Allocation& al) {
  if (al.host) {
    d.hostAllocator.free(d.hostAllocator.user, {al.memory, al.offset, al.size, al.mapped, al.typeIndex, al.hostHandle});
    d.allocator->allocationCount--;
    d.allocator->liveBytes -= al.size;
    al = Allocation{};
    return;
  }
  if (!al.block) return;
  al.block->ranges.free(al.offset);
  d.allocator->allocationCount--;
  d.allocator->liveBytes -= al.size;
  al = Allocation{};
}

}  // namespace

Status initAllocator(Device&, Allocator*) { return Status(); }

void destroyAllocator(Device& d, Allocator& a) {
  for (auto& b : a.blocks) {
    if (b->mapped) d.vk.UnmapMemory(d.device, b->memory);
    d.vk.FreeMemory(d.device, b->memory, d.allocationCallbacks);
  }
  a.blocks.clear();
  a.blockBytes = 0;
}

VkImageAspectFlags aspectOf(VkFormat f) {
  switch (f) {
    case VK_FORMAT_D16_UNORM:
    case VK_FORMAT_D32_SFLOAT:
    case VK_FORMAT_X8_D24_UNORM_PACK32: return VK_IMAGE_ASPECT_DEPTH_BIT;
    case VK_FORMAT_D16_UNORM_S8_UINT:
    case VK_FORMAT_D24_UNORM_S8_UINT:
    case VK_FORMAT_D32_SFLOAT_S8_UINT: return VK_IMAGE_ASPECT_DEPTH_BIT | VK_IMAGE_ASPECT_STENCIL_BIT;
    default: return VK_IMAGE_ASPECT_COLOR_BIT;
  }
}

Status createBuffer(Device& d, VkDeviceSize size, VkBufferUsageFlags usage, MemoryUsage memory, Buffer* out,
                    const char* debugName) {
  *out = Buffer{};
  if (size == 0) return Status::error(std::string("buffer '") + (debugName ? debugName : "?") + "' has size 0");
  VkBufferCreateInfo ci{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  ci.size = size;
  ci.usage = usage;
  ci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  CANOPY_VK(d.vk.CreateBuffer(d.device, &ci, d.allocationCallbacks, &out->buffer));
  VkMemoryRequirements req;
  d.vk.GetBufferMemoryRequirements(d.device, out->buffer, &req);
  Status s = allocate(d, req, memory, true, &out->allocation);
  if (s.ok()) {
    VkResult r = d.vk.BindBufferMemory(d.device, out->buffer, out->allocation.memory, out->allocation.offset);
    if (r != VK_SUCCESS) s = vkError("vkBindBufferMemory", r);
  }
  if (!s.ok()) {
    destroyBuffer(d, *out);
    return s.context(std::string("creating buffer '") + (debugName ? debugName : "?") + "'");
  }
  out->size = size;
  setDebugName(d, VK_OBJECT_TYPE_BUFFER, uint64_t(out->buffer), debugName);
  return Status();
}

void destroyBufferLater(Device& d, Buffer& b) {
  if (!b.buffer) return;
  auto held = std::make_shared<Buffer>(b);
  Device* dev = &d;
  deferRelease(d, [dev, held] { destroyBuffer(*dev, *held); });
  b = Buffer{};
}

void destroyBuffer(Device& d, Buffer& b) {
  if (b.buffer) d.vk.DestroyBuffer(d.device, b.buffer, d.allocationCallbacks);
  release(d, b.allocation);
  b = Buffer{};
}

void* hostCoherentPointer(const Device& d, const Allocation& a) {
  if (!a.mapped) return nullptr;
  const VkMemoryPropertyFlags want = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  return (d.memoryProperties.memoryTypes[a.typeIndex].propertyFlags & want) == want ? a.mapped : nullptr;
}

ImageDesc descOf(const Image& img) {
  ImageDesc d;
  d.format = img.format;
  d.width = img.extent.width;
  d.height = img.extent.height;
  d.layers = img.layers;
  return d;
}

Status createImage(Device& d, const ImageDesc& desc, Image* out, const char* debugName) {
  *out = Image{};
  const std::string name = debugName ? debugName : "?";
  if (desc.width == 0 || desc.height == 0 || desc.layers == 0)
    return Status::error("image '" + name + "' has a zero extent");
  VkImageCreateInfo ci{VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO};
  ci.imageType = VK_IMAGE_TYPE_2D;
  ci.format = desc.format;
  ci.extent = {desc.width, desc.height, 1};
  ci.mipLevels = 1;
  ci.arrayLayers = desc.layers;
  ci.samples = VK_SAMPLE_COUNT_1_BIT;
  ci.tiling = VK_IMAGE_TILING_OPTIMAL;
  ci.usage = desc.usage;
  ci.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  CANOPY_VK(d.vk.CreateImage(d.device, &ci, d.allocationCallbacks, &out->image));
  VkMemoryRequirements req;
  d.vk.GetImageMemoryRequirements(d.device, out->image, &req);
  Status s = allocate(d, req, MemoryUsage::DeviceLocal, false, &out->allocation);
  if (s.ok()) {
    VkResult r = d.vk.BindImageMemory(d.device, out->image, out->allocation.memory, out->allocation.offset);
    if (r != VK_SUCCESS) s = vkError("vkBindImageMemory", r);
  }
  out->format = desc.format;
  out->extent = ci.extent;
  out->layers = desc.layers;
  out->aspect = aspectOf(desc.format);
  if (s.ok()) {
    VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
    vi.image = out->image;
    vi.viewType = (desc.layers > 1 || desc.arrayView) ? VK_IMAGE_VIEW_TYPE_2D_ARRAY : VK_IMAGE_VIEW_TYPE_2D;
    vi.format = desc.format;
    vi.subresourceRange = {out->aspect, 0, 1, 0, desc.layers};
    VkResult r = d.vk.CreateImageView(d.device, &vi, d.allocationCallbacks, &out->view);
    if (r != VK_SUCCESS) s = vkError("vkCreateImageView", r);
  }
  if (!s.ok()) {
    destroyImage(d, *out);
    return s.context("creating image '" + name + "'");
  }
  setDebugName(d, VK_OBJECT_TYPE_IMAGE, uint64_t(out->image), debugName);
  return Status();
}

void destroyImage(Device& d, Image& img) {
  if (img.view) d.vk.DestroyImageView(d.device, img.view, d.allocationCallbacks);
  if (img.image) d.vk.DestroyImage(d.device, img.image, d.allocationCallbacks);
  release(d, img.allocation);
  img = Image{};
}

uint32_t texelBytes(VkFormat f) {
  switch (f) {
    case VK_FORMAT_R8_UNORM: return 1;
    case VK_FORMAT_D16_UNORM: return 2;
    case VK_FORMAT_R8G8B8A8_UNORM: case VK_FORMAT_R8G8B8A8_SRGB: case VK_FORMAT_B8G8R8A8_UNORM:
    case VK_FORMAT_B8G8R8A8_SRGB: case VK_FORMAT_R16G16_SFLOAT: case VK_FORMAT_R32_SFLOAT:
    case VK_FORMAT_R32_UINT: case VK_FORMAT_D32_SFLOAT: return 4;
    case VK_FORMAT_R16G16B16A16_SFLOAT: case VK_FORMAT_R32G32_SFLOAT: case VK_FORMAT_R32G32_UINT: return 8;
    case VK_FORMAT_R32G32B32A32_SFLOAT: return 16;
    default: return 0;
  }
}

}  // namespace canopy
