#pragma once
// Fault injection through the host's loader (what a host using volk could do): a
// vkGetInstanceProcAddr that hands out Canopy's entry points wrapped so that, after a given number
// of successful object creations and memory allocations, they fail with VK_ERROR_OUT_OF_DEVICE_MEMORY
// or (device-lost mode) every creation, submission and wait returns VK_ERROR_DEVICE_LOST. It counts
// the objects created and destroyed through it, so a test can prove that nothing leaked.
// Process-wide state: one fault scenario at a time (tests and the demo's --inject-fault).
#include <cstdint>
#include <string>
#include <vulkan/vulkan.h>

namespace canopy::fault {

enum class Mode { Off, OutOfMemory, DeviceLost };

// Arms the loader: the next `successes` wrapped creations/allocations succeed, then `mode` begins.
void arm(Mode mode, int64_t successes);
// Creations/allocations seen since arm() (to size a sweep over every failure point).
int64_t calls();
// Objects created through the loader and not yet destroyed (memory, buffers, images, views,
// samplers, pipelines, layouts, command pools, fences, query pools, shader modules).
int64_t liveObjects();
// Whether the fault has been triggered since arm().
bool triggered();

// The wrapping loader, over `real` (usually the loader's own vkGetInstanceProcAddr).
PFN_vkGetInstanceProcAddr loader(PFN_vkGetInstanceProcAddr real);

// "oom:N" or "lost:N" (the demo's --inject-fault); false on anything else.
bool parse(const std::string& spec, Mode* mode, int64_t* successes);

}  // namespace canopy::fault
