// SPDX-License-Identifier: GPL-3.0-or-later
// libFuzzer target of the E57 reader. Page checksums would stop almost every mutation at the
// first page, so the input is taken as the logical bytes (payload without checksums) and the
// checksums are computed here: the mutations reach the header, the XML and the packets.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>

#include "io/detail/e57_format.h"
#include "io/detail/e57_pages.h"
#include "pointsurf/core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace pointsurf::io::detail;
  if (size > (1u << 22)) return 0;
  std::string file;
  for (std::size_t at = 0; at < size || at == 0; at += kE57PagePayload) {
    std::string page(reinterpret_cast<const char*>(data) + std::min(at, size), std::min(kE57PagePayload, size - std::min(at, size)));
    page.resize(kE57PagePayload, '\0');
    const std::uint32_t crc = crc32c(page.data(), page.size());
    for (int b = 3; b >= 0; --b) page.push_back(static_cast<char>(crc >> (8 * b)));
    file += page;
  }
  // The header's file length is rewritten to the real one, or nearly every input stops there.
  if (file.size() >= 48) {
    const std::uint64_t length = file.size();
    std::memcpy(file.data() + 16, &length, 8);
    const std::uint32_t crc = crc32c(file.data(), kE57PagePayload);
    for (int b = 3; b >= 0; --b) file[kE57PagePayload + 3 - b] = static_cast<char>(crc >> (8 * b));
  }
  try {
    pointsurf::ReadOptions options;
    (void)read_e57_bytes(file, "fuzz.e57", options);
  } catch (const pointsurf::InputError&) {
  }
  return 0;
}
