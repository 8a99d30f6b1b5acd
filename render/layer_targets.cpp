#include "render/layer_targets.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "engine/device.h"
#include "engine/transfer.h"
#include "render/layer_common.h"

namespace canopy {

// Frees the layer images once no host frame in flight can read them (deferRelease), so a new
// layer count or size never waits for the device; `now`: at once (images no frame has used).
void destroyLayerTargets(Device& device, LayerTargets& targets, bool now) {
  Device* d = &device;
  dropPreparedWork(*d, targets.pendingClear);  // a clear of these images never recorded: nothing to wait for
  std::vector<VkImageView> views;
  for (auto* v : {&targets.colorLayerViews, &targets.depthLayerViews, &targets.idsLayerViews, &targets.next.colorLayerViews,
                  &targets.next.depthLayerViews}) {
    views.insert(views.end(), v->begin(), v->end());
    v->clear();
  }
  std::vector<Image> images;
  for (Image* img : {&targets.color, &targets.depth, &targets.ids, &targets.backgroundColor, &targets.backgroundDepth, &targets.next.color,
                     &targets.next.depth, &targets.next.backgroundColor, &targets.next.backgroundDepth}) {
    if (img->image) images.push_back(*img);
    *img = Image{};
  }
  auto release = [d, views, images]() mutable {
    for (VkImageView v : views) d->vk.DestroyImageView(d->device, v, d->allocationCallbacks);
    for (Image& img : images) destroyImage(*d, img);
  };
  if (now) release();
  else deferRelease(*d, std::move(release));
}


namespace {
Status layerView(Device& d, const Image& img, uint32_t layer, VkImageView* out) {
  VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vi.image = img.image;
  vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
  vi.format = img.format;
  vi.subresourceRange = {img.aspect, 0, 1, layer, 1};
  CANOPY_VK(d.vk.CreateImageView(d.device, &vi, d.allocationCallbacks, out));
  return Status();
}
}  // namespace


// Creates the layer arrays and the background for the current layer count, cleared and left in
// the rest state so that every later graph can import them with a fixed initial state.
Status createLayerTargets(Device& d, const LayerTargetsDesc& desc, LayerTargets& targets) {
  const uint32_t n = desc.layers;
  targets.restUse = desc.restUse;
  ImageDesc c;
  c.format = desc.colorFormat;
  c.width = desc.width;
  c.height = desc.height;
  c.layers = n;
  c.arrayView = true;
  c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
            VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, c, &targets.color, "layers: colour"));
  ImageDesc z = c;
  z.format = kLayerDepthFormat;
  z.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
            VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, z, &targets.depth, "layers: depth"));
  if (desc.ids) {
    ImageDesc i = c;
    i.format = kLayerIdsFormat;
    CANOPY_TRY(createImage(d, i, &targets.ids, "layers: ids"));
  }
  ImageDesc bc = c;
  bc.layers = 1;
  bc.arrayView = false;
  CANOPY_TRY(createImage(d, bc, &targets.backgroundColor, "background: colour"));
  ImageDesc bz = z;
  bz.layers = 1;
  bz.arrayView = false;
  CANOPY_TRY(createImage(d, bz, &targets.backgroundDepth, "background: depth"));
  if (desc.nextSet) {
    CANOPY_TRY(createImage(d, c, &targets.next.color, "layers (next set): colour"));
    CANOPY_TRY(createImage(d, z, &targets.next.depth, "layers (next set): depth"));
    CANOPY_TRY(createImage(d, bc, &targets.next.backgroundColor, "background (next set): colour"));
    CANOPY_TRY(createImage(d, bz, &targets.next.backgroundDepth, "background (next set): depth"));
    for (uint32_t l = 0; l < n; ++l) {
      VkImageView v;
      CANOPY_TRY(layerView(d, targets.next.color, l, &v));
      targets.next.colorLayerViews.push_back(v);
      CANOPY_TRY(layerView(d, targets.next.depth, l, &v));
      targets.next.depthLayerViews.push_back(v);
    }
  }
  for (uint32_t l = 0; l < n; ++l) {
    VkImageView v;
    CANOPY_TRY(layerView(d, targets.color, l, &v));
    targets.colorLayerViews.push_back(v);
    CANOPY_TRY(layerView(d, targets.depth, l, &v));
    targets.depthLayerViews.push_back(v);
    if (desc.ids) {
      CANOPY_TRY(layerView(d, targets.ids, l, &v));
      targets.idsLayerViews.push_back(v);
    }
  }
  // Clear once (empty layers until the first rebuild) into the rest state.
  PreparedWork work;
  work.graph = std::make_shared<rg::RenderGraph>();
  rg::RenderGraph& g = *work.graph;
  const rg::State rest = rg::stateOf(desc.restUse);
  std::vector<std::pair<rg::ResourceId, const Image*>> imgs;
  for (const Image* img : {&targets.color, &targets.depth, &targets.ids, &targets.backgroundColor, &targets.backgroundDepth}) {
    if (!img->image) continue;
    imgs.push_back({g.importImage("layer target", descOf(*img), {}, rest), img});
  }
  for (const Image* img : {&targets.next.color, &targets.next.depth, &targets.next.backgroundColor, &targets.next.backgroundDepth}) {
    if (!img->image) continue;
    imgs.push_back({g.importImage("layer target (next set)", descOf(*img), {}, kNextRest), img});
  }
  std::vector<rg::ResourceId> ids;
  for (auto& [id, img] : imgs) ids.push_back(id);
  // The images as bound to this graph (by value: the clear may be recorded frames later).
  auto pass = g.addPass("layers: initial clear", [ids](rg::PassContext& ctx) {
    for (rg::ResourceId id : ids) {
      const Image& img = ctx.image(id);
      const VkImageSubresourceRange range{img.aspect, 0, 1, 0, img.layers};
      if (img.aspect & VK_IMAGE_ASPECT_DEPTH_BIT) {
        VkClearDepthStencilValue v{1.0f, 0};
        ctx.device->vk.CmdClearDepthStencilImage(ctx.cmd, img.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &v, 1, &range);
      } else {
        VkClearColorValue v{};
        ctx.device->vk.CmdClearColorImage(ctx.cmd, img.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, &v, 1, &range);
      }
    }
    return Status();
  });
  for (auto& [id, img] : imgs) {
    pass.write(id, rg::Use::TransferDst);
    CANOPY_TRY(g.bindImage(id, *img));
  }
  // On a host's device the clear is recorded into its next frame (LayerTargets::pendingClear), else now.
  return submitOrDefer(d, std::move(work), &targets.pendingClear);
}


