#!/usr/bin/env bash
# README command 2: install what is missing, build the test configuration (AddressSanitizer +
# UBSan) into build/test, run the whole suite with ctest. GPU tests use whatever Vulkan device is
# present (lavapipe on a machine without a GPU) with validation and synchronization validation on.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh clang libclang-rt-14-dev  # clang and libFuzzer: ctest FuzzBounded
cmake -S . -B build/test -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCANOPY_SANITIZE=ON >/dev/null
cmake --build build/test
ctest --test-dir build/test --output-on-failure -j"$(nproc)" "$@"
