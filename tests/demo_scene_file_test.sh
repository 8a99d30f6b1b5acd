#!/bin/bash
# ctest: canopy-demo --scene-file (issue 53; docs/scene-files.md). The generated forest clearing of
# demo/scenes (no assets needed) walks 6 frames with its 4 species in one vegetation; the six-species
# scene of ../shared/assets walks 30 frames with every species in view, then again with far copies as
# impostors (skipped with a message where the folder is absent); a broken scene file is refused in one line naming the file and the JSON
# pointer. Validation and synchronization validation on: any message fails the run (exit 1).
set -u
demo=$1 scenes=$2 assets=$3 out=$4
rm -rf "$out" && mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }

"$demo" --scene-file "$scenes/forest_clearing.json" --camera walk --frames 6 --size 160x120 --warmup 0.2 --validate --no-mp4 \
  --out "$out/clearing" >"$out/stdout" 2>"$out/stderr" || fail "forest clearing: exit $? ($(tail -5 "$out/stderr"))"
[ -s "$out/clearing/frame_0005.png" ] || fail "forest clearing: no sixth frame"
grep -q "^species: 4, copies: 69;" "$out/clearing/timing.txt" || fail "forest clearing: $(grep '^species' "$out/clearing/timing.txt")"
echo "forest clearing: $(grep '^species' "$out/clearing/timing.txt")"

printf '{ "species": [ { "name": "a", "generated": "shrub" } ],\n  "instances": [ { "species": "a", "position": [0, 0, 0], "scale": -1 } ] }\n' \
  >"$out/bad.json"
"$demo" --scene-file "$out/bad.json" --frames 1 --out "$out/bad" >/dev/null 2>"$out/bad_stderr"
rc=$?
[ $rc = 1 ] || fail "a bad scene file: exit $rc"
grep -q "bad.json.*/instances/0/scale" "$out/bad_stderr" || fail "the refusal does not name the file and pointer: $(cat "$out/bad_stderr")"
echo "refused: $(head -1 "$out/bad_stderr")"

if [ ! -d "$assets" ]; then
  echo "SKIP the six-species scene: $assets is absent"
  exit 0
fi
"$demo" --scene-file "$scenes/six_species.json" --camera walk --frames 30 --size 320x240 --warmup 0.2 --validate --no-mp4 \
  --out "$out/six" >"$out/stdout_six" 2>"$out/stderr_six" || fail "six species: exit $? ($(tail -5 "$out/stderr_six"))"
[ -s "$out/six/frame_0029.png" ] || fail "six species: no 30th frame"
grep -q "^species: 6, copies: 338; in the last re-slice's view: [0-9]* copies of 6 species" "$out/six/timing.txt" ||
  fail "six species: $(grep '^species' "$out/six/timing.txt")"
echo "six species: $(grep '^species' "$out/six/timing.txt")"

# The per-vertex baseline on the six species (issue 66): each species bends through its own
# hierarchy or about its own trunk; validation on.
"$demo" --scene-file "$scenes/six_species.json" --method per-vertex --frames 3 --size 160x120 --warmup 0 --validate --no-mp4 \
  --out "$out/six_pv" >"$out/stdout_six_pv" 2>"$out/stderr_six_pv" || fail "six species, per-vertex: exit $? ($(tail -5 "$out/stderr_six_pv"))"
[ -s "$out/six_pv/frame_0002.png" ] || fail "six species, per-vertex: no 3rd frame"
grep -q "^species: 6, copies: 338" "$out/six_pv/timing.txt" || fail "six species, per-vertex: $(grep '^species' "$out/six_pv/timing.txt")"
grep -q "per-vertex: draw" "$out/six_pv/timing.txt" || fail "six species, per-vertex: no per-vertex draw timed"
echo "six species, per-vertex baseline: 3 frames, $(grep '^species' "$out/six_pv/timing.txt" | cut -d';' -f1)"

# The same walk with far copies drawn as impostors of their species (each species' boxes baked once).
"$demo" --scene-file "$scenes/six_species.json" --camera walk --frames 30 --size 320x240 --warmup 0.2 --validate --no-mp4 \
  --impostors far --out "$out/six_far" >"$out/stdout_six_far" 2>"$out/stderr_six_far" ||
  fail "six species, impostors far: exit $? ($(tail -5 "$out/stderr_six_far"))"
[ -s "$out/six_far/frame_0029.png" ] || fail "six species, impostors far: no 30th frame"
grep -q "^species: 6, copies: 338; in the last re-slice's view: [0-9]* copies of 6 species" "$out/six_far/timing.txt" ||
  fail "six species, impostors far: $(grep '^species' "$out/six_far/timing.txt")"
grep -q "^impostors: [0-9]* boxes baked; the last re-slice drew [1-9][0-9]* as impostors .* for [1-9][0-9]* copies" "$out/six_far/timing.txt" ||
  fail "six species, impostors far: no copy drawn as an impostor: $(grep '^impostors' "$out/six_far/timing.txt")"
echo "six species, impostors far: $(grep '^impostors' "$out/six_far/timing.txt")"
