#include "render/host_images.h"

#include <cstdio>
#include <string>
#include <utility>

#include "engine/render_graph.h"

namespace canopy {
namespace {

bool sameState(const rg::State& a, const rg::State& b) {
  return a.stage == b.stage && a.access == b.access && a.layout == b.layout;
}

std::string usageBitNames(VkImageUsageFlags bits) {
  const std::pair<VkImageUsageFlags, const char*> names[] = {
      {VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, "VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT"},
      {VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT, "VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT"},
      {VK_IMAGE_USAGE_SAMPLED_BIT, "VK_IMAGE_USAGE_SAMPLED_BIT"}};
  std::string s;
  for (const auto& [bit, name] : names)
    if (bits & bit) s += (s.empty() ? "" : " | ") + std::string(name);
  return s;
}

std::string handleText(VkImage image) {
  char h[32];
  std::snprintf(h, sizeof h, "0x%llx", (unsigned long long)(uintptr_t)image);
  return h;
}

// docs/embedding.md "Host images": what the host declared against what Canopy does with the image.
Status checkHostImage(const char* which, const CanopyImage& img, VkFormat format, VkImageUsageFlags need,
                      VkImageAspectFlags aspect, const char* why) {
  const std::string name = std::string("CanopyFrameInputs.") + which + " (VkImage " + handleText(img.image) + ")";
  if (img.usage == 0)
    return Status::error(Result::InvalidArgument, name + ": usage is not declared; set it to the VkImageCreateInfo.usage the image "
                                                         "was created with (Canopy needs " + usageBitNames(need) + ")");
  if ((img.usage & need) != need)
    return Status::error(Result::InvalidArgument, name + ": usage lacks " + usageBitNames(need & ~img.usage) + "; create the image with it (" +
                                                         why + ")");
  if (img.format != format)
    return Status::error(Result::InvalidArgument, name + ": format " + std::to_string(int(img.format)) + " is not the CanopyDesc format " +
                                                         std::to_string(int(format)) + " the context was created for");
  if (img.samples != VK_SAMPLE_COUNT_1_BIT)
    return Status::error(Result::InvalidArgument, name + ": " + std::to_string(int(img.samples)) +
                                                         " samples; Canopy draws into single-sampled targets (resolve the host's first)");
  if (img.viewAspects != 0 && img.viewAspects != aspect)
    return Status::error(Result::InvalidArgument, name + ": the view's aspects are " + std::to_string(img.viewAspects) + ", Canopy needs " +
                                                         (aspect == VK_IMAGE_ASPECT_DEPTH_BIT ? "the depth aspect only (a depth-only view of a "
                                                                                               "depth-stencil image)"
                                                                                             : "the colour aspect"));
  return Status();
}

}  // namespace

bool sameHostImage(const CanopyImage& a, const CanopyImage& b) {
  return a.image == b.image && a.view == b.view && sameState(a.current, b.current) && sameState(a.final, b.final) &&
         a.usage == b.usage && a.format == b.format && a.samples == b.samples && a.viewAspects == b.viewAspects;
}

Image hostImage(const CanopyImage& h, VkFormat format, uint32_t width, uint32_t height) {
  Image img;
  img.image = h.image;
  img.view = h.view;
  img.format = format;
  img.extent = {width, height, 1};
  img.aspect = aspectOf(format);
  return img;
}

// The host's images against the context's description, before anything is recorded (a refused frame records
// nothing: docs/embedding.md "Errors, and what to do").
Status checkFrameInputs(const CanopyDesc& desc, const CanopyFrameInputs& in) {
  const bool motion = desc.motionFormat != VK_FORMAT_UNDEFINED;
  if (!in.color.image || !in.color.view || !in.depth.image || !in.depth.view)
    return Status::error("recordCanopy: the colour and depth images and views are required");
  if (motion != (in.motion.image != VK_NULL_HANDLE) || (motion && !in.motion.view))
    return Status::error(motion ? "recordCanopy: CanopyDesc.motionFormat is set but no motion image (and view) was given"
                                : "recordCanopy: a motion image was given but CanopyDesc.motionFormat is UNDEFINED");
  // The host's declarations, checked once per set of images (a graph is built for each).
  CANOPY_TRY(checkHostImage("color", in.color, desc.colorFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
                            "Canopy blends the vegetation into it as a colour attachment"));
  CANOPY_TRY(checkHostImage("depth", in.depth, desc.depthFormat,
                            VK_IMAGE_USAGE_DEPTH_STENCIL_ATTACHMENT_BIT | VK_IMAGE_USAGE_SAMPLED_BIT, VK_IMAGE_ASPECT_DEPTH_BIT,
                            "Canopy reads the host's depth to put the scene between its layers, then writes the vegetation's"));
  if (motion)
    CANOPY_TRY(checkHostImage("motion", in.motion, desc.motionFormat, VK_IMAGE_USAGE_COLOR_ATTACHMENT_BIT, VK_IMAGE_ASPECT_COLOR_BIT,
                              "Canopy writes the vegetation's motion as a colour attachment"));
  return Status();
}

}  // namespace canopy
