#!/bin/bash
# ctest: canopy-layers on a real model writes its PNGs; a refused file and a bad option each exit
# non-zero with exactly one line on stderr naming the problem. Skips (77) without ../shared/assets.
set -u
tool=$1 assets=$2 out=$3
[ -d "$assets" ] || { echo "shared assets folder absent ($assets): skipped"; exit 77; }
rm -rf "$out" && mkdir -p "$out"
fail() { echo "FAIL: $*"; exit 1; }

"$tool" "$assets/DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf" --layers '5(3-1-1)' --size 320x240 \
  --out "$out/plant" --cache-dir "$out/cache" >"$out/stdout" 2>"$out/stderr" || fail "real model: exit $? ($(cat "$out/stderr"))"
for f in layer_00 layer_01 layer_02 layer_03 layer_04 background layers_false_colour composite; do
  [ -s "$out/plant/$f.png" ] || fail "missing $f.png"
done
grep -q "Leaves: 36" "$out/stdout" || fail "leaf count line missing: $(cat "$out/stdout")"
# Second run reads the leaf-root cache.
"$tool" "$assets/DiffuseTransmissionPlant/DiffuseTransmissionPlant.gltf" --size 64x48 --out "$out/plant2" \
  --cache-dir "$out/cache" >"$out/stdout2" 2>&1 || fail "second run"
grep -q "(read .*leafroots)" "$out/stdout2" || fail "cache not read: $(cat "$out/stdout2")"

expect_refusal() {  # expected-exit-code pattern args...
  local code=$1 pattern=$2; shift 2
  "$tool" "$@" >/dev/null 2>"$out/err"
  local rc=$?
  [ $rc -eq "$code" ] || fail "'$*': exit $rc, expected $code"
  [ "$(wc -l <"$out/err")" -eq 1 ] || fail "'$*': stderr is not one line: $(cat "$out/err")"
  grep -q "^canopy-layers: .*$pattern" "$out/err" || fail "'$*': stderr does not name '$pattern': $(cat "$out/err")"
  echo "refused as expected: $(cat "$out/err")"
}
# A hand-made file whose accessor runs past its buffer view.
cat >"$out/bad.gltf" <<'GLTF'
{"asset":{"version":"2.0"},"scenes":[{"nodes":[0]}],"scene":0,"nodes":[{"mesh":0}],
 "meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],
 "buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
 "bufferViews":[{"buffer":0,"byteLength":36}],
 "accessors":[{"bufferView":0,"componentType":5126,"count":30,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}]}
GLTF
expect_refusal 1 "accessors\[0\]" "$out/bad.gltf" --out "$out/x"
expect_refusal 1 "cannot open" "$out/absent.glb" --out "$out/x"
expect_refusal 1 "names no material" "$assets/fern_02/fern_02.glb" --rigid Bark --out "$out/x"
expect_refusal 2 "layer layout '6(3-1-1)'" "$assets/fern_02/fern_02.glb" --layers '6(3-1-1)'
expect_refusal 2 "--size" "$assets/fern_02/fern_02.glb" --size 0x10
echo "canopy-layers CLI: all checks passed"
