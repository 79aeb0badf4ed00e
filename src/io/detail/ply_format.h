// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// PLY (Stanford polygon format), shared by the reader (ply_read.cpp) and the writer
// (ply_write.cpp): the body encodings and their names in the header.
#include <string_view>

namespace pointsurf::io::detail::ply {

enum class Encoding { Ascii, BinaryLittleEndian, BinaryBigEndian };

/// The header's name of an encoding ("format binary_little_endian 1.0").
inline std::string_view encoding_name(Encoding e) {
  switch (e) {
    case Encoding::Ascii: return "ascii";
    case Encoding::BinaryLittleEndian: return "binary_little_endian";
    case Encoding::BinaryBigEndian: return "binary_big_endian";
  }
  return "ascii";
}

}  // namespace pointsurf::io::detail::ply
