#!/bin/bash
# ctest FuzzBounded: the two libFuzzer targets (glTF loading, scene files; tests/fuzz/) for a bounded
# time each, in a build folder of the test's own and without touching the tree (FUZZ_RECORD=0):
# any sanitizer report or crash fails. scripts/test.sh installs clang and libFuzzer (scripts/deps.sh).
set -u
src=$1 out=$2 seconds=${3:-20}
command -v clang++ >/dev/null || { echo "FAIL: clang++ not installed (scripts/test.sh installs it)"; exit 1; }
for target in gltf scene; do
  args=("$seconds")
  [ "$target" = scene ] && args=(scene "$seconds")
  FUZZ_BUILD="$out" FUZZ_RECORD=0 FUZZ_JOBS=1 bash "$src/scripts/fuzz.sh" "${args[@]}" >"$out.$target.log" 2>&1
  rc=$?
  line=$(grep "^fuzz $target:" "$out.$target.log")
  [ $rc -eq 0 ] && [ -n "$line" ] || { echo "FAIL: $target (exit $rc)"; tail -40 "$out.$target.log"; exit 1; }
  echo "$line"
  execs=$(echo "$line" | sed -n 's/^fuzz [a-z]*: \([0-9]*\) executions.*/\1/p')
  [ "${execs:-0}" -gt 0 ] || { echo "FAIL: $target ran no input"; exit 1; }
done
