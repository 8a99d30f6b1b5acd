#!/usr/bin/env bash
# The installed public headers compile after the platform's window-system headers and before them
# (issue 78): <X11/Xlib.h>, <X11/Xutil.h>, vulkan_xlib.h, vulkan_xcb.h and GLFW's native X11
# header define Status, Success, None, Bool, True, False... as macros. Each order, each public
# header, C++17 with -Wall -Wextra -Werror; the names a host after X11 uses (CanopyStatus,
# Result::Ok, CompositeDebugView::Off, ParamCheck::Unchecked) and, without X11, 0.8's names.
#   x11_headers_test.sh BUILD_DIR WORK_DIR
set -euo pipefail
build=$1 work=$2
rm -rf "$work"
mkdir -p "$work"
cmake --install "$build" --prefix "$work/prefix" >/dev/null
inc="$work/prefix/include"
for h in X11/Xlib.h X11/Xutil.h X11/extensions/Xrandr.h vulkan/vulkan_xlib.h vulkan/vulkan_xcb.h GLFW/glfw3native.h; do
  if ! echo "#include <$h>" | c++ -x c++ -fsyntax-only - >/dev/null 2>&1 && [ ! -f "/usr/include/$h" ]; then
    echo "x11 headers: /usr/include/$h is missing (scripts/deps.sh installs libx11-dev, libxrandr-dev, libxcb1-dev)" >&2
    exit 1
  fi
done
platform='#include <X11/Xlib.h>
#include <X11/Xutil.h>
#define VK_USE_PLATFORM_XLIB_KHR
#define VK_USE_PLATFORM_XCB_KHR
#include <vulkan/vulkan.h>
#define GLFW_INCLUDE_VULKAN
#include <GLFW/glfw3.h>
#define GLFW_EXPOSE_NATIVE_X11
#include <GLFW/glfw3native.h>'
use='int main() {
  canopy::CanopyStatus s = canopy::CanopyStatus::error(canopy::Result::InvalidArgument, "x");
  canopy::CompositeParams c;
  const bool names = c.debugView == canopy::CompositeDebugView::Off && canopy::Result::Ok != s.code() &&
                     canopy::ParamCheck::Unchecked == canopy::ParamCheck(0);
  Display* display = nullptr;  // X11 is usable beside Canopy
  (void)display;
  return names ? 0 : 1;
}'
n=0
for header in canopy.h canopy_graph.h canopy_params.h canopy_core.h; do
  extra=""
  [ "$header" = canopy_core.h ] && extra="#include <canopy/canopy_params.h>"
  [ "$header" = canopy_graph.h ] && extra="#include <canopy/canopy.h>"
  printf '%s\n#include <canopy/%s>\n%s\n#include <canopy/canopy_schema.h>\n%s\n' "$platform" "$header" "$extra" "$use" > "$work/after_${header%.h}.cpp"
  printf '#include <canopy/%s>\n%s\n#include <canopy/canopy_schema.h>\n%s\n%s\n' "$header" "$extra" "$platform" "$use" > "$work/before_${header%.h}.cpp"
  for order in after before; do
    c++ -std=c++17 -Wall -Wextra -Werror -fsyntax-only -I"$inc" "$work/${order}_${header%.h}.cpp"
    n=$((n + 1))
  done
done
echo "the public headers compile after and before X11, Xutil, vulkan_xlib/xcb and GLFW's native X11 header ($n translation units)"
# Without X11 a host written for 0.8 keeps its names (Status, Result::Success, ..., None).
echo '#include <canopy/canopy.h>
#include <canopy/canopy_schema.h>
int main() {
  canopy::Status s;
  canopy::CompositeParams c;
  return s.ok() && s.code() == canopy::Result::Success && c.debugView == canopy::CompositeDebugView::None &&
                 canopy::ParamCheck::None == canopy::ParamCheck::Unchecked ? 0 : 1;
}' > "$work/names_08.cpp"
c++ -std=c++17 -Wall -Wextra -Werror -fsyntax-only -I"$inc" "$work/names_08.cpp"
echo "0.8's names compile without X11"
