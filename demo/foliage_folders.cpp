#include "demo/foliage_folders.h"

#include <algorithm>
#include <cstdio>
#include <unistd.h>
#include <vector>

#include "tools/foliage_measure.h"
#include "tools/image_io.h"

namespace canopy::demo {

int readFramePair(const std::string& a, const std::string& b, uint32_t n, uint32_t* width, uint32_t* height,
                  std::vector<uint8_t>* pixelsA, std::vector<uint8_t>* pixelsB) {
  char name[32];
  std::snprintf(name, sizeof name, "/frame_%04u.png", n);
  const std::string fa = a + name, fb = b + name;
  const bool haveA = access(fa.c_str(), F_OK) == 0, haveB = access(fb.c_str(), F_OK) == 0;
  if (!haveA && !haveB) return 1;
  uint32_t wb = 0, hb = 0;
  Status s = haveA && haveB ? readPng(fa, width, height, pixelsA) : Status::error((haveA ? fb : fa) + " is missing");
  if (s.ok()) s = readPng(fb, &wb, &hb, pixelsB);
  if (s.ok() && (*width != wb || *height != hb))
    s = Status::error(fa + " is " + std::to_string(*width) + "x" + std::to_string(*height) + ", " + fb + " " + std::to_string(wb) +
                      "x" + std::to_string(hb));
  if (s.ok()) return 0;
  std::fprintf(stderr, "canopy-demo: %s\n", s.message().c_str());
  return 2;
}

int measureFoliageFolders(const std::string& wind, const std::string& still) {
  // One line per frame, machine-read by scripts/wind_views.py: keep the columns.
  std::printf("foliage of %s (wind) against %s (still)\n", wind.c_str(), still.c_str());
  std::printf("%6s %8s %8s %9s %10s %10s %7s %10s\n", "frame", "wind_px", "still_px", "coverage", "offset_px", "top_x",
              "height", "sharpness");
  double leastCoverage = 1e30, leastSharpness = 1e30;
  uint32_t n = 0;
  for (;; ++n) {
    uint32_t ww = 0, hw = 0;
    std::vector<uint8_t> a, b;
    const int rc = readFramePair(wind, still, n, &ww, &hw, &a, &b);
    if (rc == 1) break;
    if (rc == 2) return 1;
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
