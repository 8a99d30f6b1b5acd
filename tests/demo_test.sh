#!/bin/bash
# ctest: canopy-demo headless (validation + synchronization validation on) writes its frames,
# contact sheet and timing summary; a generated scene round-trips through canopy-scene's .glb into
# the demo; --window without a display falls back to headless; bad options exit 2 with one line.
set -u
demo=$1 scene=$2 out=$3
rm -rf "$out" && mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }

"$demo" --frames 4 --size 160x120 --validate --no-mp4 --out "$out/headless" >"$out/stdout" 2>"$out/stderr" ||
  fail "headless: exit $? ($(tail -5 "$out/stderr"))"
for f in frame_0000 frame_0001 frame_0002 frame_0003 contact_sheet; do
  [ -s "$out/headless/$f.png" ] || fail "missing $f.png"
done
grep -q "composite: warp + composite" "$out/headless/timing.txt" || fail "timing.txt lacks the composite pass"
grep -q "wall clock" "$out/headless/timing.txt" || fail "timing.txt lacks the wall-clock line"
echo "headless: $(grep -c . "$out/headless/timing.txt") lines of timing, $(ls "$out/headless" | wc -l) files"

# Another scene, orbit camera, approximate delay, a debug view, through a .glb written by canopy-scene.
"$scene" --scene kelp --faces 20K --out "$out/kelp.glb" >/dev/null || fail "canopy-scene"
"$demo" --gltf "$out/kelp.glb" --frames 3 --size 128x96 --camera orbit --delay approx --debug velocity --layers 3 \
  --validate --no-mp4 --out "$out/kelp" >"$out/stdout2" 2>"$out/stderr2" || fail "kelp.glb: exit $? ($(tail -5 "$out/stderr2"))"
[ -s "$out/kelp/contact_sheet.png" ] || fail "kelp contact sheet missing"

# No display: --window says so and renders headless.
env -u DISPLAY -u WAYLAND_DISPLAY "$demo" --window --frames 2 --size 96x72 --no-mp4 --out "$out/fallback" \
  >/dev/null 2>"$out/stderr3" || fail "fallback: exit $?"
grep -q "running headless instead" "$out/stderr3" || fail "no fallback message: $(cat "$out/stderr3")"
[ -s "$out/fallback/frame_0001.png" ] || fail "fallback frames missing"

expect_refusal() {  # pattern args...
  local pattern=$1; shift
  "$demo" "$@" >/dev/null 2>"$out/err"
  local rc=$?
  [ $rc -eq 2 ] || fail "'$*': exit $rc, expected 2"
  [ "$(wc -l <"$out/err")" -eq 1 ] || fail "'$*': stderr is not one line: $(cat "$out/err")"
  grep -q -- "^canopy-demo: .*$pattern" "$out/err" || fail "'$*': stderr does not name '$pattern': $(cat "$out/err")"
  echo "refused as expected: $(cat "$out/err")"
}
expect_refusal "--frames" --frames 0
expect_refusal "--layers" --layers "5(3-1)"
expect_refusal "palm" --scene palm
expect_refusal "--size" --size 10x10
expect_refusal "north" --wind north
expect_refusal "--strength" --strength -1
expect_refusal "--bogus" --bogus
"$demo" --help | grep -q -- "--frames N .*default 48" || fail "--help does not document --frames with its default"
"$demo" --gltf "$out/absent.glb" --frames 1 >/dev/null 2>"$out/err" && fail "a missing glTF file was accepted"
grep -q "absent.glb" "$out/err" || fail "missing file not named: $(cat "$out/err")"
echo "PASS"
