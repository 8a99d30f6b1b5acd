#include "demo/foliage_folders.h"

#include <algorithm>
#include <cstdio>
#include <unistd.h>
#include <vector>

#include "tools/foliage_measure.h"
#include "tools/image_io.h"

namespace canopy::demo {

int measureFoliageFolders(const std::string& wind, const std::string& still) {
  // One line per frame, machine-read by scripts/wind_views.py: keep the columns.
  std::printf("foliage of %s (wind) against %s (still)\n", wind.c_str(), still.c_str());
  std::printf("%6s %8s %8s %9s %10s %10s %7s %10s\n", "frame", "wind_px", "still_px", "coverage", "offset_px", "top_x",
              "height", "sharpness");
  double leastCoverage = 1e30, leastSharpness = 1e30;
  uint32_t n = 0;
  for (;; ++n) {
    char name[32];
    std::snprintf(name, sizeof name, "/frame_%04u.png", n);
    const std::string fw = wind + name, fs = still + name;
    const bool haveW = access(fw.c_str(), F_OK) == 0, haveS = access(fs.c_str(), F_OK) == 0;
    if (!haveW && !haveS) break;
    uint32_t ww = 0, hw = 0, ws = 0, hs = 0;
    std::vector<uint8_t> a, b;
    Status s = haveW && haveS ? readPng(fw, &ww, &hw, &a) : Status::error((haveW ? fs : fw) + " is missing");
    if (s.ok()) s = readPng(fs, &ws, &hs, &b);
    if (s.ok() && (ww != ws || hw != hs))
      s = Status::error(fw + " is " + std::to_string(ww) + "x" + std::to_string(hw) + ", " + fs + " " + std::to_string(ws) + "x" +
                        std::to_string(hs));
    if (!s.ok()) {
      std::fprintf(stderr, "canopy-demo: %s\n", s.message().c_str());
      return 1;
    }
    const FoliageMeasure m = measureFoliage(a, b, ww, hw);
    std::printf("%6u %8llu %8llu %9.4f %10.3f %10.3f %7u %10.4f\n", n, (unsigned long long)m.windPixels,
                (unsigned long long)m.stillPixels, m.coverage, m.offsetPx, m.windTopX, m.heightPx, m.sharpness);
    leastCoverage = std::min(leastCoverage, m.coverage);
    leastSharpness = std::min(leastSharpness, m.sharpness);
  }
  if (n == 0) {
    std::fprintf(stderr, "canopy-demo: no frame_0000.png in %s or %s\n", wind.c_str(), still.c_str());
    return 1;
  }
  std::printf("least over %u frames: coverage %.4f, sharpness %.4f\n", n, leastCoverage, leastSharpness);
  return 0;
}

}  // namespace canopy::demo
