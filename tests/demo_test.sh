#!/bin/bash
# ctest: canopy-demo headless (validation + synchronization validation on) writes its frames,
# contact sheet and timing summary; a generated scene round-trips through canopy-scene's .glb into
# the demo; --window without a display falls back to headless; bad options exit 2 with one line.
set -u
demo=$1 scene=$2 out=$3
rm -rf "$out" && mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }

"$demo" --frames 4 --size 160x120 --warmup 0.2 --validate --no-mp4 --out "$out/headless" >"$out/stdout" 2>"$out/stderr" ||
  fail "headless: exit $? ($(tail -5 "$out/stderr"))"
grep -q "warm-up: 6 frames" "$out/stderr" || fail "no warm-up line: $(cat "$out/stderr")"
for f in frame_0000 frame_0001 frame_0002 frame_0003 contact_sheet; do
  [ -s "$out/headless/$f.png" ] || fail "missing $f.png"
done
grep -q "composite: warp + composite" "$out/headless/timing.txt" || fail "timing.txt lacks the composite pass"
grep -q "wall clock" "$out/headless/timing.txt" || fail "timing.txt lacks the wall-clock line"
grep -q "^Sway (top third" "$out/headless/timing.txt" || fail "timing.txt lacks the sway line"
grep -q "PNG file per frame" "$out/headless/timing.txt" || fail "timing.txt lacks the PNG writing line (the demo's own work)"
grep -q "^Canopy's frame alone" "$out/headless/timing.txt" || fail "timing.txt lacks Canopy's frame measured alone"
echo "headless: $(grep -c . "$out/headless/timing.txt") lines of timing, $(ls "$out/headless" | wc -l) files"

# An output folder with a space and quotes (ffmpeg is run without a shell: nothing is injected);
# a shorter second run into the same folder leaves no frames of the first one behind.
weird="$out/we ird'; touch INJECTED; '"
"$demo" --frames 3 --size 96x72 --warmup 0 --out "$weird" >/dev/null 2>"$out/stderr_w" || fail "quoted folder: exit $?"
"$demo" --frames 2 --size 96x72 --warmup 0 --out "$weird" >/dev/null 2>>"$out/stderr_w" || fail "second run: exit $?"
[ ! -e INJECTED ] && [ ! -e "$out/INJECTED" ] || fail "the output folder's name was run as a command"
[ -s "$weird/frame_0001.png" ] && [ ! -e "$weird/frame_0002.png" ] || fail "frames of the longer first run were left: $(ls "$weird")"
if command -v ffmpeg >/dev/null && command -v ffprobe >/dev/null; then
  n=$(ffprobe -v error -count_frames -select_streams v:0 -show_entries stream=nb_read_frames -of csv=p=0 "$weird/demo.mp4")
  [ "$n" = 2 ] || fail "demo.mp4 has $n frames, expected 2"
  echo "demo.mp4: $n frames"
else
  echo "ffmpeg not installed: demo.mp4 not checked (the demo says so and writes the PNGs)"
fi

# The default wind visibly sways the shrub; no wind leaves it still (the sway is measured by the
# demo on its own frames: the horizontal centroid of the top third of the vegetation).
sway_range() { sed -n 's/^Sway .* range \([0-9.]*\) px.*/\1/p' "$1/timing.txt"; }
"$demo" --frames 24 --size 320x240 --warmup 1 --no-mp4 --out "$out/wind" >/dev/null 2>&1 || fail "wind run: exit $?"
"$demo" --frames 24 --size 320x240 --warmup 1 --strength 0 --no-mp4 --out "$out/calm" >/dev/null 2>&1 || fail "calm run: exit $?"
wind=$(sway_range "$out/wind") calm=$(sway_range "$out/calm")
[ -n "$wind" ] && [ -n "$calm" ] || fail "no sway figures"
awk -v w="$wind" -v c="$calm" 'BEGIN { exit !(w >= 2.0 && c <= 0.25) }' ||
  fail "sway: wind $wind px (expected >= 2), no wind $calm px (expected <= 0.25)"
echo "sway over 24 frames at 320x240: wind $wind px, no wind $calm px"

# Another scene, orbit camera, approximate delay, a debug view, through a .glb written by canopy-scene.
"$scene" --scene kelp --faces 20K --out "$out/kelp.glb" >/dev/null || fail "canopy-scene"
"$demo" --gltf "$out/kelp.glb" --frames 3 --size 128x96 --camera orbit --delay approx --debug velocity --layers 3 \
  --validate --no-mp4 --out "$out/kelp" >"$out/stdout2" 2>"$out/stderr2" || fail "kelp.glb: exit $? ($(tail -5 "$out/stderr2"))"
[ -s "$out/kelp/contact_sheet.png" ] || fail "kelp contact sheet missing"

# A moving camera (a pure rotation), drawn by the policy and re-sliced every frame, wind off:
# --compare-frames measures one against the other (frames identical to themselves: IoU 1).
"$demo" --camera turn --degrees-per-frame 1 --frames 4 --size 160x120 --warmup 0 --strength 0 --validate --no-mp4 \
  --out "$out/turn" >/dev/null 2>"$out/stderr6" || fail "turn: exit $? ($(tail -5 "$out/stderr6"))"
