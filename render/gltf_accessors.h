#pragma once
// glTF accessors read with every byte range checked (render/gltf_loader.cpp): component sizes and
// conversions, and the GltfReader that turns an accessor (with its sparse part) into doubles.
#include <cstdint>
#include <vector>

#include <tiny_gltf.h>

#include "engine/status.h"

namespace canopy {

// Bytes of a component type (0: unknown) and components of an accessor type (0: unknown).
uint32_t componentSize(int type);
uint32_t componentCount(int type);
// One component at `p` as a double (a normalized integer mapped to [0, 1] or [-1, 1]).
double readComponent(const unsigned char* p, int type, bool normalized);

class GltfReader {
 public:
  explicit GltfReader(const tinygltf::Model& m) : m_(m) {}

  // The byte range [offset, offset+size) of a buffer view, checked against its buffer.
  Status view(int index, const unsigned char** data, uint64_t* size, uint32_t* stride) const;

  // Reads accessor `index` as doubles (count x components), with every byte range checked,
  // sparse substitution applied, and the allowed component types enforced. Nothing is allocated
  // before the count is checked against the bytes behind it (or, for an accessor with no
  // bufferView, against `maxCount`).
  Status read(int index, const std::vector<int>& types, std::vector<uint32_t> componentTypes, uint64_t maxCount,
              std::vector<double>* out, uint32_t* outComponents, uint64_t* outCount) const;

 private:
  const tinygltf::Model& m_;
};

}  // namespace canopy
