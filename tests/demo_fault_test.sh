#!/bin/bash
# ctest: canopy-demo with faults injected into Canopy's Vulkan calls (--inject-fault,
# tools/fault_loader.h): out of device memory at the first allocation, during creation and during
# the frames, and a lost device; each run ends within the timeout with exit 1 and one error line
# naming the failing call and the VkResult, never a crash or a hang.
set -u
demo=$1 out=$2
rm -rf "$out" && mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }
for spec in oom:0 oom:25 oom:60 oom:120 lost:0 lost:40 lost:110; do
  timeout 300 "$demo" --frames 3 --size 96x72 --warmup 0 --no-mp4 --faces 20000 --inject-fault "$spec" --out "$out/run" \
    >"$out/stdout" 2>"$out/stderr"
  rc=$?
  [ "$rc" = 1 ] || fail "$spec: exit $rc, expected 1 ($(tail -3 "$out/stderr"))"
  errors=$(grep -c '^canopy-demo: ' "$out/stderr")
  [ "$errors" = 1 ] || fail "$spec: $errors error lines: $(cat "$out/stderr")"
  line=$(grep '^canopy-demo: ' "$out/stderr")
  case $spec in
    oom:*) want=VK_ERROR_OUT_OF_DEVICE_MEMORY ;;
    lost:*) want=VK_ERROR_DEVICE_LOST ;;
  esac
  echo "$line" | grep -q "$want" || fail "$spec: the error line does not name $want: $line"
  echo "$spec: exit 1: $line"
done
