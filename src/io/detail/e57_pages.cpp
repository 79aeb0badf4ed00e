// SPDX-License-Identifier: GPL-3.0-or-later
#include "io/detail/e57_pages.h"

#include <array>
#include <cstring>

#include <fmt/format.h>

#include "io/detail/file_util.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
namespace {

std::array<std::uint32_t, 256> make_crc_table() {
  std::array<std::uint32_t, 256> table{};
  for (std::uint32_t i = 0; i < 256; ++i) {
    std::uint32_t c = i;
    for (int k = 0; k < 8; ++k) c = (c & 1) ? (c >> 1) ^ 0x82F63B78u : c >> 1;
    table[i] = c;
  }
  return table;
}

std::uint32_t crc32c_table(const unsigned char* p, std::size_t size) noexcept {
  static const std::array<std::uint32_t, 256> table = make_crc_table();
  std::uint32_t c = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < size; ++i) c = table[(c ^ p[i]) & 0xFF] ^ (c >> 8);
  return c ^ 0xFFFFFFFFu;
}

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
__attribute__((target("sse4.2"))) std::uint32_t crc32c_sse42(const unsigned char* p, std::size_t size) noexcept {
  std::uint64_t c = 0xFFFFFFFFu;
  std::size_t i = 0;
  for (; i + 8 <= size; i += 8) {
    std::uint64_t word;
    std::memcpy(&word, p + i, 8);
    c = __builtin_ia32_crc32di(c, word);
  }
  std::uint32_t c32 = static_cast<std::uint32_t>(c);
  for (; i < size; ++i) c32 = __builtin_ia32_crc32qi(c32, p[i]);
  return c32 ^ 0xFFFFFFFFu;
}
#endif

}  // namespace

std::uint32_t crc32c(const void* data, std::size_t size) noexcept {
  const auto* p = static_cast<const unsigned char*>(data);
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
  static const bool have_sse42 = __builtin_cpu_supports("sse4.2");
  if (have_sse42) return crc32c_sse42(p, size);
#endif
  return crc32c_table(p, size);
}

E57PagedReader::E57PagedReader(std::string_view file, std::string name) : file_(file), name_(std::move(name)) {
  if (file.size() < kE57HeaderSize || file.substr(0, 8) != "ASTM-E57")
    throw InputError(fmt::format("{}: not an E57 file (expected the signature ASTM-E57 and a 48-byte header)", name_));
  const char* h = file.data();
  header_.major = load_value<std::uint32_t>(h + 8);
  header_.minor = load_value<std::uint32_t>(h + 12);
  header_.file_physical_length = load_value<std::uint64_t>(h + 16);
  header_.xml_physical_offset = load_value<std::uint64_t>(h + 24);
  header_.xml_logical_length = load_value<std::uint64_t>(h + 32);
  header_.page_size = load_value<std::uint64_t>(h + 40);
  if (header_.major != 1)
    throw InputError(fmt::format("{}: header: E57 version {}.{}, expected 1.x", name_, header_.major, header_.minor));
  if (header_.page_size != kE57PageSize)
    throw InputError(fmt::format("{}: header: page size {}, expected {}", name_, header_.page_size, kE57PageSize));
  if (header_.file_physical_length != file.size())
    throw InputError(fmt::format("{}: header: file length {} bytes, but the file has {} (truncated or padded)", name_,
                                 header_.file_physical_length, file.size()));
  if (file.size() % kE57PageSize != 0)
    throw InputError(fmt::format("{}: {} bytes is not a whole number of {}-byte pages (truncated)", name_, file.size(), kE57PageSize));
  const std::size_t pages = file.size() / kE57PageSize;
  for (std::size_t page = 0; page < pages; ++page) {
    const char* p = file.data() + page * kE57PageSize;
    const std::uint32_t stored = load_value<std::uint32_t>(p + kE57PagePayload, true);
    const std::uint32_t computed = crc32c(p, kE57PagePayload);
    if (stored != computed)
      throw InputError(fmt::format("{}: page {} (bytes {}..{}): CRC-32C checksum mismatch (stored {:08x}, computed {:08x}): the file is corrupt",
                                   name_, page, page * kE57PageSize, (page + 1) * kE57PageSize - 1, stored, computed));
  }
  logical_size_ = static_cast<std::uint64_t>(pages) * kE57PagePayload;
  if (!is_payload_offset(header_.xml_physical_offset) || e57_logical(header_.xml_physical_offset) > logical_size_ ||
      header_.xml_logical_length > logical_size_ - e57_logical(header_.xml_physical_offset))
    throw InputError(fmt::format("{}: header: XML section (offset {}, {} bytes) lies outside the file", name_,
                                 header_.xml_physical_offset, header_.xml_logical_length));
}

void E57PagedReader::read(std::uint64_t logical, std::size_t size, void* out, std::string_view what) const {
  if (logical > logical_size_ || size > logical_size_ - logical)
    throw InputError(fmt::format("{}: {}: {} bytes at logical offset {} run past the end of the file ({} logical bytes)", name_, what, size,
                                 logical, logical_size_));
  char* dst = static_cast<char*>(out);
  while (size > 0) {
    const std::uint64_t in_page = logical % kE57PagePayload;
    const std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(size, kE57PagePayload - in_page));
    std::memcpy(dst, file_.data() + e57_physical(logical), n);
    dst += n;
    logical += n;
    size -= n;
  }
}

void E57LogicalWriter::append(const void* data, std::size_t size) {
  const char* p = static_cast<const char*>(data);
  bytes_.insert(bytes_.end(), p, p + size);
}

void E57LogicalWriter::pad_to(std::size_t alignment) {
  while (bytes_.size() % alignment != 0) bytes_.push_back(0);
}

void E57LogicalWriter::patch(std::uint64_t logical, const void* data, std::size_t size) {
  std::memcpy(bytes_.data() + logical, data, size);
}

void E57LogicalWriter::write_pages(FileWriter& out) const {
  const std::size_t pages = std::max<std::size_t>(1, (bytes_.size() + kE57PagePayload - 1) / kE57PagePayload);
  char page[kE57PageSize];
  for (std::size_t index = 0; index < pages; ++index) {
    const std::size_t begin = index * kE57PagePayload;
    const std::size_t n = std::min(kE57PagePayload, bytes_.size() - std::min(bytes_.size(), begin));
    if (n > 0) std::memcpy(page, bytes_.data() + begin, n);
    std::memset(page + n, 0, kE57PagePayload - n);
    const std::uint32_t crc = byteswap_value(crc32c(page, kE57PagePayload));  // stored big endian
    std::memcpy(page + kE57PagePayload, &crc, 4);
    out.write(page, kE57PageSize);
  }
}

}  // namespace pointsurf::io::detail
