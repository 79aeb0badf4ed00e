// SPDX-License-Identifier: GPL-3.0-or-later
// PNG through libpng, in memory: the library never writes files (the CLI and stage do).
#include "pointsurf/render/image.h"

#include <png.h>

#include <csetjmp>
#include <cstring>

#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

struct ReadState {
  const std::vector<std::uint8_t>* bytes;
  std::size_t offset = 0;
};

void write_bytes(png_structp png, png_bytep data, png_size_t length) {
  auto* out = static_cast<std::vector<std::uint8_t>*>(png_get_io_ptr(png));
  out->insert(out->end(), data, data + length);
}

void read_bytes(png_structp png, png_bytep data, png_size_t length) {
  auto* state = static_cast<ReadState*>(png_get_io_ptr(png));
  if (state->offset + length > state->bytes->size()) png_error(png, "file ends early");
  std::memcpy(data, state->bytes->data() + state->offset, length);
  state->offset += length;
}

// libpng reports errors by longjmp; the message is kept so that the C++ side can throw.
struct ErrorText {
  char text[256] = {0};
};

void on_error(png_structp png, png_const_charp message) {
  auto* e = static_cast<ErrorText*>(png_get_error_ptr(png));
  std::snprintf(e->text, sizeof e->text, "%s", message);
  png_longjmp(png, 1);
}

void on_warning(png_structp, png_const_charp) {}

}  // namespace

std::vector<std::uint8_t> encode_png(const Image& image, int compression) {
  if (image.width <= 0 || image.height <= 0 || image.rgb.size() != std::size_t(3) * std::size_t(image.width) * std::size_t(image.height))
    throw ComputeError(fmt::format("encode_png: image of {}x{} holds {} bytes, expected 3 per pixel", image.width, image.height, image.rgb.size()));
  std::vector<std::uint8_t> out;
  ErrorText error;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, on_error, on_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr) {
    png_destroy_write_struct(&png, nullptr);
    throw ComputeError("encode_png: libpng could not start");
  }
  std::vector<png_bytep> rows(std::size_t(image.height));
  for (int y = 0; y < image.height; ++y) rows[std::size_t(y)] = const_cast<png_bytep>(image.at(0, y));
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw ComputeError(fmt::format("encode_png: {}", error.text));
  }
  png_set_write_fn(png, &out, write_bytes, nullptr);
  png_set_compression_level(png, compression < 0 ? 0 : compression > 9 ? 9 : compression);
  png_set_IHDR(png, info, png_uint_32(image.width), png_uint_32(image.height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  png_write_image(png, rows.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return out;
}

Image decode_png(const std::vector<std::uint8_t>& bytes, const std::string& origin) {
  if (bytes.size() < 8 || png_sig_cmp(bytes.data(), 0, 8) != 0) throw InputError(fmt::format("{}: not a PNG file (no PNG signature)", origin));
  ErrorText error;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, on_error, on_warning);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    throw ComputeError("decode_png: libpng could not start");
  }
  ReadState state{&bytes, 0};
  Image image;
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw InputError(fmt::format("{}: {}", origin, error.text));
  }
  png_set_read_fn(png, &state, read_bytes);
  png_read_info(png, info);
  png_set_expand(png);
  png_set_strip_16(png);
  png_set_strip_alpha(png);
  png_set_gray_to_rgb(png);
  png_read_update_info(png, info);
  image = Image(int(png_get_image_width(png, info)), int(png_get_image_height(png, info)));
  rows.resize(std::size_t(image.height));
  for (int y = 0; y < image.height; ++y) rows[std::size_t(y)] = image.at(0, y);
  png_read_image(png, rows.data());
  png_destroy_read_struct(&png, &info, nullptr);
  return image;
}

}  // namespace pointsurf
