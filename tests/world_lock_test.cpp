// The world-lock measure (tools/world_lock.h) on drawn shapes whose answers are known: identical
// frames, a disc shifted by a known number of pixels, a recoloured disc, an empty frame.
#include <cmath>

#include <gtest/gtest.h>

#include "tools/world_lock.h"

namespace canopy {
namespace {

constexpr uint32_t kW = 200, kH = 150;
const uint8_t kClear[3] = {115, 153, 204};

std::vector<uint8_t> disc(float cx, float cy, float r, uint8_t red = 40) {
  std::vector<uint8_t> px(size_t(kW) * kH * 4);
  for (uint32_t y = 0; y < kH; ++y)
    for (uint32_t x = 0; x < kW; ++x) {
      uint8_t* p = &px[4 * (size_t(y) * kW + x)];
      const bool in = std::hypot(x + 0.5f - cx, y + 0.5f - cy) <= r;
      p[0] = in ? red : kClear[0];
      p[1] = in ? 120 : kClear[1];
      p[2] = in ? 30 : kClear[2];
      p[3] = 255;
    }
  return px;
}

TEST(WorldLock, IdenticalFramesHaveNoError) {
  const auto a = disc(100, 75, 40);
  const WorldLockError e = compareFrames(a, a, kW, kH, kClear);
  EXPECT_EQ(e.coverageIoU, 1.0);
  EXPECT_EQ(e.silhouetteMeanPx, 0.0);
  EXPECT_EQ(e.silhouetteP99Px, 0.0);
  EXPECT_EQ(e.centroidPx, 0.0);
  EXPECT_EQ(e.colourMean, 0.0);
  EXPECT_GT(e.coveredA, 4900u);  // ~pi 40^2
}

TEST(WorldLock, AShiftedDiscMeasuresItsShift) {
  const auto a = disc(100, 75, 40), b = disc(106, 75, 40);
  const WorldLockError e = compareFrames(a, b, kW, kH, kClear);
  // Two discs of radius r shifted by s overlap in 2r^2 acos(s/2r) - (s/2) sqrt(4r^2 - s^2).
  const double r = 40, s = 6, inter = 2 * r * r * std::acos(s / (2 * r)) - s / 2 * std::sqrt(4 * r * r - s * s);
  EXPECT_NEAR(e.coverageIoU, inter / (2 * M_PI * r * r - inter), 0.01);
  EXPECT_NEAR(e.centroidPx, 6.0, 0.05);
  // Each silhouette point is at most the shift from the other circle, on average 2s/pi (distance of
  // a point on one circle to the other, r >> s: s |cos theta|).
  EXPECT_NEAR(e.silhouetteMeanPx, 2 * s / M_PI, 0.6);
  EXPECT_LE(e.silhouetteP99Px, 6.5);
  EXPECT_GE(e.silhouetteP99Px, 5.0);
  EXPECT_GT(e.colourMean, 0.0);
}

TEST(WorldLock, ColourIsMeasuredOverCoveredPixelsOnly) {
  const auto a = disc(100, 75, 40, 40), b = disc(100, 75, 40, 70);
  const WorldLockError e = compareFrames(a, b, kW, kH, kClear);
  EXPECT_EQ(e.coverageIoU, 1.0);
  EXPECT_NEAR(e.colourMean, 30.0 / 3.0, 1e-9);  // red differs by 30, green and blue not
}

TEST(WorldLock, AnEmptyFrameAgainstACoveredOneIsTheWorstCase) {
  const auto a = disc(100, 75, 0), b = disc(100, 75, 30);
  const WorldLockError e = compareFrames(a, b, kW, kH, kClear);
  EXPECT_EQ(e.coveredA, 0u);
  EXPECT_EQ(e.coverageIoU, 0.0);
  EXPECT_NEAR(e.silhouetteMeanPx, std::hypot(double(kW), double(kH)), 1e-9);
  const WorldLockError none = compareFrames(a, a, kW, kH, kClear);
  EXPECT_EQ(none.coverageIoU, 1.0);
  EXPECT_EQ(none.silhouetteMeanPx, 0.0);
}

}  // namespace
}  // namespace canopy
