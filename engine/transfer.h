#pragma once
// Staging upload and readback, outside the per-frame path. Each copy is a one-pass render graph
// over the imported resource, so its barriers come from the graph like every other pass.
#include <vulkan/vulkan.h>

#include "engine/memory.h"
#include "engine/render_graph.h"
#include "engine/status.h"

namespace canopy {
struct Device;

// Copies `size` bytes into `dst` at `offset`. `state` is how the buffer is used before and after
// (the graph makes the copy visible to that use). Waits for completion.
Status uploadBuffer(Device& device, const Buffer& dst, const void* data, VkDeviceSize size, rg::State state,
                    VkDeviceSize offset = 0);
// Fills mip 0 of every layer of a freshly created image (colour or depth) with tightly packed
// texels, layer after layer (previous contents discarded), and leaves it in `final`. Waits.
Status uploadImage(Device& device, const Image& dst, const void* texels, VkDeviceSize size, rg::State final);
// Copies `size` bytes from `src` at `offset` into `out`. Waits for completion.
Status readbackBuffer(Device& device, const Buffer& src, void* out, VkDeviceSize size, rg::State state,
                      VkDeviceSize offset = 0);
// Reads one layer of a colour image (tightly packed texels, bytesPerTexel each) into `out`.
Status readbackImage(Device& device, const Image& src, uint32_t layer, uint32_t bytesPerTexel, void* out,
                     rg::State state);

}  // namespace canopy
