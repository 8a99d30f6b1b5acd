#pragma once
// Lookup of the SPIR-V embedded at build time (cmake/CanopyShaders.cmake): binaries run from anywhere.
#include <cstddef>
#include <cstdint>

namespace canopy {

struct EmbeddedShader {
  const char* name;      // source file name, e.g. "sim_tile.comp"
  const uint32_t* code;  // SPIR-V words
  size_t sizeBytes;
};

// Returns the embedded shader compiled from shaders/<name>, or nullptr when no such shader exists.
const EmbeddedShader* findEmbeddedShader(const char* name);
// The index-th embedded shader, nullptr past the last (tests walk every shader).
const EmbeddedShader* embeddedShaderAt(size_t index);

}  // namespace canopy
