// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/render/colormap.h"

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

namespace pointsurf {
namespace {

using Rgb = std::array<std::uint8_t, 3>;

TEST(ColorMap, DivergingIsBlueWhiteRedWithAGreenToleranceBand) {
  ColorScale s;
  s.kind = ColorMapKind::Diverging;
  s.min = -2.0;
  s.max = 2.0;
  const Rgb low = s.color(-2.0), mid = s.color(0.0), high = s.color(2.0);
  EXPECT_GT(low[2], low[0]);   // blue end
  EXPECT_GT(high[0], high[2]); // red end
  EXPECT_EQ(mid[0], mid[1]);   // grey-white middle
  EXPECT_EQ(mid[1], mid[2]);
  EXPECT_GT(mid[0], 200);
  EXPECT_EQ(s.color(-5.0), low);  // clamped
  EXPECT_EQ(s.color(9.0), high);
  s.tolerance = 0.5;
  EXPECT_EQ(s.color(0.49), (Rgb{64, 176, 72}));
  EXPECT_EQ(s.color(-0.5), (Rgb{64, 176, 72}));
  EXPECT_NE(s.color(0.51), (Rgb{64, 176, 72}));
  EXPECT_EQ(s.color(std::numeric_limits<double>::quiet_NaN()), (Rgb{128, 128, 128}));
}

TEST(ColorMap, SequentialRunsFromDarkToBright) {
  ColorScale s;
  s.min = 10;
  s.max = 20;
  const Rgb a = s.color(10), b = s.color(20);
  EXPECT_LT(a[0] + a[1] + a[2], b[0] + b[1] + b[2]);
  int last = -1;
  for (int k = 0; k <= 10; ++k) {  // viridis brightens monotonically (green channel)
    const Rgb c = s.color(10 + k);
    EXPECT_GE(int(c[1]), last);
    last = c[1];
  }
}

TEST(ColorMap, DefaultScales) {
  const std::vector<double> dev = {-0.3, 0.1, 0.25, std::numeric_limits<double>::infinity()};
  const ColorScale d = default_color_scale(dev, "deviation");
  EXPECT_EQ(d.kind, ColorMapKind::Diverging);
  EXPECT_DOUBLE_EQ(d.min, -0.3);
  EXPECT_DOUBLE_EQ(d.max, 0.3);
  const ColorScale small = default_color_scale(std::vector<double>{-2, 1, 5}, "intensity");
  EXPECT_EQ(small.kind, ColorMapKind::Sequential);
  EXPECT_DOUBLE_EQ(small.min, -2);
  EXPECT_DOUBLE_EQ(small.max, 5);
  // A large field drops 1% at each end: two outliers among 10,000 do not set the range.
  std::vector<double> big(10000);
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = double(i % 100);
  big[0] = -1e6;
  big[1] = 1e6;
  const ColorScale robust = default_color_scale(big, "z");
  EXPECT_GE(robust.min, 0.0);
  EXPECT_LE(robust.max, 99.0);
  const ColorScale constant = default_color_scale(std::vector<double>{3, 3}, "c");
  EXPECT_LT(constant.min, constant.max);
}

// A deviation map is clipped at the 99th percentile of |d|, never stretched by a few outliers,
// at least twice the tolerance wide, and shows what lies beyond in its own colours.
TEST(ColorMap, DeviationScaleIsClippedWithOutOfRangeColours) {
  std::vector<double> dev(10000);
  for (std::size_t i = 0; i < dev.size(); ++i) dev[i] = (i % 2 ? 1.0 : -1.0) * 0.001 * double(i % 1000) / 999.0;  // |d| <= 0.001
  for (std::size_t i = 0; i < 50; ++i) dev[i] = i % 2 ? 0.5 : -0.4;  // 0.5 % far outliers
  const ColorScale s = default_color_scale(dev, "deviation", false, 0.0002);
  EXPECT_EQ(s.kind, ColorMapKind::Diverging);
  EXPECT_TRUE(s.out_of_range);
  EXPECT_DOUBLE_EQ(s.tolerance, 0.0002);
  EXPECT_NEAR(s.high(), 0.001, 2e-5);  // the 99th percentile of |d|, not 0.5
  EXPECT_DOUBLE_EQ(s.low(), -s.high());
  EXPECT_EQ(s.color(0.5), ColorScale::kOverRange);
  EXPECT_EQ(s.color(-0.4), ColorScale::kUnderRange);
  EXPECT_NE(s.color(0.0009), ColorScale::kOverRange);
  EXPECT_EQ(s.color(0.0001), (Rgb{64, 176, 72}));  // the tolerance band
  EXPECT_NE(ColorScale::kOverRange, ColorScale::kUnderRange);
  for (double v : {-0.0009, -0.0005, 0.0005, 0.0009}) {  // neither out-of-range colour is in the map
    EXPECT_NE(s.color(v), ColorScale::kOverRange);
    EXPECT_NE(s.color(v), ColorScale::kUnderRange);
  }
  // A wide tolerance: the map reaches twice it, so the band never fills the whole bar.
  const ColorScale wide = default_color_scale(dev, "deviation", false, 0.01);
  EXPECT_DOUBLE_EQ(wide.high(), 0.02);
  // Without out_of_range (a sequential field, or set off) values beyond the ends are clamped.
  ColorScale clamped = s;
  clamped.out_of_range = false;
  EXPECT_EQ(clamped.color(0.5), clamped.color(s.high()));
}

}  // namespace
}  // namespace pointsurf
