// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/render/image.h"

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/files.h"

namespace pointsurf {
namespace {

TEST(Png, EncodeThenDecodeGivesTheSamePixels) {
  Image img(37, 23);
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      std::uint8_t* p = img.at(x, y);
      p[0] = std::uint8_t(7 * x);
      p[1] = std::uint8_t(11 * y);
      p[2] = std::uint8_t(x ^ y);
    }
  for (int level : {0, 6, 9}) {
    const std::vector<std::uint8_t> png = encode_png(img, level);
    ASSERT_GT(png.size(), 8u);
    EXPECT_EQ(png[1], 'P');
    const Image back = decode_png(png);
    EXPECT_EQ(back.width, 37);
    EXPECT_EQ(back.height, 23);
    EXPECT_EQ(back.rgb, img.rgb) << "level " << level;
  }
}

TEST(Png, MalformedInputIsAnInputErrorNamingTheOrigin) {
  test::expect_error<InputError>([] { decode_png({1, 2, 3}, "x.png"); }, "x.png: not a PNG file");
  std::vector<std::uint8_t> png = encode_png(Image(16, 16, 9));
  png.resize(png.size() / 2);
  test::expect_error<InputError>([&] { decode_png(png, "cut.png"); }, "cut.png: ");
  Image bad(4, 4);
  bad.rgb.pop_back();
  test::expect_error<ComputeError>([&] { encode_png(bad); }, "expected 3 per pixel");
}

}  // namespace
}  // namespace pointsurf
