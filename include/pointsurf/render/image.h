// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// An 8-bit RGB picture and its PNG encoding (libpng, inside image.cpp).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace pointsurf {

/// width x height pixels, row by row from the top, 3 bytes (R, G, B) each.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // 3 * width * height

  Image() = default;
  Image(int w, int h, std::uint8_t grey = 255) : width(w), height(h), rgb(std::size_t(3) * std::size_t(w) * std::size_t(h), grey) {}
  std::uint8_t* at(int x, int y) { return rgb.data() + 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x)); }
  const std::uint8_t* at(int x, int y) const { return rgb.data() + 3 * (std::size_t(y) * std::size_t(width) + std::size_t(x)); }
};

/// The image as PNG bytes (8-bit RGB, not interlaced, zlib level `compression` 0..9).
/// Throws ComputeError when libpng fails. Thread-safe.
std::vector<std::uint8_t> encode_png(const Image& image, int compression = 6);

/// Decodes PNG bytes (any bit depth or colour type libpng reads; alpha is dropped, grey
/// expanded) into 8-bit RGB. Throws InputError "PNG: ..." on malformed data, naming `origin`.
Image decode_png(const std::vector<std::uint8_t>& bytes, const std::string& origin = "PNG");

}  // namespace pointsurf
