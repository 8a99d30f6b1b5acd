#!/bin/bash
# ctest: canopy-demo --shadows (issue 54; docs/design.md "Shadows"). With wind (--strength 2) the
# shadow map's caster centroid sways in step with the crown's on-screen centroid (timing.txt's
# correlation >= 0.8) and --debug shadow-map writes the map of every frame; with --strength 0 the
# shadow is still (its centroid's s.d. under 0.01 light px). Validation and synchronization
# validation on: any message fails the run (exit 1).
set -u
demo=$1 out=$2
rm -rf "$out" && mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }

"$demo" --shadows --debug shadow-map --strength 2 --frames 30 --size 160x120 --warmup 0.5 --validate --no-mp4 \
  --out "$out/wind" >"$out/stdout" 2>"$out/stderr" || fail "wind: exit $? ($(tail -5 "$out/stderr"))"
[ -s "$out/wind/frame_0029.png" ] && [ -s "$out/wind/shadow_0029.png" ] || fail "wind: no 30th frame or shadow map"
line=$(grep '^Shadow' "$out/wind/timing.txt") || fail "wind: no Shadow line in timing.txt"
echo "wind: $line"
r=$(echo "$line" | sed -n 's/.*correlation \([-0-9.]*\) over.*/\1/p')
awk -v r="$r" 'BEGIN { exit !(r >= 0.8) }' || fail "wind: correlation $r < 0.8"

"$demo" --shadows --strength 0 --frames 10 --size 160x120 --warmup 0.5 --validate --no-mp4 \
  --out "$out/still" >"$out/stdout_still" 2>"$out/stderr_still" || fail "still: exit $? ($(tail -5 "$out/stderr_still"))"
line=$(grep '^Shadow' "$out/still/timing.txt") || fail "still: no Shadow line in timing.txt"
echo "still: $line"
sd=$(echo "$line" | sed -n 's/.*in the map sways \([0-9.]*\) light px.*/\1/p')
awk -v s="$sd" 'BEGIN { exit !(s < 0.01) }' || fail "still: the shadow moves ($sd light px)"
echo "PASS"
