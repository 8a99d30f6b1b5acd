#!/usr/bin/env bash
# Runs a docs sample that is a whole program (docs/embedding.md's minimal host) as a reader would:
# on a generated plant (canopy-scene writes a .glb: no asset needed), with the Khronos validation
# layer and synchronization validation switched on from outside through the loader's environment
# (the sample itself has no validation code). Any validation message, a non-zero exit or no
# vegetation in the picture fails.
#   doc_sample_test.sh SAMPLE_BINARY CANOPY_SCENE WORK_DIR
set -euo pipefail
sample=$1 scene=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
layer=/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json
if [ ! -f "$layer" ]; then
  echo "the validation layer is not installed ($layer; apt-get install vulkan-validationlayers)" >&2
  exit 1
fi
"$scene" --scene shrub --faces 20000 --out "$work/shrub.glb" >/dev/null
export VK_INSTANCE_LAYERS=VK_LAYER_KHRONOS_validation
export VK_LAYER_ENABLES=VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT
set +e
"$sample" "$work/shrub.glb" "$work/frame.ppm" > "$work/out.txt" 2>&1
rc=$?
set -e
cat "$work/out.txt"
if [ $rc -ne 0 ]; then
  echo "the sample exited with $rc" >&2
  exit 1
fi
if grep -q "Validation" "$work/out.txt"; then
  echo "validation messages above" >&2
  exit 1
fi
test -s "$work/frame.ppm"
echo "PASS: $(basename "$sample") ran with validation and synchronization validation clean"
