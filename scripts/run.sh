#!/usr/bin/env bash
# README command 1: install what is missing, build (Release) into build/release, run the main job.
# Until the demo exists this is canopy-smoke: the chosen device and a timed example compute graph.
# Arguments are passed to the program (canopy-smoke --help).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DCANOPY_BUILD_TESTS=OFF >/dev/null
cmake --build build/release --target canopy-smoke
exec ./build/release/canopy-smoke "$@"
