// SPDX-License-Identifier: GPL-3.0-or-later
#include "render/detail/text.h"

#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <vector>

namespace pointsurf::detail {
namespace {

std::vector<char32_t> decode_utf8(const std::string& s) {
  std::vector<char32_t> out;
  for (std::size_t i = 0; i < s.size();) {
    const auto c = static_cast<unsigned char>(s[i]);
    int extra = c < 0x80 ? 0 : (c >> 5) == 0x6 ? 1 : (c >> 4) == 0xE ? 2 : (c >> 3) == 0x1E ? 3 : -1;
    if (extra < 0 || i + std::size_t(extra) >= s.size()) {
      out.push_back(U'?');
      ++i;
      continue;
    }
    char32_t code = extra == 0 ? c : c & (0x3F >> extra);
    for (int k = 1; k <= extra; ++k) code = (code << 6) | (static_cast<unsigned char>(s[i + std::size_t(k)]) & 0x3F);
    out.push_back(code);
    i += std::size_t(extra) + 1;
  }
  return out;
}

}  // namespace

TextPainter::TextPainter(const std::string& font_file) {
  FT_Library lib = nullptr;
  if (FT_Init_FreeType(&lib) != 0) {
    error_ = "FreeType could not start";
    return;
  }
  library_ = lib;
  FT_Face face = nullptr;
  if (FT_New_Face(lib, font_file.c_str(), 0, &face) != 0) {
    error_ = font_file + ": cannot load the font (install fonts-dejavu-core); labels are left out";
    return;
  }
  face_ = face;
}

TextPainter::~TextPainter() {
  if (face_) FT_Done_Face(static_cast<FT_Face>(face_));
  if (library_) FT_Done_FreeType(static_cast<FT_Library>(library_));
}

int TextPainter::width(const std::string& text, int size_px) {
  if (!ok()) return 0;
  auto face = static_cast<FT_Face>(face_);
  FT_Set_Pixel_Sizes(face, 0, FT_UInt(size_px));
  long advance = 0;
  for (char32_t c : decode_utf8(text))
    if (FT_Load_Char(face, c, FT_LOAD_DEFAULT) == 0) advance += face->glyph->advance.x;
  return int(advance >> 6);
}

void TextPainter::draw(Image& image, int x, int y, const std::string& text, int size_px, std::array<std::uint8_t, 3> color) {
  if (!ok()) return;
  auto face = static_cast<FT_Face>(face_);
  FT_Set_Pixel_Sizes(face, 0, FT_UInt(size_px));
  long pen = long(x) << 6;
  for (char32_t c : decode_utf8(text)) {
    if (FT_Load_Char(face, c, FT_LOAD_RENDER) != 0) continue;
    const FT_GlyphSlot g = face->glyph;
    const int left = int(pen >> 6) + g->bitmap_left, top = y - g->bitmap_top;
    for (int r = 0; r < int(g->bitmap.rows); ++r)
      for (int col = 0; col < int(g->bitmap.width); ++col) {
        const int px = left + col, py = top + r;
        if (px < 0 || py < 0 || px >= image.width || py >= image.height) continue;
        const int a = g->bitmap.buffer[r * g->bitmap.pitch + col];
        if (a == 0) continue;
        std::uint8_t* p = image.at(px, py);
        for (int k = 0; k < 3; ++k) p[k] = std::uint8_t((p[k] * (255 - a) + color[std::size_t(k)] * a + 127) / 255);
      }
    pen += g->advance.x;
  }
}

}  // namespace pointsurf::detail
