#pragma once
// Staging upload and readback, outside the per-frame path. Each copy is a one-pass render graph
// over the imported resource, so its barriers come from the graph like every other pass.
#include <memory>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/memory.h"
#include "engine/render_graph.h"
#include "engine/status.h"

namespace canopy {
struct Device;

// Work prepared outside a frame (uploads while a context is created, the clear of new layer
// images): a one-pass graph and the staging buffers it reads.
struct PreparedWork {
  std::shared_ptr<rg::RenderGraph> graph;  // compiled and realized
  std::vector<Buffer> staging;
};
// Work that waits for the host's next frame; each part that prepares work owns its list and the
// facade flushes it (docs/design.md, "Embedding contract").
using PreparedList = std::vector<PreparedWork>;
// On a device that records such work into the host's command buffer (Device::deferUploads, what
// adoptDevice() sets) the work is kept in `deferred` until recordCanopy() flushes it at the start
// of the next frame; otherwise, or with a null list, it is submitted at once and waited for on its
// own fence. The list is the caller's: nothing decides it behind the call.
Status submitOrDefer(Device& device, PreparedWork work, PreparedList* deferred);
// Records every kept graph into `cmd`; their objects are released framesInFlight frames later.
Status flushPreparedWork(Device& device, PreparedList& list, VkCommandBuffer cmd);
// Frees kept work that was never recorded (a context destroyed before its first frame).
void dropPreparedWork(Device& device, PreparedList& list);

// Copies `size` bytes into `dst` at `offset`. `state` is how the buffer is used before and after
// (the graph makes the copy visible to that use). Submitted or kept in `deferred` (submitOrDefer).
Status uploadBuffer(Device& device, PreparedList* deferred, const Buffer& dst, const void* data, VkDeviceSize size,
                    rg::State state, VkDeviceSize offset = 0);
// Fills mip 0 of every layer of a freshly created image (colour or depth) with tightly packed
// texels, layer after layer (previous contents discarded), and leaves it in `final`. Submitted or
// kept in `deferred` (submitOrDefer).
Status uploadImage(Device& device, PreparedList* deferred, const Image& dst, const void* texels, VkDeviceSize size,
                   rg::State final);
// Copies `size` bytes from `src` at `offset` into `out`. Waits for completion.
Status readbackBuffer(Device& device, const Buffer& src, void* out, VkDeviceSize size, rg::State state,
                      VkDeviceSize offset = 0);
// Reads one layer of a colour image (tightly packed texels, bytesPerTexel each) into `out`.
Status readbackImage(Device& device, const Image& src, uint32_t layer, uint32_t bytesPerTexel, void* out,
                     rg::State state);

}  // namespace canopy
