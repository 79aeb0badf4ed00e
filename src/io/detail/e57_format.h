// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The E57 reader over bytes already in memory, for the fuzz target and the tests of corrupted
// files (read_e57 maps the file and calls it).
#include <string>
#include <string_view>

#include "io/detail/formats.h"

namespace pointsurf::io::detail {

/// Reads an E57 file held in `bytes`; `name` is used in messages. Throws InputError on any
/// malformed input, naming the page, section, scan or field.
RawData read_e57_bytes(std::string_view bytes, const std::string& name, const ReadOptions& options);

}  // namespace pointsurf::io::detail
