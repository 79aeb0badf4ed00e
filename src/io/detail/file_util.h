// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Small shared helpers for the format readers and writers: whole-file reading, a text cursor
// with line numbers, number parsing with std::from_chars, byte swapping and a buffered writer.
#include <bit>
#include <charconv>
#include <cmath>
#include <limits>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <iterator>
#include <string>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {

/// The whole file in memory. Throws InputError when it cannot be opened or read.
std::string read_file_bytes(const std::filesystem::path& path);

/// The bytes of a file, memory-mapped when possible (a copy otherwise: pipes, special files).
/// Mapping avoids copying a large body into freshly allocated memory, whose first touch costs
/// as much as decoding it. Throws InputError like read_file_bytes.
class FileBytes {
public:
  explicit FileBytes(const std::filesystem::path& path);
  ~FileBytes();
  FileBytes(const FileBytes&) = delete;
  FileBytes& operator=(const FileBytes&) = delete;
  std::string_view view() const { return map_ ? std::string_view(static_cast<const char*>(map_), size_) : std::string_view(copy_); }

private:
  void* map_ = nullptr;
  std::size_t size_ = 0;
  std::string copy_;
};

/// ASCII lower case.
std::string lower(std::string_view s);
/// `s` without leading and trailing blanks (space, tab, vertical tab, form feed).
std::string_view trim(std::string_view s);
/// A token for an error message, cut short when it is long (binary junk, a wrong file).
std::string shown(std::string_view token);

/// Parses a whole token as a number; false when the token is not entirely a number.
/// Accepts a leading '+', "nan", "inf" (any case) for floating types.
bool parse_number(std::string_view token, double& out) noexcept;
bool parse_number(std::string_view token, long long& out) noexcept;

template <typename T>
T byteswap_value(T value) noexcept {
  static_assert(std::is_trivially_copyable_v<T>);
  unsigned char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(bytes[i], bytes[sizeof(T) - 1 - i]);
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

/// A field value (held as double) in a file's storage type T. Floating types convert; integer
/// types round and saturate (a value outside T's range is clamped, NaN becomes 0), since a
/// writer cannot refuse one odd value of a field.
template <typename T>
T to_stored(double v) noexcept {
  if constexpr (std::is_floating_point_v<T>) {
    return static_cast<T>(v);
  } else {
    if (!(v == v)) return 0;
    const double r = std::round(v);
    if (r <= static_cast<double>(std::numeric_limits<T>::min())) return std::numeric_limits<T>::min();
    // The max of a 64-bit type rounds up to 2^63 or 2^64 as a double: compare with >=.
    if (r >= static_cast<double>(std::numeric_limits<T>::max())) return std::numeric_limits<T>::max();
    return static_cast<T>(r);
  }
}

/// Reads a T stored little endian (big endian when `big`) at `p`.
template <typename T>
T load_value(const char* p, bool big = false) noexcept {
  T value;
  std::memcpy(&value, p, sizeof(T));
  if (big != (std::endian::native == std::endian::big)) value = byteswap_value(value);
  return value;
}

/// Line-oriented cursor over text held in memory; tracks the 1-based line number.
class TextCursor {
public:
  explicit TextCursor(std::string_view text) : text_(text) {}
  /// Next line without its terminator ("\n", "\r\n" or "\r"); false at the end of the text.
  bool next_line(std::string_view& line) noexcept;
  /// Line number of the line last returned (1-based).
  std::size_t line_number() const noexcept { return line_; }
  /// Byte offset of the first byte not yet consumed.
  std::size_t offset() const noexcept { return pos_; }
  bool at_end() const noexcept { return pos_ >= text_.size(); }

private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::size_t line_ = 0;
};

/// Splits `line` at whitespace (and at commas when `commas`), skipping empty tokens.
/// Reuses `tokens` to avoid allocation per line.
void split_tokens(std::string_view line, std::vector<std::string_view>& tokens, bool commas = false);

/// Buffered binary/text output to a file opened for writing; throws Error on any failure.
class FileWriter {
public:
  explicit FileWriter(const std::filesystem::path& path);
  ~FileWriter();
  FileWriter(const FileWriter&) = delete;
  FileWriter& operator=(const FileWriter&) = delete;

  void write(const void* data, std::size_t size);
  void write(std::string_view text) { write(text.data(), text.size()); }
  /// Appends formatted text; per-record lines go through fmt's inline buffer, not a std::string.
  template <typename... Args>
  void print(fmt::format_string<Args...> format, Args&&... args) {
    fmt::memory_buffer text;
    fmt::format_to(std::back_inserter(text), format, std::forward<Args>(args)...);
    write(text.data(), text.size());
  }
  template <typename T>
  void write_value(T value, bool big = false) {
    if (big != (std::endian::native == std::endian::big)) value = byteswap_value(value);
    write(&value, sizeof(T));
  }
  /// Appends a double in shortest round-trip form (or with `precision` significant digits).
  void write_double(double value, int precision = 17);
  /// Flushes and closes; throws on failure. Called by the destructor without throwing.
  void close();

private:
  void flush();
  std::FILE* file_ = nullptr;
  std::filesystem::path path_;
  std::vector<char> buffer_;
  std::size_t used_ = 0;
};

/// A temporary file next to the target, renamed over it on commit(), removed otherwise: an
/// output is whole or absent. Throws Error when the directory does not exist.
class TemporaryOutput {
public:
  explicit TemporaryOutput(const std::filesystem::path& target);
  ~TemporaryOutput();
  TemporaryOutput(const TemporaryOutput&) = delete;
  TemporaryOutput& operator=(const TemporaryOutput&) = delete;
  const std::filesystem::path& path() const { return temp_; }
  void commit();

private:
  std::filesystem::path target_, temp_;
  bool committed_ = false;
};

}  // namespace pointsurf::io::detail
