#pragma once
// The loading path under fuzzing: bytes -> validated model -> material split -> leaf roots.
//
// Input format (so one input can carry a .gltf and the files beside it): the model's bytes (a .glb
// when they start with "glTF", else .gltf JSON), then optionally sections "\n#file:NAME\n" followed
// by that file's bytes up to the next section (NAME relative to the model, e.g. "tree.bin").
#include <cstddef>
#include <cstdint>

namespace canopy::fuzz {

// Runs one input; traps (a crash to libFuzzer) when a loaded model breaks an invariant the
// renderer relies on. Returns 0.
int runGltfInput(const uint8_t* data, size_t size);

}  // namespace canopy::fuzz
