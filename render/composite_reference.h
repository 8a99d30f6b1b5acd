#pragma once
// CPU reference of the inverse warp + compositing pass (tests only): the same algorithm as
// shaders/composite.frag, written plainly over host arrays, with the shared grid lookup and "over"
// step from shaders/shared/composite.h. Sampling follows Vulkan's rules: bilinear at texel centres
// (x - 0.5), clamp-to-border (transparent colour, far depth).
#include <cstdint>
#include <vector>
#include <glm/glm.hpp>

#include "shared/composite.h"

namespace canopy {

struct CompositeReferenceInputs {
  uint32_t width = 0, height = 0, layers = 0;  // the output's size
  // The layer images' size (the output plus the guard band, push.originX / originY on each side;
  // 0: the output's).
  uint32_t layerWidth = 0, layerHeight = 0;
  std::vector<glm::vec4> layerColor;     // layers x layerHeight x layerWidth, premultiplied
  std::vector<float> layerDepth;         // layers x layerHeight x layerWidth
  std::vector<glm::vec4> backgroundColor;  // layerHeight x layerWidth (empty: no background)
  std::vector<float> backgroundDepth;
  std::vector<glm::vec4> sceneColor;     // the host's colour before the composite
  std::vector<float> sceneDepth;         // the host's depth before the composite (height x width)
  std::vector<glm::vec2> displacement;   // layers x gridY x gridX, pixels
  std::vector<glm::vec2> previous;       // same shape (motion vectors)
  gpu::CompositeView view{};             // read where push.flags has COMPOSITE_REPROJECT
};
struct CompositeReferenceOutputs {
  std::vector<glm::vec4> color;   // premultiplied result over sceneColor
  std::vector<float> depth;
  std::vector<glm::vec2> motion;  // (0,0) where the vegetation is not frontmost
  std::vector<uint8_t> vegetationFront;
};
// `push` as prepareComposite() fills it (flags decide early exit, bilinear, background...).
void compositeReference(const gpu::CompositePush& push, const CompositeReferenceInputs& in, CompositeReferenceOutputs* out);

}  // namespace canopy
