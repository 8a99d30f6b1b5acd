#!/usr/bin/env bash
# Fuzzes the glTF loading path (bytes -> validated model -> material split -> leaf roots,
# tests/fuzz/) with libFuzzer, clang, AddressSanitizer and UBSan, tinygltf compiled in with the
# same sanitizers; any report halts the run. Seeds: ../shared/assets (malformed corpus and sample
# models, with the files beside them) and tests/fuzz/regressions; dictionary tests/fuzz/gltf.dict.
#   scripts/fuzz.sh [SECONDS]      (default 300; FUZZ_JOBS worker processes, default nproc;
#                                  FUZZ_MAX_LEN longest input, default 65536)
# Prints executions, coverage and crashes, appends them to tests/fuzz/runs.tsv, and copies every
# crashing input into tests/fuzz/regressions/ (ctest FuzzRegressions replays them all).
#   scripts/fuzz.sh scene [SECONDS] the scene-file parser instead (canopy_scene_fuzz; seeds: demo/scenes
#                                  and tests/fuzz/scenes; runs in tests/fuzz/runs_scene.tsv)
# FUZZ_BUILD=DIR builds and runs in DIR (default build/fuzz); FUZZ_RECORD=0 leaves the tree as it is
# (no row in the runs file, crashing inputs kept in DIR/crashes only): ctest FuzzBounded.
set -euo pipefail
cd "$(dirname "$0")/.."
target=gltf
if [ "${1:-}" = scene ]; then target=scene; shift; fi
seconds=${1:-300}
jobs=${FUZZ_JOBS:-$(nproc)}
if ! command -v clang++ >/dev/null; then
  echo "installing clang (libFuzzer)"; apt-get install -y -qq clang >/dev/null
fi
out=${FUZZ_BUILD:-build/fuzz}
record=${FUZZ_RECORD:-1}
cmake -S tests/fuzz -B "$out" -G Ninja -DCMAKE_CXX_COMPILER=clang++ >/dev/null
cmake --build "$out" >/dev/null
rm -rf "$out/seeds" "$out/crashes"
mkdir -p "$out/corpus" "$out/crashes"
runs=tests/fuzz/runs.tsv
binary=canopy_gltf_fuzz
dict=gltf.dict
if [ "$target" = scene ]; then
  runs=tests/fuzz/runs_scene.tsv
  binary=canopy_scene_fuzz
  dict=scene.dict
  mkdir -p "$out/seeds" "$out/corpus_scene"
  cp demo/scenes/*.json tests/fuzz/scenes/* "$out/seeds/" 2>/dev/null || true
elif [ -d ../shared/assets ]; then
  python3 scripts/fuzz_seeds.py ../shared/assets "$out/seeds" tests/fuzz/regressions
  cp tests/data/compressed/*.glb "$out/seeds/"  # the compressed files (Draco, meshopt, WebP, texture transform)
else
  echo "../shared/assets absent: seeding from tests/fuzz/regressions only"
  mkdir -p "$out/seeds"; cp tests/fuzz/regressions/* "$out/seeds/" 2>/dev/null || true
  cp tests/data/compressed/*.glb "$out/seeds/"
fi
# One libFuzzer process per worker on a shared corpus (fork mode restarts its children every few
# seconds and costs half the executions); each stops at the first report.
rm -f "$out"/fuzz-*.log
set +e
corpus=corpus
[ "$target" = scene ] && corpus=corpus_scene
dictPath=$(pwd)/tests/fuzz/$dict
(cd "$out" && ./$binary -jobs="$jobs" -workers="$jobs" -max_total_time="$seconds" -max_len="${FUZZ_MAX_LEN:-65536}" -timeout=20 \
  -rss_limit_mb=2048 -dict="$dictPath" -artifact_prefix=crashes/ -print_final_stats=1 \
  $corpus seeds > last_run.log 2>&1)
rc=$?
set -e
execs=0 cov=0
logs=("$out"/fuzz-*.log)
[ -f "${logs[0]}" ] || logs=("$out/last_run.log")  # one job runs in-process: its log is last_run.log
for l in "${logs[@]}"; do
  n=$(grep -aE '^stat::number_of_executed_units:' "$l" | awk '{print $2}' | tail -1)
  [ -n "$n" ] || n=$(grep -aoE '^#[0-9]+' "$l" | tail -1 | tr -d '#')
  execs=$((execs + ${n:-0}))
  c=$(grep -aoE 'cov: [0-9]+' "$l" | tail -1 | awk '{print $2}')
  [ "${c:-0}" -gt "$cov" ] && cov=$c
done
corp=$(find "$out/$corpus" -type f | wc -l)
crashes=$(find "$out/crashes" -type f | wc -l)
keep=tests/fuzz/regressions
[ "$target" = scene ] && keep=tests/fuzz/scenes
if [ "$record" = 1 ]; then
  for f in "$out"/crashes/*; do
    [ -f "$f" ] && cp "$f" $keep/ && echo "kept $(basename "$f") in $keep/"
  done
  [ -f $runs ] || printf 'date\tseconds\tjobs\texecutions\tcoverage\tcorpus\tcrashes\tcommit\n' > $runs
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$(date -u +%FT%TZ)" "$seconds" "$jobs" "${execs:-0}" "${cov:-0}" "${corp:-0}" \
    "$crashes" "$(git rev-parse --short HEAD 2>/dev/null || echo -)" >> $runs
fi
total=$(awk -F'\t' 'NR > 1 { s += $4 } END { print s + 0 }' $runs)
echo "fuzz $target: ${execs:-0} executions in ${seconds} s on $jobs workers, coverage ${cov:-?}, corpus ${corp:-?}, crashes $crashes (libFuzzer exit $rc); all runs in $runs: $total executions"
[ "$crashes" -eq 0 ] || { grep -ahE -A30 'ERROR|runtime error|deadly signal' "${logs[@]}" | head -60; exit 1; }
