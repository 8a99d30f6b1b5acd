#pragma once
// The host's images as recordCanopy() receives them (docs/embedding.md "Host images"): each
// declared with its usage and format, checked against what Canopy does with it before anything of
// the frame is recorded, and turned into the render graph's imported image.
#include <canopy/canopy.h>

#include "engine/memory.h"

namespace canopy {

// The same image, view, states and declaration (a compiled graph is reused only for these).
bool sameHostImage(const CanopyImage& a, const CanopyImage& b);
// The host's image as the render graph binds it (its handles; the format and size Canopy's).
Image hostImage(const CanopyImage& image, VkFormat format, uint32_t width, uint32_t height);
// The frame's images against the context's description: present, declared with the usage Canopy
// needs, of its formats, single-sampled, the views' aspects; an error names the image and the fix.
Status checkFrameInputs(const CanopyDesc& desc, const CanopyFrameInputs& inputs);

}  // namespace canopy
