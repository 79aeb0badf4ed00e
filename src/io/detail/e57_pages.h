// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The paged layer of an E57 file (ASTM E2807, section 7): the file is a sequence of 1024-byte
// pages, each 1020 bytes of payload followed by the CRC-32C (Castagnoli) of that payload,
// stored big endian. Offsets in the file header and the XML are physical (byte offsets in the
// file); the sections themselves are contiguous in the logical byte stream that leaves the
// checksums out.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace pointsurf::io::detail {

class FileWriter;

constexpr std::size_t kE57PageSize = 1024;
constexpr std::size_t kE57PagePayload = 1020;
constexpr std::size_t kE57HeaderSize = 48;

/// CRC-32C (reflected polynomial 0x82F63B78, initial and final value 0xFFFFFFFF) of `size`
/// bytes; uses the SSE4.2 instruction where the processor has it.
std::uint32_t crc32c(const void* data, std::size_t size) noexcept;

/// Physical offset of logical offset `logical`, and back (the second is exact only for a
/// physical offset that lies in a page's payload: check `is_payload_offset` first).
inline std::uint64_t e57_physical(std::uint64_t logical) noexcept {
  return logical / kE57PagePayload * kE57PageSize + logical % kE57PagePayload;
}
inline std::uint64_t e57_logical(std::uint64_t physical) noexcept {
  return physical / kE57PageSize * kE57PagePayload + physical % kE57PageSize;
}
inline bool is_payload_offset(std::uint64_t physical) noexcept { return physical % kE57PageSize < kE57PagePayload; }

/// The fixed 48-byte file header at offset 0.
struct E57Header {
  std::uint32_t major = 1, minor = 0;
  std::uint64_t file_physical_length = 0;
  std::uint64_t xml_physical_offset = 0;
  std::uint64_t xml_logical_length = 0;
  std::uint64_t page_size = kE57PageSize;
};

/// Read access to the logical bytes of a whole E57 file held in memory. The constructor checks
/// the header and the checksum of every page, and throws InputError naming `name` and the page
/// (or the header field) that is wrong.
class E57PagedReader {
public:
  E57PagedReader(std::string_view file, std::string name);
  const E57Header& header() const noexcept { return header_; }
  /// Number of logical bytes (payload of every page).
  std::uint64_t logical_size() const noexcept { return logical_size_; }
  /// Copies `size` logical bytes from `logical` into `out`; throws InputError naming `what` when
  /// the range runs past the end of the file.
  void read(std::uint64_t logical, std::size_t size, void* out, std::string_view what) const;
  const std::string& name() const noexcept { return name_; }

private:
  std::string_view file_;
  std::string name_;
  E57Header header_;
  std::uint64_t logical_size_ = 0;
};

/// Builds the logical byte stream of an E57 file; `pages()` cuts it into checksummed pages.
class E57LogicalWriter {
public:
  /// Current logical size (the offset of the next byte).
  std::uint64_t size() const noexcept { return bytes_.size(); }
  void append(const void* data, std::size_t size);
  template <typename T>
  void append_value(T value) { append(&value, sizeof(T)); }  // little endian hosts only (checked in io/detail/e57_format.h)
  void pad_to(std::size_t alignment);
  /// Overwrites bytes already written at `logical`.
  void patch(std::uint64_t logical, const void* data, std::size_t size);
  void reserve(std::size_t size) { bytes_.reserve(size); }
  /// The logical bytes written so far.
  std::string_view bytes() const noexcept { return {bytes_.data(), bytes_.size()}; }
  /// Writes the physical file: the logical bytes padded to whole pages, each followed by its CRC.
  void write_pages(FileWriter& out) const;

private:
  std::vector<char> bytes_;
};

}  // namespace pointsurf::io::detail
