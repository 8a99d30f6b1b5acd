// libFuzzer's entry point for canopy_gltf_fuzz (scripts/fuzz.sh builds it with clang, ASan, UBSan).
#include "tests/fuzz/gltf_fuzz.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) { return canopy::fuzz::runGltfInput(data, size); }
