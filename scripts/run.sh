#!/usr/bin/env bash
# README command 1: install what is missing, build every program (Release, no tests) into
# build/release, run the demo headless on its built-in default scene (an 80K-face shrub, generated, no asset needed): frames,
# contact sheet and per-pass timing go to demo_out/ (and demo_out/demo.mp4 with ffmpeg).
# Arguments are passed to the demo (canopy-demo --help), e.g. --window for a live window.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/deps.sh
cmake -S . -B build/release -G Ninja -DCMAKE_BUILD_TYPE=Release -DCANOPY_BUILD_TESTS=OFF >/dev/null
cmake --build build/release
exec ./build/release/canopy-demo "$@"
