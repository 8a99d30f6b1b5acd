#!/usr/bin/env bash
# cmake --install of the build tree into a fresh prefix; the installed public header compiles alone
# with no include path but the prefix; the install holds no internal header and its package needs
# none of tinygltf, nlohmann-json or GLFW; then a separate C++17 project does find_package(Canopy),
# links Canopy::canopy, and runs (own device, adoption, refusals, a context), and the example host
# built from that prefix alone runs its self-check.
#   install_consumer_test.sh BUILD_DIR SOURCE_DIR WORK_DIR
set -euo pipefail
build=$1 src=$2 work=$3
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
inc="$work/prefix/include"
test -f "$inc/canopy/canopy.h"
test -f "$inc/canopy/canopy_graph.h"
test -f "$inc/canopy/canopy_core.h"
test -f "$inc/canopy/canopy_params.h"
test -f "$work/prefix/lib/cmake/Canopy/CanopyConfig.cmake"
extra=$(cd "$inc" && find . -type f ! -path './canopy/*' | head -5)
if [ -n "$extra" ] || [ -d "$inc/canopy/engine" ] || [ -d "$inc/canopy/render" ] || [ -d "$inc/canopy/compute" ]; then
  echo "internal headers were installed: $extra" >&2
  exit 1
fi
if grep -Eiq 'tinygltf|nlohmann|glfw' "$work/prefix/lib/cmake/Canopy/"*.cmake; then
  echo "the installed package refers to tinygltf, nlohmann-json or GLFW" >&2
  exit 1
fi
echo '#include <canopy/canopy.h>
int main() { return canopy::libraryVersion() == CANOPY_HEADER_VERSION ? 0 : 1; }' > "$work/alone.cpp"
c++ -std=c++17 -Wall -Wextra -Werror -fsyntax-only -I"$inc" "$work/alone.cpp"
echo '#include <canopy/canopy_graph.h>
int main() { std::vector<canopy::CanopyTargetUse> u; return canopy::canopyPassGroupUses(nullptr, &u).ok() ? 1 : 0; }' > "$work/graph_alone.cpp"
c++ -std=c++17 -Wall -Wextra -Werror -fsyntax-only -I"$inc" "$work/graph_alone.cpp"
echo '#include <canopy/canopy_core.h>
int main() { canopy::Status s; canopy::ResourceState r; (void)r; return s.ok() ? 0 : 1; }' > "$work/core_alone.cpp"
c++ -std=c++17 -Wall -Wextra -Werror -fsyntax-only -I"$inc" "$work/core_alone.cpp"
echo '#include <canopy/canopy_params.h>
int main() { canopy::CanopyDesc d; return canopy::checkParams(d).ok() ? 0 : 1; }' > "$work/params_alone.cpp"
c++ -std=c++17 -Wall -Wextra -Werror -fsyntax-only -I"$inc" "$work/params_alone.cpp"
echo "the public headers compile alone (C++17, -I$inc only)"
# The version policy (docs/embedding.md "Versions"): below 1.0 a minor version breaks the API, so
# a host asking for an older minor version (or a newer one) is refused at configure time.
major=$(sed -n 's/^#define CANOPY_VERSION_MAJOR \([0-9]*\)$/\1/p' "$inc/canopy/canopy_core.h")
minor=$(sed -n 's/^#define CANOPY_VERSION_MINOR \([0-9]*\)$/\1/p' "$inc/canopy/canopy_core.h")
for asked in "$major.$((minor - 1))" "$major.$((minor + 1))" "$major.$minor"; do
  mkdir -p "$work/asks_$asked"
  printf 'cmake_minimum_required(VERSION 3.20)\nproject(AsksCanopy LANGUAGES CXX)\nfind_package(Canopy %s REQUIRED)\n' "$asked" \
    > "$work/asks_$asked/CMakeLists.txt"
  if cmake -S "$work/asks_$asked" -B "$work/asks_$asked/build" -DCMAKE_PREFIX_PATH="$work/prefix" > "$work/asks_$asked.log" 2>&1; then
    result=accepted
  else
    result=refused
  fi
  expected=refused
  [ "$asked" = "$major.$minor" ] && expected=accepted
  echo "find_package(Canopy $asked) against the installed $major.$minor: $result"
  if [ "$result" != "$expected" ]; then
    echo "expected $expected; the configure log:" >&2
    cat "$work/asks_$asked.log" >&2
    exit 1
  fi
done
grep -q "version: $major.$minor" "$work/asks_$major.$((minor - 1)).log" || { echo "the refusal does not name the installed version" >&2; cat "$work/asks_$major.$((minor - 1)).log" >&2; exit 1; }
cmake -S "$src/tests/consumer" -B "$work/build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$work/prefix" -DCANOPY_SOURCE_DIR="$src" >/dev/null
cmake --build "$work/build" > "$work/build.log" 2>&1 || { cat "$work/build.log" >&2; exit 1; }
"$work/build/canopy_consumer"
# The example host, compiled against the installed prefix: its own device, 2 frames in flight,
# reverse-Z, validation on, its self-check.
"$work/build/installed_example_host" --frames 8 --validate
