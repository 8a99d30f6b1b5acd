#!/usr/bin/env bash
# cmake --install of the build tree into a fresh prefix, then a separate project that does
# find_package(Canopy) and links Canopy::canopy is configured, built and run.
#   install_consumer_test.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build=$1 src=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
test -f "$work/prefix/include/canopy/render/canopy.h"
test -f "$work/prefix/lib/cmake/Canopy/CanopyConfig.cmake"
if find "$work/prefix/include" -name '*_reference.h' | grep -q .; then
  echo "test-only reference headers were installed" >&2
  exit 1
fi
cmake -S "$src/tests/consumer" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null
cmake --build "$work/build" >/dev/null
"$work/build/canopy_consumer"
