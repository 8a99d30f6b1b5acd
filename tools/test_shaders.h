#pragma once
// The tests' own compute shaders (tests/shaders: the render graph's example passes, the shared
// struct layout probe, the per-vertex bend probe), embedded into the tools library by
// cmake/CanopyShaders.cmake in a registry of their own: the runtime a host links holds none of
// them. A pipeline names this registry in ComputePipelineDesc::shaderLookup.
#include <cstddef>

#include "engine/shader_registry.h"

namespace canopy_test {
const canopy::EmbeddedShader* findEmbeddedShader(const char* name);
const canopy::EmbeddedShader* embeddedShaderAt(size_t index);
}  // namespace canopy_test
