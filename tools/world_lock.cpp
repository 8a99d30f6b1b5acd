#include "tools/world_lock.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>

namespace canopy {
namespace {

std::vector<uint8_t> silhouette(const std::vector<uint8_t>& m, uint32_t w, uint32_t h) {
  std::vector<uint8_t> s(m.size(), 0);
  auto at = [&](int x, int y) { return x >= 0 && y >= 0 && x < int(w) && y < int(h) ? m[size_t(y) * w + x] : uint8_t(0); };
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      if (m[size_t(y) * w + x])
        s[size_t(y) * w + x] = !at(int(x) - 1, int(y)) || !at(int(x) + 1, int(y)) || !at(int(x), int(y) - 1) || !at(int(x), int(y) + 1);
  return s;
}

// Exact squared Euclidean distance of a 1D sampled function (Felzenszwalb & Huttenlocher 2012):
// d[q] = min_p (q - p)^2 + f[p].
void distance1d(const std::vector<double>& f, std::vector<double>& d, std::vector<int>& v, std::vector<double>& z) {
  const int n = int(f.size());
  const double inf = std::numeric_limits<double>::infinity();
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (f[q] == inf) continue;
    double s = -inf;
    while (k >= 0) {
      s = ((f[q] + double(q) * q) - (f[v[k]] + double(v[k]) * v[k])) / (2.0 * (q - v[k]));
      if (s > z[k]) break;
      --k;
    }
    ++k;
    v[k] = q;
    z[k] = k == 0 ? -inf : s;
    z[k + 1] = inf;
  }
  for (int q = 0, j = 0; q < n; ++q) {
    if (k < 0) {
      d[q] = inf;
      continue;
    }
    while (z[j + 1] < q) ++j;
    d[q] = double(q - v[j]) * (q - v[j]) + f[v[j]];
  }
}

// Squared distance of every pixel to the nearest set pixel of `s` (infinity when none is set).
std::vector<double> distanceField(const std::vector<uint8_t>& s, uint32_t w, uint32_t h) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> g(s.size());
  for (size_t i = 0; i < s.size(); ++i) g[i] = s[i] ? 0.0 : inf;
  const uint32_t n = std::max(w, h);
  std::vector<double> f(n), d(n), z(n + 1);
  std::vector<int> v(n);
  for (uint32_t x = 0; x < w; ++x) {
    f.resize(h), d.resize(h);
    for (uint32_t y = 0; y < h; ++y) f[y] = g[size_t(y) * w + x];
    distance1d(f, d, v, z);
    for (uint32_t y = 0; y < h; ++y) g[size_t(y) * w + x] = d[y];
  }
  for (uint32_t y = 0; y < h; ++y) {
    f.assign(g.begin() + size_t(y) * w, g.begin() + size_t(y + 1) * w);
    d.resize(w);
    distance1d(f, d, v, z);
    std::copy(d.begin(), d.end(), g.begin() + size_t(y) * w);
  }
  return g;
}

}  // namespace

std::vector<uint8_t> coverageMask(const std::vector<uint8_t>& rgba, uint32_t width, uint32_t height, const uint8_t clear[3]) {
  std::vector<uint8_t> m(size_t(width) * height, 0);
  for (size_t i = 0; i < m.size() && 4 * i + 2 < rgba.size(); ++i)
    for (int c = 0; c < 3; ++c) m[i] |= std::abs(int(rgba[4 * i + c]) - int(clear[c])) > 1;
  return m;
}

WorldLockError compareFrames(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b, uint32_t width, uint32_t height,
                             const uint8_t clear[3]) {
  return compareMasks(coverageMask(a, width, height, clear), coverageMask(b, width, height, clear), a, b, width, height);
}

WorldLockError compareMasks(const std::vector<uint8_t>& ma, const std::vector<uint8_t>& mb, const std::vector<uint8_t>& a,
                            const std::vector<uint8_t>& b, uint32_t width, uint32_t height) {
  WorldLockError e;
  uint64_t both = 0, either = 0;
  double ax = 0, ay = 0, bx = 0, by = 0, colour = 0;
  for (uint32_t y = 0; y < height; ++y)
    for (uint32_t x = 0; x < width; ++x) {
      const size_t i = size_t(y) * width + x;
      e.coveredA += ma[i];
      e.coveredB += mb[i];
      both += ma[i] & mb[i];
      if (ma[i]) ax += x, ay += y;
      if (mb[i]) bx += x, by += y;
      if (!(ma[i] | mb[i])) continue;
      ++either;
      for (int c = 0; c < 3; ++c) colour += std::abs(int(a[4 * i + c]) - int(b[4 * i + c]));
    }
  e.coverageIoU = either ? double(both) / double(either) : 1.0;
  e.colourMean = either ? colour / (3.0 * double(either)) : 0.0;
  if (e.coveredA && e.coveredB)
    e.centroidPx = std::hypot(ax / double(e.coveredA) - bx / double(e.coveredB), ay / double(e.coveredA) - by / double(e.coveredB));

  const std::vector<uint8_t> sa = silhouette(ma, width, height), sb = silhouette(mb, width, height);
  const std::vector<double> da = distanceField(sa, width, height), db = distanceField(sb, width, height);
  const double diagonal = std::hypot(double(width), double(height));
  std::vector<double> dist;
  for (size_t i = 0; i < sa.size(); ++i) {
    if (sa[i]) dist.push_back(std::isfinite(db[i]) ? std::sqrt(db[i]) : diagonal);
    if (sb[i]) dist.push_back(std::isfinite(da[i]) ? std::sqrt(da[i]) : diagonal);
  }
  if (!dist.empty()) {
    double sum = 0;
    for (double x : dist) sum += x;
    e.silhouetteMeanPx = sum / double(dist.size());
    const size_t k = std::min(dist.size() - 1, size_t(std::ceil(0.99 * double(dist.size()))) - 1);
    std::nth_element(dist.begin(), dist.begin() + std::ptrdiff_t(k), dist.end());
    e.silhouetteP99Px = dist[k];
  }
  return e;
}

}  // namespace canopy
