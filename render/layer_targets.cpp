#include "render/layer_targets.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

#include "engine/device.h"
#include "engine/transfer.h"
#include "render/layer_common.h"
#include "render/layers.h"

namespace canopy {

bool spreadEnabled(const LayeredVegetation& lv) { return lv.settings.rebuildBudgetMs > 0 && !lv.desc.writeIds; }
bool usesNextSet(const LayeredVegetation& lv) { return spreadEnabled(lv) || lv.mesh.streamed; }

// Frees the layer images once no host frame in flight can read them (deferRelease), so a new
// layer count or size never waits for the device; `now`: at once (images no frame has used).
void destroyLayerTargets(LayeredVegetation& lv, bool now) {
  Device* d = lv.device;
  dropPreparedWork(*d, lv.targets.pendingClear);  // a clear of these images never recorded: nothing to wait for
  std::vector<VkImageView> views;
  for (auto* v : {&lv.targets.colorLayerViews, &lv.targets.depthLayerViews, &lv.targets.idsLayerViews, &lv.targets.next.colorLayerViews,
                  &lv.targets.next.depthLayerViews}) {
    views.insert(views.end(), v->begin(), v->end());
    v->clear();
  }
  std::vector<Image> images;
  for (Image* img : {&lv.targets.color, &lv.targets.depth, &lv.targets.ids, &lv.targets.backgroundColor, &lv.targets.backgroundDepth, &lv.targets.next.color,
                     &lv.targets.next.depth, &lv.targets.next.backgroundColor, &lv.targets.next.backgroundDepth}) {
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
Status createLayerTargets(LayeredVegetation& lv) {
  Device& d = *lv.device;
  const uint32_t n = lv.settings.layout.count();
  ImageDesc c;
  c.format = lv.desc.colorFormat;
  c.width = lv.desc.width;
  c.height = lv.desc.height;
  c.layers = n;
  c.arrayView = true;
  c.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_SRC_BIT |
            VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, c, &lv.targets.color, "layers: colour"));
  ImageDesc z = c;
  z.format = kLayerDepthFormat;
  z.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT |
            VK_IMAGE_USAGE_TRANSFER_SRC_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  CANOPY_TRY(createImage(d, z, &lv.targets.depth, "layers: depth"));
  if (lv.desc.writeIds) {
    ImageDesc i = c;
    i.format = kLayerIdsFormat;
    CANOPY_TRY(createImage(d, i, &lv.targets.ids, "layers: ids"));
  }
  ImageDesc bc = c;
  bc.layers = 1;
  bc.arrayView = false;
  CANOPY_TRY(createImage(d, bc, &lv.targets.backgroundColor, "background: colour"));
  ImageDesc bz = z;
  bz.layers = 1;
  bz.arrayView = false;
  CANOPY_TRY(createImage(d, bz, &lv.targets.backgroundDepth, "background: depth"));
  if (usesNextSet(lv)) {
    CANOPY_TRY(createImage(d, c, &lv.targets.next.color, "layers (next set): colour"));
    CANOPY_TRY(createImage(d, z, &lv.targets.next.depth, "layers (next set): depth"));
    CANOPY_TRY(createImage(d, bc, &lv.targets.next.backgroundColor, "background (next set): colour"));
    CANOPY_TRY(createImage(d, bz, &lv.targets.next.backgroundDepth, "background (next set): depth"));
    for (uint32_t l = 0; l < n; ++l) {
      VkImageView v;
      CANOPY_TRY(layerView(d, lv.targets.next.color, l, &v));
      lv.targets.next.colorLayerViews.push_back(v);
      CANOPY_TRY(layerView(d, lv.targets.next.depth, l, &v));
      lv.targets.next.depthLayerViews.push_back(v);
    }
  }
  for (uint32_t l = 0; l < n; ++l) {
    VkImageView v;
    CANOPY_TRY(layerView(d, lv.targets.color, l, &v));
    lv.targets.colorLayerViews.push_back(v);
    CANOPY_TRY(layerView(d, lv.targets.depth, l, &v));
    lv.targets.depthLayerViews.push_back(v);
    if (lv.desc.writeIds) {
      CANOPY_TRY(layerView(d, lv.targets.ids, l, &v));
      lv.targets.idsLayerViews.push_back(v);
    }
  }
  // Clear once (empty layers until the first rebuild) into the rest state.
  PreparedWork work;
  work.graph = std::make_shared<rg::RenderGraph>();
  rg::RenderGraph& g = *work.graph;
  const rg::State rest = rg::stateOf(lv.desc.restUse);
  std::vector<std::pair<rg::ResourceId, const Image*>> imgs;
  for (const Image* img : {&lv.targets.color, &lv.targets.depth, &lv.targets.ids, &lv.targets.backgroundColor, &lv.targets.backgroundDepth}) {
    if (!img->image) continue;
    imgs.push_back({g.importImage("layer target", descOf(*img), {}, rest), img});
  }
  for (const Image* img : {&lv.targets.next.color, &lv.targets.next.depth, &lv.targets.next.backgroundColor, &lv.targets.next.backgroundDepth}) {
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
  // On a host's device the clear is recorded into its next frame (lv.targets.pendingClear), else now.
  return submitOrDefer(d, std::move(work), &lv.targets.pendingClear);
}


Status imageLayerView(Device& device, const Image& image, uint32_t layer, VkImageView* out) {
  return layerView(device, image, layer, out);
}


namespace {
Status readColorImage(LayeredVegetation& lv, const Image& img, uint32_t layer, std::vector<glm::vec4>* rgba) {
  const size_t n = size_t(img.extent.width) * img.extent.height;
  rgba->assign(n, glm::vec4(0));
  if (img.format == VK_FORMAT_R16G16B16A16_SFLOAT) {
    std::vector<uint64_t> raw(n);
    CANOPY_TRY(readbackImage(*lv.device, img, layer, 8, raw.data(), rg::stateOf(lv.desc.restUse)));
    for (size_t i = 0; i < n; ++i) {
      const glm::uvec2 halves(uint32_t(raw[i]), uint32_t(raw[i] >> 32));
      (*rgba)[i] = glm::vec4(glm::unpackHalf2x16(halves.x), glm::unpackHalf2x16(halves.y));
    }
  } else {
    std::vector<uint32_t> raw(n);
    CANOPY_TRY(readbackImage(*lv.device, img, layer, 4, raw.data(), rg::stateOf(lv.desc.restUse)));
    for (size_t i = 0; i < n; ++i) (*rgba)[i] = glm::unpackUnorm4x8(raw[i]);
  }
  return Status();
}
}  // namespace

Status readLayerColor(LayeredVegetation& lv, uint32_t layer, std::vector<glm::vec4>* rgba) {
  return readColorImage(lv, lv.targets.color, layer, rgba);
}

Status readLayerDepth(LayeredVegetation& lv, uint32_t layer, std::vector<float>* depth) {
  depth->assign(size_t(lv.desc.width) * lv.desc.height, 0.0f);
  return readbackImage(*lv.device, lv.targets.depth, layer, 4, depth->data(), rg::stateOf(lv.desc.restUse));
}

Status readLayerIds(LayeredVegetation& lv, uint32_t layer, std::vector<glm::uvec2>* ids) {
  if (!lv.desc.writeIds) return Status::error("readLayerIds: created without writeIds");
  ids->assign(size_t(lv.desc.width) * lv.desc.height, glm::uvec2(0));
  return readbackImage(*lv.device, lv.targets.ids, layer, 8, ids->data(), rg::stateOf(lv.desc.restUse));
}

Status readBackground(LayeredVegetation& lv, std::vector<glm::vec4>* rgba, std::vector<float>* depth) {
  CANOPY_TRY(readColorImage(lv, lv.targets.backgroundColor, 0, rgba));
  depth->assign(size_t(lv.desc.width) * lv.desc.height, 0.0f);
  return readbackImage(*lv.device, lv.targets.backgroundDepth, 0, 4, depth->data(), rg::stateOf(lv.desc.restUse));
}

}  // namespace canopy