"$demo" --camera turn --degrees-per-frame 1 --frames 4 --size 160x120 --warmup 0 --strength 0 --reslice every-frame \
  --validate --no-mp4 --out "$out/turn_every" >/dev/null 2>"$out/stderr7" || fail "turn every-frame: exit $? ($(tail -5 "$out/stderr7"))"
grep -q "camera turn" "$out/turn_every/timing.txt" && grep -q "every frame re-slices" "$out/turn_every/timing.txt" ||
  fail "timing.txt does not name the path and the every-frame policy"
"$demo" --compare-frames "$out/turn" "$out/turn" >"$out/cmp_same" || fail "--compare-frames: exit $?"
grep -q "^4 frames: IoU min 1.0000" "$out/cmp_same" || fail "a folder against itself: $(tail -1 "$out/cmp_same")"
"$demo" --compare-frames "$out/turn" "$out/turn_every" >"$out/cmp" || fail "--compare-frames: exit $?"
echo "turn 1 deg/frame, policy vs every frame: $(tail -1 "$out/cmp")"
"$demo" --compare-frames "$out/turn" "$out/absent" >/dev/null 2>"$out/err" && fail "--compare-frames with a missing folder passed"

# The per-vertex baseline on the same scene (validation on): it sways in the wind and stands still without.
"$demo" --method per-vertex --frames 16 --size 320x240 --warmup 1 --validate --no-mp4 --out "$out/pv" >/dev/null 2>"$out/stderr4" ||
  fail "per-vertex run: exit $? ($(tail -5 "$out/stderr4"))"
"$demo" --method per-vertex --frames 6 --size 320x240 --warmup 0.5 --strength 0 --no-mp4 --out "$out/pvcalm" >/dev/null 2>&1 ||
  fail "per-vertex calm run: exit $?"
pv=$(sway_range "$out/pv") pvcalm=$(sway_range "$out/pvcalm")
awk -v w="$pv" -v c="$pvcalm" 'BEGIN { exit !(w >= 1.0 && c == 0) }' ||
  fail "per-vertex sway: wind $pv px (expected >= 1), no wind $pvcalm px (expected 0)"
echo "per-vertex sway over 16 frames at 320x240 (no wind: 6 frames): wind $pv px, no wind $pvcalm px"
# The uniform wind of before 0.7 is still reachable and sways too.
"$demo" --method per-vertex --per-vertex-wind uniform --frames 16 --size 320x240 --warmup 1 --no-mp4 --out "$out/pvu" >/dev/null 2>&1 ||
  fail "per-vertex uniform run: exit $?"
pvu=$(sway_range "$out/pvu")
awk -v w="$pvu" 'BEGIN { exit !(w >= 1.0) }' || fail "per-vertex uniform sway: $pvu px (expected >= 1)"

# Impostors (issue 18) on a field, every box with views an impostor, with the debug view (validation on).
"$demo" --scene field --faces 60K --impostors size --impostor-pixels 4096 --impostor-debug --frames 2 --size 160x120 \
  --warmup 0 --validate --no-mp4 --out "$out/imp" >/dev/null 2>"$out/stderr5" || fail "impostors: exit $? ($(tail -5 "$out/stderr5"))"
[ -s "$out/imp/frame_0001.png" ] || fail "impostor frames missing"
# The twelve views and the facing polygon of before 0.7 (validation on).
"$demo" --scene field --faces 60K --impostors size --impostor-pixels 4096 --impostor-views 12 --impostor-shape facing \
  --frames 2 --size 160x120 --warmup 0 --validate --no-mp4 --out "$out/imp12" >/dev/null 2>"$out/stderr8" ||
  fail "impostors, 12 views, facing: exit $? ($(tail -5 "$out/stderr8"))"
[ -s "$out/imp12/frame_0001.png" ] || fail "impostor frames (12 views) missing"

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
expect_refusal "--impostors" --impostors near
expect_refusal "--impostor-views" --impostor-views 8
expect_refusal "--per-vertex-wind" --per-vertex-wind gusty
expect_refusal "--size" --size 10x10
expect_refusal "north" --wind north
expect_refusal "--strength" --strength -1
expect_refusal "--gust" --gust 2
expect_refusal "--warmup" --warmup -1
expect_refusal "--bogus" --bogus
expect_refusal "--method" --method 3d
expect_refusal "spin" --camera spin
expect_refusal "--reslice" --reslice sometimes
"$demo" --help | grep -q -- "--frames N .*default 60" || fail "--help does not document --frames with its default"
"$demo" --help | grep -q -- "--warmup S .*" || fail "--help does not document --warmup"
"$demo" --gltf "$out/absent.glb" --frames 1 >/dev/null 2>"$out/err" && fail "a missing glTF file was accepted"
grep -q "absent.glb" "$out/err" || fail "missing file not named: $(cat "$out/err")"
echo "PASS"
