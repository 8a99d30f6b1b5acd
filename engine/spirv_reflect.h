#pragma once
// The descriptor bindings a SPIR-V module declares, read from the module itself: every pipeline's
// set layout is built from its shaders (docs/design.md "Descriptors from the SPIR-V"), so no C++
// list of descriptor types or binding numbers can drift from the GLSL.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>
#include <vulkan/vulkan.h>

#include "engine/status.h"

namespace canopy {

// Binding b of set 0 (index b). VK_DESCRIPTOR_TYPE_MAX_ENUM: no variable at that binding.
using DescriptorTypes = std::vector<VkDescriptorType>;

// Reads the set-0 descriptor variables of `code`: storage/uniform buffers (Uniform with
// BufferBlock/Block, or StorageBuffer), combined image samplers, sampled and storage images and
// samplers. Refuses a malformed module, a set other than 0, or an array of descriptors.
Status reflectDescriptors(const uint32_t* code, size_t words, DescriptorTypes* out);

// Merges the stages' bindings (a graphics pipeline's vertex and fragment shader): a binding both
// declare must have one type. `what` names the pipeline in the error.
Status mergeDescriptors(const DescriptorTypes& a, const DescriptorTypes& b, const std::string& what,
                        DescriptorTypes* out);

// The layout a push-descriptor pipeline is built with: every binding 0..n-1 declared (the bind
// lists are positional), else an error naming the first missing binding.
Status requireContiguous(const DescriptorTypes& types, const std::string& what);

// "storage buffer", "combined image sampler", ... (errors and tests).
const char* descriptorTypeName(VkDescriptorType type);

}  // namespace canopy
