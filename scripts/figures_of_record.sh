#!/usr/bin/env bash
# The figures of record in one command, on whatever Vulkan device is present (docs/performance.md
# "The figures of record on any device"): the device (canopy-smoke: name, driver, subgroup size),
# the correctness subset that matters on a new driver (the simulation and the composite against
# their CPU references, the dynamics, the goldens, reprojection), the paper's Table 1 (still, orbit
# and every-frame re-slices), the moving-camera bench, the work counted per frame kind and the
# pacing of a moving camera (re-slices at once and paced), written
# to OUT as JSON and CSV with a one-page summary (OUT/summary.md).
#   scripts/figures_of_record.sh [--device NAME] [--build DIR] [--reduced] OUT
# --build: a configured build tree with the tests (default build/figures, configured Release and
# built here when missing); --reduced: small sizes and few frames (CI runs it so, so it cannot rot).
set -euo pipefail
cd "$(dirname "$0")/.."
device="" build="build/figures" reduced=0 out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --device) device="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --reduced) reduced=1; shift ;;
    -h|--help) sed -n '2,10p' "$0"; exit 0 ;;
    *) out="$1"; shift ;;
  esac
done
[ -n "$out" ] || { echo "usage: scripts/figures_of_record.sh [--device NAME] [--build DIR] [--reduced] OUT" >&2; exit 2; }
mkdir -p "$out"
start=$(date +%s)
if [ ! -x "$build/canopy-bench" ] || [ ! -x "$build/tests/canopy_gpu_tests" ]; then
  bash scripts/deps.sh
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$build" --target canopy-bench canopy-smoke canopy_gpu_tests
fi
[ -n "$device" ] && export CANOPY_DEVICE="$device"
dev=(); [ -n "$device" ] && dev=(--device "$device")

echo "== device"
"$build/canopy-smoke" --frames 3 --size 256x256 "${dev[@]}" | grep -E '^(Device|Driver)' | tee "$out/device.txt"

echo "== correctness subset"
subset='Steps/SimAgreement.*:DynamicsTest.DisplacementMatchesTheCpuReference:CompositeTest.MatchesTheCpuReference*:Scenes/GoldenTest.*:CanopyTest.ReprojectedLayersMatchLayersDrawnAtTheNewCamera:CountersTest.*'
# Reduced (ctest FiguresOfRecordReduced): one test of each kind, so that the script's steps cannot
# rot; ctest runs the whole subset itself (CorrectnessSubsetGpuClass, CorrectnessSubsetWidth4).
[ $reduced = 1 ] && subset='Steps/SimAgreement.*Stam_1steps*:DynamicsTest.DisplacementMatchesTheCpuReference:CompositeTest.MatchesTheCpuReference*:CountersTest.*'
set +e
"$build/tests/canopy_gpu_tests" --gtest_filter="$subset" --gtest_output="json:$out/correctness.json" >"$out/correctness.log" 2>&1
tests_rc=$?
set -e
grep -E '^\[  (PASSED|FAILED) ' "$out/correctness.log" | tee "$out/correctness.txt"

if [ $reduced = 1 ]; then
  t1=(--faces 80000 --frames 4 --pair-frames 3 --size 320x240) cam=(--faces 80000 --frames 6 --size 320x240 --paths orbit,dolly)
  cnt=(--faces 80000 --size 320x240) pace=(--faces 80000 --paths orbit --degrees-list 0.25 --frames 6 --size 320x240 --no-reference)
else
  t1=(--faces 80000,1000000) cam=(--faces 80000 --size 1024x768 --paths orbit,dolly) cnt=()
  pace=(--faces 80000 --paths orbit,dolly,strafe,turn --frames 120)
fi
echo "== Table 1"
"$build/canopy-bench" table1 "${t1[@]}" "${dev[@]}" --json "$out/table1.json" >"$out/table1.txt" 2>&1
echo "== camera"
"$build/canopy-bench" camera "${cam[@]}" "${dev[@]}" --csv "$out/camera.csv" >"$out/camera.txt" 2>&1
echo "== counters"
"$build/canopy-bench" counters "${cnt[@]}" "${dev[@]}" --json "$out/counters.json" >"$out/counters.txt" 2>&1
echo "== pacing (re-slices at once, then paced)"
for mode in off on; do
  "$build/canopy-bench" pacing "${pace[@]}" --paced $mode "${dev[@]}" --json "$out/pacing_$mode.json" >"$out/pacing_$mode.txt" 2>&1
done

{
  echo "# Figures of record"
  echo
  echo "$(date -u +%Y-%m-%dT%H:%MZ), commit $(git rev-parse --short HEAD 2>/dev/null || echo unknown), $([ $reduced = 1 ] && echo reduced || echo full), $(( $(date +%s) - start )) s"
  echo
  echo '## Device'; echo; sed 's/^/    /' "$out/device.txt"; echo
  echo '## Correctness subset'; echo; sed 's/^/    /' "$out/correctness.txt"; echo
  echo '## Table 1 (canopy-bench table1)'; echo; grep -E '^ *[0-9]+(K|M)? ' "$out/table1.txt" | head -20 | sed 's/^/    /'; echo
  echo '## Moving camera (canopy-bench camera)'; echo; grep -E 'still camera|^  path|^  Reprojected frames|^  (orbit|dolly|strafe|turn|zoom|walk) ' "$out/camera.txt" | sed 's/^/    /'; echo
  echo '## Work per frame, counted (canopy-bench counters)'; echo; grep -E '^  [0-9]' "$out/counters.txt" | sed 's/^/    /'; echo
  for mode in off on; do
    echo "## Pacing, --paced $mode (canopy-bench pacing)"; echo; grep -E '^  (path|orbit|dolly|strafe|turn) ' "$out/pacing_$mode.txt" | sed 's/^/    /'; echo
  done
} >"$out/summary.md"
echo "wrote $out/summary.md ($(( $(date +%s) - start )) s)"
exit $tests_rc
