#pragma once
// The glTF file's framing and JSON checked before tinygltf parses it (render/gltf_loader.cpp): the
// GLB header and chunk lengths, the JSON's nesting depth, and every index, count and offset
// Canopy depends on as a non-negative integer in its range (docs/design.md "Errors and hostile
// input"); and the checked arithmetic the loader combines the file's numbers with.
#include <cstddef>
#include <cstdint>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "engine/status.h"

namespace canopy {

// ---- checked arithmetic on numbers read from the file ------------------------------------------
// Offsets, counts and lengths are combined only through these: a sum or product that does not fit
// in 64 bits is a refusal, never a wrapped value.
inline bool addTo(uint64_t* acc, uint64_t v) { return !__builtin_add_overflow(*acc, v, acc); }
inline bool mulTo(uint64_t* acc, uint64_t v) { return !__builtin_mul_overflow(*acc, v, acc); }
// [offset, offset + length) inside [0, size)
inline bool rangeFits(uint64_t offset, uint64_t length, uint64_t size) { return offset <= size && length <= size - offset; }

// GLB framing: header, chunk lengths inside the file.
Status checkGlb(const std::vector<unsigned char>& bytes);
// The JSON nests at most maxDepth arrays/objects (tinygltf's parser recurses on them).
Status checkJsonDepth(const unsigned char* json, size_t bytes, uint32_t maxDepth);
// The fields tinygltf reads without a range check, checked on the parsed document; an integer
// written as a float (1.0, 1e0) is written back as an integer.
Status checkGltfJsonFields(nlohmann::json& doc);

}  // namespace canopy
