// The picture-in-wind measure (tools/foliage_measure.h) on drawn images whose answers are known:
// a green crown shifted sideways, a crown that lost half its pixels, a blurred crown, nothing green.
#include <cmath>

#include <gtest/gtest.h>

#include "tools/foliage_measure.h"

namespace canopy {
namespace {

constexpr uint32_t kW = 120, kH = 90;

// Sky, and a green crown of alternating light and dark stripes (its detail) in rectangle
// [x0, x0 + w) x [y0, y0 + h); `soft` halves the stripes' contrast (a blurred crown).
std::vector<uint8_t> crown(int x0, int y0, int w, int h, bool soft = false) {
  std::vector<uint8_t> px(size_t(kW) * kH * 4);
  for (uint32_t y = 0; y < kH; ++y)
    for (uint32_t x = 0; x < kW; ++x) {
      uint8_t* p = &px[4 * (size_t(y) * kW + x)];
      const bool in = int(x) >= x0 && int(x) < x0 + w && int(y) >= y0 && int(y) < y0 + h;
      const int g = soft ? (x % 2 ? 130 : 110) : (x % 2 ? 140 : 100);
      p[0] = in ? 40 : 150;
      p[1] = in ? uint8_t(g) : 190;
      p[2] = in ? 30 : 225;
      p[3] = 255;
    }
  return px;
}

TEST(FoliageMeasure, TheSameFrameKeepsEverything) {
  const auto a = crown(30, 20, 40, 60);
  const FoliageMeasure m = measureFoliage(a, a, kW, kH);
  EXPECT_EQ(m.windPixels, 40u * 60u);
  EXPECT_DOUBLE_EQ(m.coverage, 1.0);
  EXPECT_DOUBLE_EQ(m.offsetPx, 0.0);
  EXPECT_DOUBLE_EQ(m.sharpness, 1.0);
  EXPECT_EQ(m.heightPx, 60u);
  EXPECT_NEAR(m.windTopX, 49.5, 1e-9);
}

TEST(FoliageMeasure, ACrownMovedSidewaysShowsItsOffsetInTheTopThird) {
  const FoliageMeasure m = measureFoliage(crown(37, 20, 40, 60), crown(30, 20, 40, 60), kW, kH);
  EXPECT_NEAR(m.offsetPx, 7.0, 1e-9);
  EXPECT_DOUBLE_EQ(m.coverage, 1.0);
}

TEST(FoliageMeasure, LostPixelsAndLostDetailReadBelowOne) {
  const auto still = crown(30, 20, 40, 60);
  EXPECT_NEAR(measureFoliage(crown(30, 20, 20, 60), still, kW, kH).coverage, 0.5, 1e-9);
  // The stripes' contrast halved: the mean gradient over the crown falls to about half (0.558:
  // the steps from the crown's last row and column to the sky are not halved).
  const FoliageMeasure blur = measureFoliage(crown(30, 20, 40, 60, true), still, kW, kH);
  EXPECT_GT(blur.sharpness, 0.5);
  EXPECT_LT(blur.sharpness, 0.6);
  EXPECT_DOUBLE_EQ(blur.coverage, 1.0);
}

TEST(FoliageMeasure, NothingGreenIsNotFoliage) {
  const auto sky = crown(0, 0, 0, 0);
  const FoliageMeasure m = measureFoliage(sky, sky, kW, kH);
  EXPECT_EQ(m.stillPixels, 0u);
  EXPECT_DOUBLE_EQ(m.coverage, 1.0);
  EXPECT_EQ(m.heightPx, 0u);
  EXPECT_TRUE(std::isinf(measureFoliage(crown(30, 20, 40, 60), sky, kW, kH).coverage));
  EXPECT_FALSE(isFoliage(150, 190, 225)) << "the sky";
  EXPECT_FALSE(isFoliage(100, 115, 100)) << "green by 15 levels only";
  EXPECT_TRUE(isFoliage(40, 120, 30));
}

}  // namespace
}  // namespace canopy
