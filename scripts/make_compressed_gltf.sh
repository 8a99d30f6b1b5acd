#!/usr/bin/env bash
# Makes the compressed glTF test files (issue 78) from ../shared/assets with the public tools people
# compress with: gltf-transform (Draco, WebP) and gltfpack (meshopt, quantization with
# KHR_texture_transform), pinned versions from the npm registry, installed into a temporary folder.
# The outputs are small (about 60 KB each, mostly the model's own PNG atlas) and committed to
# tests/data/compressed/, with their licence; the tests read them, never the network.
#   bash scripts/make_compressed_gltf.sh [ASSETS_DIR]     (default: ../shared/assets)
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
assets=${1:-$here/../shared/assets}
src=$assets/kaykit_tree_1_c/Tree_1_C_Color1.gltf   # CC0 (KayKit Forest Nature Pack)
out=$here/tests/data/compressed
[ -f "$src" ] || { echo "make_compressed_gltf: $src not found (pass the assets folder)" >&2; exit 1; }
tools=$(mktemp -d)
trap 'rm -rf "$tools"' EXIT
(cd "$tools" && npm install --no-audit --no-fund --silent @gltf-transform/cli@4.5.1 gltfpack@1.3.0 >/dev/null)
bin=$tools/node_modules/.bin
mkdir -p "$out"
"$bin/gltf-transform" draco "$src" "$out/kaykit_draco.glb"        # KHR_draco_mesh_compression
"$bin/gltf-transform" webp "$src" "$out/kaykit_webp.glb"          # EXT_texture_webp
"$bin/gltfpack" -i "$src" -o "$out/kaykit_meshopt.glb" -cc        # EXT_meshopt_compression (+ quantization, KHR_texture_transform)
"$bin/gltfpack" -i "$src" -o "$out/kaykit_quantized.glb"          # KHR_mesh_quantization + KHR_texture_transform
cp "$assets/kaykit_tree_1_c/License.txt" "$out/License.txt"
ls -l "$out"
