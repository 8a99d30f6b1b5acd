#!/bin/bash
# ctest: canopy-demo --window under Xvfb on whatever Vulkan device is present (lavapipe in CI):
# opens, renders, is resized (swapchain and targets recreated), closes after N frames, with
# validation + synchronization validation clean; the last frame, read back from the swapchain
# image, must not be blank (the demo checks that itself and exits 1 otherwise).
set -u
demo=$1 out=$2
command -v xvfb-run >/dev/null || { echo "xvfb-run not installed (scripts/deps.sh installs xvfb): skipped"; exit 77; }
rm -rf "$out" && mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }
xvfb-run -a -s "-screen 0 1024x768x24" "$demo" --window --frames 16 --resize-at 6 --size 320x240 --validate \
  --screenshot "$out/window.png" --out "$out" >"$out/stdout" 2>"$out/stderr" || fail "exit $? ($(tail -5 "$out/stderr"))"
cat "$out/stdout"
grep -q "swapchain 320x240" "$out/stdout" || fail "no initial swapchain"
grep -q "swapchain 240x180" "$out/stdout" || fail "the swapchain was not recreated at the new size"
grep -q "Canopy resized to 240x180: scene and simulation kept ([1-9][0-9]* steps so far)" "$out/stdout" ||
  fail "the resize did not keep Canopy's context"
grep -q "window closed after 16 frames" "$out/stdout" || fail "did not close after 16 frames"
[ -s "$out/window.png" ] || fail "no screenshot"
echo "PASS"
