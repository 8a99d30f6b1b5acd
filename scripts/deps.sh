#!/usr/bin/env bash
# Installs the Debian packages Canopy needs when any is missing (as root), or prints the exact
# apt-get line and stops (not root). Sourced by scripts/run.sh and scripts/test.sh.
# Usage: scripts/deps.sh [extra packages...]
set -euo pipefail
packages=(cmake ninja-build g++ pkg-config
  libvulkan-dev mesa-vulkan-drivers vulkan-validationlayers vulkan-tools
  glslang-tools glslang-dev libglm-dev libglfw3-dev libtinygltf-dev nlohmann-json3-dev libstb-dev
  libgtest-dev xvfb xauth libx11-dev libxrandr-dev libxcb1-dev
  libdraco-dev libmeshoptimizer-dev libwebp-dev "$@")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
line="apt-get install -y --no-install-recommends ${missing[*]}"
if [ "$(id -u)" -ne 0 ]; then
  echo "canopy: missing packages. Run as root:" >&2
  echo "  apt-get update && $line" >&2
  exit 1
fi
echo "canopy: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