Status imageLayerView(Device& device, const Image& image, uint32_t layer, VkImageView* out) {
  return layerView(device, image, layer, out);
}


namespace {
Status readColorImage(Device& d, const LayerTargets& t, const Image& img, uint32_t layer, std::vector<glm::vec4>* rgba) {
  const size_t n = size_t(img.extent.width) * img.extent.height;
  rgba->assign(n, glm::vec4(0));
  if (img.format == VK_FORMAT_R16G16B16A16_SFLOAT) {
    std::vector<uint64_t> raw(n);
    CANOPY_TRY(readbackImage(d, img, layer, 8, raw.data(), rg::stateOf(t.restUse)));
    for (size_t i = 0; i < n; ++i) {
      const glm::uvec2 halves(uint32_t(raw[i]), uint32_t(raw[i] >> 32));
      (*rgba)[i] = glm::vec4(glm::unpackHalf2x16(halves.x), glm::unpackHalf2x16(halves.y));
    }
  } else {
    std::vector<uint32_t> raw(n);
    CANOPY_TRY(readbackImage(d, img, layer, 4, raw.data(), rg::stateOf(t.restUse)));
    for (size_t i = 0; i < n; ++i) (*rgba)[i] = glm::unpackUnorm4x8(raw[i]);
  }
  return Status();
}

size_t pixelsOf(const Image& img) { return size_t(img.extent.width) * img.extent.height; }
}  // namespace

Status readLayerColor(Device& d, const LayerTargets& t, uint32_t layer, std::vector<glm::vec4>* rgba) {
  return readColorImage(d, t, t.color, layer, rgba);
}

Status readLayerDepth(Device& d, const LayerTargets& t, uint32_t layer, std::vector<float>* depth) {
  depth->assign(pixelsOf(t.depth), 0.0f);
  return readbackImage(d, t.depth, layer, 4, depth->data(), rg::stateOf(t.restUse));
}

Status readLayerIds(Device& d, const LayerTargets& t, uint32_t layer, std::vector<glm::uvec2>* ids) {
  if (!t.ids.image) return Status::error("readLayerIds: created without writeIds");
  ids->assign(pixelsOf(t.ids), glm::uvec2(0));
  return readbackImage(d, t.ids, layer, 8, ids->data(), rg::stateOf(t.restUse));
}

Status readBackground(Device& d, const LayerTargets& t, std::vector<glm::vec4>* rgba, std::vector<float>* depth) {
  CANOPY_TRY(readColorImage(d, t, t.backgroundColor, 0, rgba));
  depth->assign(pixelsOf(t.backgroundDepth), 0.0f);
  return readbackImage(d, t.backgroundDepth, 0, 4, depth->data(), rg::stateOf(t.restUse));
}

}  // namespace canopy
