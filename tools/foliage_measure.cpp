#include "tools/foliage_measure.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace canopy {

namespace {
double luma(const std::vector<uint8_t>& im, size_t k) {
  return 0.2126 * im[4 * k] + 0.7152 * im[4 * k + 1] + 0.0722 * im[4 * k + 2];
}

// Foliage pixel count, the centroid x of those in rows [lo, hi), and the mean gradient over them.
struct Stats {
  uint64_t pixels = 0;
  double topX = std::numeric_limits<double>::quiet_NaN();
  double gradient = 0.0;
};

Stats stats(const std::vector<uint8_t>& im, uint32_t w, uint32_t h, uint32_t lo, uint32_t hi) {
  Stats s;
  double sumX = 0.0, sumG = 0.0;
  uint64_t top = 0;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const size_t k = size_t(y) * w + x;
      if (!isFoliage(im[4 * k], im[4 * k + 1], im[4 * k + 2])) continue;
      ++s.pixels;
      if (y >= lo && y < hi) sumX += x, ++top;
      const double l = luma(im, k);
      const double gx = x + 1 < w ? luma(im, k + 1) - l : 0.0, gy = y + 1 < h ? luma(im, k + w) - l : 0.0;
      sumG += std::abs(gx) + std::abs(gy);
    }
  if (top) s.topX = sumX / double(top);
  if (s.pixels) s.gradient = sumG / double(s.pixels);
  return s;
}
}  // namespace

FoliageMeasure measureFoliage(const std::vector<uint8_t>& wind, const std::vector<uint8_t>& still, uint32_t width,
                              uint32_t height) {
  FoliageMeasure m;
  const size_t n = size_t(width) * height;
  if (wind.size() < 4 * n || still.size() < 4 * n) return m;
  // The still frame's foliage rows give the crown's extent; its top third is where the sway shows.
  uint32_t first = height, last = 0;
  for (uint32_t y = 0; y < height; ++y)
    for (uint32_t x = 0; x < width; ++x) {
      const size_t k = size_t(y) * width + x;
      if (isFoliage(still[4 * k], still[4 * k + 1], still[4 * k + 2])) first = std::min(first, y), last = std::max(last, y);
    }
  uint32_t lo = 0, hi = 0;
  if (first <= last) {
    m.heightPx = last + 1 - first;
    lo = first;
    hi = first + std::max(1u, m.heightPx / 3);
  }
  const Stats a = stats(wind, width, height, lo, hi), b = stats(still, width, height, lo, hi);
  m.windPixels = a.pixels;
  m.stillPixels = b.pixels;
  m.coverage = b.pixels ? double(a.pixels) / double(b.pixels) : (a.pixels ? std::numeric_limits<double>::infinity() : 1.0);
  m.windTopX = a.topX;
  m.stillTopX = b.topX;
  m.offsetPx = a.topX - b.topX;
  m.sharpness = b.gradient > 0.0 ? a.gradient / b.gradient : 1.0;
  return m;
}

}  // namespace canopy
