// recordCanopyLoad (<canopy/canopy.h>): the loading screen's frame, into targets of its own.
#include "render/canopy_context.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>

#include "engine/memory.h"

namespace canopy {

namespace {
// The load frame's own targets (recordCanopyLoad): the host's formats and size, contents never read
// by anyone; freed once the frames after it are done.
struct LoadTargets {
  Image color, depth, motion;
  VkImageView depthOnly = VK_NULL_HANDLE;
};
void destroyLoadTargets(Device& d, LoadTargets& t) {
  if (t.depthOnly) d.vk.DestroyImageView(d.device, t.depthOnly, d.allocationCallbacks);
  destroyImage(d, t.color);
  destroyImage(d, t.depth);
  destroyImage(d, t.motion);
  t = LoadTargets{};
}
Status createLoadTargets(Device& d, const CanopyDesc& desc, LoadTargets* t) {
  ImageDesc i;
  i.width = desc.width;
  i.height = desc.height;
  i.format = desc.colorFormat;
  i.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
  CANOPY_TRY(createImage(d, i, &t->color, "load frame: colour"));
  i.format = desc.depthFormat;
  i.usage = VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT;
  CANOPY_TRY(createImage(d, i, &t->depth, "load frame: depth"));
  VkImageViewCreateInfo vi{VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO};
  vi.image = t->depth.image;
  vi.viewType = VK_IMAGE_VIEW_TYPE_2D;
  vi.format = desc.depthFormat;
  vi.subresourceRange = {VK_IMAGE_ASPECT_DEPTH_BIT, 0, 1, 0, 1};
  CANOPY_VK(d.vk.CreateImageView(d.device, &vi, d.allocationCallbacks, &t->depthOnly));
  if (desc.motionFormat != VK_FORMAT_UNDEFINED) {
    i.format = desc.motionFormat;
    i.usage = VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT;
    CANOPY_TRY(createImage(d, i, &t->motion, "load frame: motion"));
  }
  return Status();
}
}  // namespace

Status recordCanopyLoad(CanopyContext* c, VkCommandBuffer cmd, const CanopyCamera& camera) {
  return guardApi("recordCanopyLoad", [&]() -> Status {
    if (!c) return Status::error("recordCanopyLoad: null context");
    if (!cmd) return Status::error("recordCanopyLoad: null command buffer");
    Device& d = *c->device;
    // A whole frame at `camera` with the simulation held (dt 0), into targets of its own: the
    // uploads, the first re-slice, the composite's occupancy and every pass's first use happen
    // here, and the first frame of play at that camera finds the layers current.
    auto targets = std::make_shared<LoadTargets>();
    Status s = createLoadTargets(d, c->desc, targets.get());
    if (s.ok()) {
      const ResourceState none{};
      CanopyFrameInputs in;
      in.frame.camera = camera;
      in.frame.dt = 1.0f / 30.0f;
      in.frame.frameNumber = d.anyFrame ? d.frameNumber : 0;
      in.color = canopyImage(targets->color.image, targets->color.view, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, c->desc.colorFormat, none,
                             {VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                              VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL});
      in.depth = canopyImage(targets->depth.image, targets->depthOnly,
                             VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, c->desc.depthFormat, none,
                             {VK_PIPELINE_STAGE_2_LATE_FRAGMENT_TESTS_BIT, VK_ACCESS_2_DEPTH_STENCIL_ATTACHMENT_WRITE_BIT,
                              VK_IMAGE_LAYOUT_DEPTH_ATTACHMENT_OPTIMAL});
      if (targets->motion.image)
        in.motion = canopyImage(targets->motion.image, targets->motion.view, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, c->desc.motionFormat,
                                none, {VK_PIPELINE_STAGE_2_COLOR_ATTACHMENT_OUTPUT_BIT, VK_ACCESS_2_COLOR_ATTACHMENT_WRITE_BIT,
                                       VK_IMAGE_LAYOUT_COLOR_ATTACHMENT_OPTIMAL});
      // The load is no host frame: the first frame of play steps the simulation whatever its number.
      SharedSimulation& sh = *c->shared;
      const bool everStepped = sh.everStepped;
      const uint64_t lastStep = sh.lastStepFrame;
      s = recordCanopy(c, cmd, in);
      sh.everStepped = everStepped;
      sh.lastStepFrame = lastStep;
      // Its graph names these targets only: retired with them, never found for a host's images.
      std::vector<RecordGraph> keep, drop;
      for (RecordGraph& g : c->recordGraphs) (g.inputs.color.image == targets->color.image ? drop : keep).push_back(std::move(g));
      c->recordGraphs = std::move(keep);
      retireRecordGraphs(*c, std::move(drop));
    }
    Device* dev = &d;
    deferRelease(d, [dev, targets] { destroyLoadTargets(*dev, *targets); });
    return s;
  });
}

}  // namespace canopy
