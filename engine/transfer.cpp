#include "engine/transfer.h"

#include <cstring>

#include "engine/device.h"

namespace canopy {
namespace {

const rg::State kHostWritten{VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_WRITE_BIT};
const rg::State kHostRead{VK_PIPELINE_STAGE_2_HOST_BIT, VK_ACCESS_2_HOST_READ_BIT};

Status runGraph(Device& d, rg::RenderGraph& g) {
  CANOPY_TRY(g.compile());
  CANOPY_TRY(g.realize(d));
  Status s = submitAndWait(d, [&](VkCommandBuffer cmd) { return g.record(cmd); });
  g.release(d);
  return s;
}

}  // namespace

Status submitOrDefer(Device& d, PreparedWork work, PreparedList* deferred) {
  CANOPY_TRY(work.graph->compile());
  CANOPY_TRY(work.graph->realize(d));
  if (d.deferUploads && deferred) {
    deferred->push_back(std::move(work));
    return Status();
  }
  Status s = submitAndWait(d, [&](VkCommandBuffer cmd) { return work.graph->record(cmd); });
  work.graph->release(d);
  for (Buffer& b : work.staging) destroyBuffer(d, b);
  return s;
}

Status flushPreparedWork(Device& d, PreparedList& list, VkCommandBuffer cmd) {
  Status s;
  for (PreparedWork& w : list) {
    if (s.ok()) s = w.graph->record(cmd);
    Device* dev = &d;
    auto graph = w.graph;
    auto staging = std::make_shared<std::vector<Buffer>>(std::move(w.staging));
    deferRelease(d, [dev, graph, staging] {
      graph->release(*dev);
      for (Buffer& b : *staging) destroyBuffer(*dev, b);
    });
  }
  list.clear();
  return s.context("recording prepared uploads");
}

void dropPreparedWork(Device& d, PreparedList& list) {
  for (PreparedWork& w : list) {
    w.graph->release(d);
    for (Buffer& b : w.staging) destroyBuffer(d, b);
  }
  list.clear();
}

Status uploadBuffer(Device& d, PreparedList* deferred, const Buffer& dst, const void* data, VkDeviceSize size, rg::State state,
                    VkDeviceSize offset) {
  if (offset + size > dst.size || offset + size < offset)
    return Status::error("uploadBuffer: " + std::to_string(size) + " bytes at " + std::to_string(offset) +
                         " exceed the buffer's " + std::to_string(dst.size));
  Buffer staging;
  CANOPY_TRY(createBuffer(d, size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUsage::Upload, &staging, "upload staging"));
  std::memcpy(staging.allocation.mapped, data, size);
  PreparedWork w;
  w.graph = std::make_shared<rg::RenderGraph>();
  w.staging.push_back(staging);
  rg::RenderGraph& g = *w.graph;
  auto src = g.importBuffer("staging", size, kHostWritten, rg::stateOf(rg::Use::TransferSrc));
  auto dstId = g.importBuffer("destination", dst.size, state, state);
  g.addPass("upload", [src, dstId, offset, size](rg::PassContext& c) {
     VkBufferCopy region{0, offset, size};
     c.device->vk.CmdCopyBuffer(c.cmd, c.buffer(src), c.buffer(dstId), 1, &region);
     return Status();
   })
      .read(src, rg::Use::TransferSrc)
      .write(dstId, rg::Use::TransferDst);
  Status s = g.bindBuffer(src, staging.buffer);
  if (s.ok()) s = g.bindBuffer(dstId, dst.buffer);
  if (s.ok()) s = submitOrDefer(d, std::move(w), deferred);
  else destroyBuffer(d, staging);
  return s.context("uploadBuffer");
}

Status uploadImage(Device& d, PreparedList* deferred, const Image& img, const void* texels, VkDeviceSize size, rg::State final) {
  const uint32_t texel = texelBytes(img.format);
  const VkDeviceSize want = VkDeviceSize(img.extent.width) * img.extent.height * img.layers * texel;
  if (texel == 0 || size != want)
    return Status::error("uploadImage: " + std::to_string(size) + " bytes given for a " + std::to_string(img.extent.width) +
                         "x" + std::to_string(img.extent.height) + "x" + std::to_string(img.layers) + " image of " +
                         std::to_string(texel) + "-byte texels (format " + std::to_string(int(img.format)) + ")");
  Buffer staging;
  CANOPY_TRY(createBuffer(d, size, VK_BUFFER_USAGE_TRANSFER_SRC_BIT, MemoryUsage::Upload, &staging, "upload staging"));
  std::memcpy(staging.allocation.mapped, texels, size);
  PreparedWork w;
  w.graph = std::make_shared<rg::RenderGraph>();
  w.staging.push_back(staging);
  rg::RenderGraph& g = *w.graph;
  const ImageDesc desc = descOf(img);
  auto src = g.importBuffer("staging", size, kHostWritten, rg::stateOf(rg::Use::TransferSrc));
  auto dst = g.importImage("destination", desc, {}, final);
  const VkImageAspectFlags aspect = img.aspect;
  const uint32_t layers = img.layers;
  const VkExtent3D extent = img.extent;
  g.addPass("upload image", [src, dst, aspect, layers, extent](rg::PassContext& c) {
     VkBufferImageCopy region{};
     region.imageSubresource = {aspect, 0, 0, layers};
     region.imageExtent = extent;
     c.device->vk.CmdCopyBufferToImage(c.cmd, c.buffer(src), c.image(dst).image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, 1, &region);
     return Status();
   })
      .read(src, rg::Use::TransferSrc)
      .write(dst, rg::Use::TransferDst);
  Status s = g.bindBuffer(src, staging.buffer);
  if (s.ok()) s = g.bindImage(dst, img);
  if (s.ok()) s = submitOrDefer(d, std::move(w), deferred);
  else destroyBuffer(d, staging);
  return s.context("uploadImage");
}

Status readbackBuffer(Device& d, const Buffer& srcBuf, void* out, VkDeviceSize size, rg::State state,
                      VkDeviceSize offset) {
  if (offset + size > srcBuf.size || offset + size < offset)
    return Status::error("readbackBuffer: " + std::to_string(size) + " bytes at " + std::to_string(offset) +
                         " exceed the buffer's " + std::to_string(srcBuf.size));
  Buffer staging;
  CANOPY_TRY(createBuffer(d, size, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUsage::Readback, &staging, "readback staging"));
  rg::RenderGraph g;
  auto src = g.importBuffer("source", srcBuf.size, state, state);
  auto dst = g.importBuffer("staging", size, {}, kHostRead);
  g.addPass("readback", [&](rg::PassContext& c) {
     VkBufferCopy region{offset, 0, size};
     c.device->vk.CmdCopyBuffer(c.cmd, c.buffer(src), c.buffer(dst), 1, &region);
     return Status();
   })
      .read(src, rg::Use::TransferSrc)
      .write(dst, rg::Use::TransferDst);
  Status s = g.bindBuffer(src, srcBuf.buffer);
  if (s.ok()) s = g.bindBuffer(dst, staging.buffer);
  if (s.ok()) s = runGraph(d, g);
  if (s.ok()) std::memcpy(out, staging.allocation.mapped, size);
  destroyBuffer(d, staging);
  return s.context("readbackBuffer");
}

Status readbackImage(Device& d, const Image& img, uint32_t layer, uint32_t bytesPerTexel, void* out, rg::State state) {
  if (layer >= img.layers) return Status::error("readbackImage: layer " + std::to_string(layer) + " out of range");
  const VkDeviceSize size = VkDeviceSize(img.extent.width) * img.extent.height * bytesPerTexel;
  Buffer staging;
  CANOPY_TRY(createBuffer(d, size, VK_BUFFER_USAGE_TRANSFER_DST_BIT, MemoryUsage::Readback, &staging, "readback staging"));
  rg::RenderGraph g;
  const ImageDesc desc = descOf(img);
  auto src = g.importImage("source", desc, state, state);
  auto dst = g.importBuffer("staging", size, {}, kHostRead);
  g.addPass("readback image", [&](rg::PassContext& c) {
     VkBufferImageCopy region{};
     region.imageSubresource = {img.aspect, 0, layer, 1};
     region.imageExtent = img.extent;
     c.device->vk.CmdCopyImageToBuffer(c.cmd, c.image(src).image, VK_IMAGE_LAYOUT_TRANSFER_SRC_OPTIMAL, c.buffer(dst), 1, &region);
     return Status();
   })
      .read(src, rg::Use::TransferSrc)
      .write(dst, rg::Use::TransferDst);
  Status s = g.bindImage(src, img);
  if (s.ok()) s = g.bindBuffer(dst, staging.buffer);
  if (s.ok()) s = runGraph(d, g);
  if (s.ok()) std::memcpy(out, staging.allocation.mapped, size);
  destroyBuffer(d, staging);
  return s.context("readbackImage");
}

}  // namespace canopy
