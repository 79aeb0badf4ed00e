// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Labels through FreeType: anti-aliased glyphs blended into an Image. One painter per thread.
#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "pointsurf/render/image.h"

namespace pointsurf::detail {

class TextPainter {
public:
  /// Loads `font_file`; ok() is false (with error()) when FreeType cannot.
  explicit TextPainter(const std::string& font_file);
  ~TextPainter();
  TextPainter(const TextPainter&) = delete;
  TextPainter& operator=(const TextPainter&) = delete;
  bool ok() const noexcept { return face_ != nullptr; }
  const std::string& error() const noexcept { return error_; }
  /// Advance width in pixels of UTF-8 `text` at `size_px` (pixel height of the em).
  int width(const std::string& text, int size_px);
  /// Draws `text` with its baseline at y and its left at x.
  void draw(Image& image, int x, int y, const std::string& text, int size_px, std::array<std::uint8_t, 3> color);

private:
  void* library_ = nullptr;  // FT_Library
  void* face_ = nullptr;     // FT_Face
  std::string error_;
};

}  // namespace pointsurf::detail
