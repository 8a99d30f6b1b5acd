#pragma once
// The host's camera as Canopy draws with it (docs/design.md "Embedding contract"): the viewport and
// a GL clip depth folded into the projection, so every pass works in the targets' whole clip space;
// the jitter kept apart, so a jitter alone is no camera motion.
#include <glm/glm.hpp>

#include <canopy/canopy_params.h>
#include "engine/status.h"

namespace canopy {

struct HostCamera {
  CanopyCamera camera;       // viewport and clip depth folded in, unjittered (jitter and viewport zero)
  // The clip depth converted but not the viewport: the view the host sees in its rectangle (the
  // simulation plane's tile spans what it shows, as for a target of the viewport's size).
  CanopyCamera inViewport;
  glm::mat4 jitter{1.0f};    // clip -> clip: the frame's jitter, x' = x + (2 jitter.x / width) w
  glm::vec2 jitterPixels{0.0f};
  VkRect2D scissor{};        // the viewport's pixels (the whole targets without one)
};

// Checks `camera`'s viewport, clip depth and jitter against the targets (width x height) and folds
// them; errors name the field and its allowed range.
Status hostCamera(const CanopyCamera& camera, uint32_t width, uint32_t height, HostCamera* out);

}  // namespace canopy
