#!/bin/bash
# ctest: canopy-demo --scene field --pusher line (issue 55; docs/design.md "Pushers"): a sphere walks
# across the field; --compare-frames against the same run without it writes difference.png and
# counts the pixels that differ by more than 8 levels inside the band 3 radii around the sphere's
# screen path and beyond it: some inside (the grass parts), at most 5 % of them beyond. Validation
# and synchronization validation on: any message fails the run (exit 1).
set -u
demo=$1 out=$2
rm -rf "$out" && mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }
for run in push still; do
  extra=""
  [ "$run" = push ] && extra="--pusher line"
  # The wind as 0.7 blew it (the plane's left side, the demo's former defaults): the band is measured against it.
  "$demo" --scene field $extra --wind left --strength 2 --frequency 0.5 --modulation 0.8 --frames 40 --size 320x240 --warmup 0.5 --validate --no-mp4 --out "$out/$run" \
    >"$out/stdout_$run" 2>"$out/stderr_$run" || fail "$run: exit $? ($(tail -5 "$out/stderr_$run"))"
done
[ -s "$out/push/pusher_path.txt" ] || fail "no pusher_path.txt"
"$demo" --compare-frames "$out/push" "$out/still" >"$out/compare" 2>&1 || fail "--compare-frames: exit $?"
line=$(grep '^pusher band' "$out/compare") || fail "no pusher band line"
echo "$line"
[ -s "$out/push/difference.png" ] || fail "no difference.png"
inside=$(echo "$line" | sed -n 's/.*: \([0-9]*\) pixels differ by > 8 levels inside it.*/\1/p')
share=$(echo "$line" | sed -n 's/.*(\([0-9.]*\) % of the differing pixels beyond).*/\1/p')
awk -v n="$inside" 'BEGIN { exit !(n >= 200) }' || fail "the grass does not part ($inside pixels inside the band)"
awk -v s="$share" 'BEGIN { exit !(s <= 5.0) }' || fail "$share % of the differing pixels beyond the band"
echo "PASS"
