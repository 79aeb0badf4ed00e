// SPDX-License-Identifier: GPL-3.0-or-later
#include "io/detail/file_util.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <cmath>
#include <limits>
#include <random>

#include "io/detail/formats.h"

namespace pointsurf::io::detail {

std::string display_name(const std::filesystem::path& path) {
  // Writers get the temporary file that the dispatch renames afterwards
  // ("dir/.scan.las.tmp-1a2b3c4d"); messages name the file the user asked for.
  std::string file = path.filename().string();
  const std::size_t tmp = file.rfind(".tmp-");
  if (file.size() > 1 && file.front() == '.' && tmp != std::string::npos && tmp > 1 && file.size() - tmp == 13) {
    file = file.substr(1, tmp - 1);
    const std::filesystem::path dir = path.parent_path();
    return (dir.empty() ? std::filesystem::path(file) : dir / file).string();
  }
  return path.string();
}

std::string read_file_bytes(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(fmt::format("{}: is a directory, expected a file", display_name(path)));
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throw InputError(fmt::format("{}: cannot open: {}", display_name(path), std::strerror(errno)));
  // Read straight into the final buffer: one copy less than chunked appends.
  std::string bytes;
  long size = -1;
  if (std::fseek(f, 0, SEEK_END) == 0) {
    size = std::ftell(f);
    std::fseek(f, 0, SEEK_SET);
  }
  if (size > 0) {
    bytes.resize(static_cast<std::size_t>(size));
    bytes.resize(std::fread(bytes.data(), 1, bytes.size(), f));
  }
  // Streams whose size is unknown (pipes) or that grew: read the rest in chunks.
  char chunk[1 << 16];
  std::size_t got;
  while ((got = std::fread(chunk, 1, sizeof(chunk), f)) > 0) bytes.append(chunk, got);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throw InputError(fmt::format("{}: read error", display_name(path)));
  return bytes;
}

FileBytes::FileBytes(const std::filesystem::path& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd >= 0) {
    struct stat st {};
    if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && st.st_size > 0) {
      int flags = MAP_PRIVATE;
#ifdef MAP_POPULATE
      flags |= MAP_POPULATE;
#endif
      void* map = ::mmap(nullptr, static_cast<std::size_t>(st.st_size), PROT_READ, flags, fd, 0);
      if (map != MAP_FAILED) {
        map_ = map;
        size_ = static_cast<std::size_t>(st.st_size);
      }
    }
    ::close(fd);
  }
  // Anything that could not be mapped (a pipe, an empty file, an open error) goes through the
  // ordinary reader, which also words the error.
  if (!map_) copy_ = read_file_bytes(path);
}

FileBytes::~FileBytes() {
  if (map_) ::munmap(map_, size_);
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view s) {
  const std::size_t b = s.find_first_not_of(" \t\v\f");
  if (b == std::string_view::npos) return {};
  const std::size_t e = s.find_last_not_of(" \t\v\f");
  return s.substr(b, e - b + 1);
}

std::string shown(std::string_view token) {
  if (token.size() <= 40) return std::string(token);
  return std::string(token.substr(0, 37)) + "...";
}

bool parse_number(std::string_view token, double& out) noexcept {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  const char* first = token.data();
  const char* last = first + token.size();
  auto [ptr, ec] = std::from_chars(first, last, out);
  if (ec == std::errc() && ptr == last) return true;
  if (ec == std::errc::result_out_of_range && ptr == last) {  // denormal or overflow
    out = std::strtod(std::string(token).c_str(), nullptr);
    return true;
  }
  return false;
}

bool parse_number(std::string_view token, long long& out) noexcept {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return false;
  auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), out);
  return ec == std::errc() && ptr == token.data() + token.size();
}

bool TextCursor::next_line(std::string_view& line) noexcept {
  if (pos_ >= text_.size()) return false;
  const std::size_t start = pos_;
  std::size_t end = start;
  const std::size_t n = text_.size();
  while (end < n && text_[end] != '\n' && text_[end] != '\r') ++end;
  line = text_.substr(start, end - start);
  if (end < n && text_[end] == '\r') ++end;
  if (end < n && text_[end] == '\n' && (end == start + line.size() || text_[end - 1] == '\r')) ++end;
  pos_ = end;
  ++line_;
  return true;
}

void split_tokens(std::string_view line, std::vector<std::string_view>& tokens, bool commas) {
  tokens.clear();
  std::size_t i = 0;
  const std::size_t n = line.size();
  auto is_sep = [commas](char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f' || (commas && (c == ',' || c == ';')); };
  while (i < n) {
    while (i < n && is_sep(line[i])) ++i;
    if (i >= n) break;
    std::size_t j = i;
    while (j < n && !is_sep(line[j])) ++j;
    tokens.push_back(line.substr(i, j - i));
    i = j;
  }
}

FileWriter::FileWriter(const std::filesystem::path& path) : path_(path), buffer_(1 << 20) {
  file_ = std::fopen(path.c_str(), "wb");
  if (!file_) throw Error(fmt::format("{}: cannot open for writing: {}", display_name(path), std::strerror(errno)));
}

FileWriter::~FileWriter() {
  if (file_) std::fclose(file_);
}

void FileWriter::flush() {
  if (used_ == 0) return;
  if (std::fwrite(buffer_.data(), 1, used_, file_) != used_)
    throw Error(fmt::format("{}: write failed: {}", display_name(path_), std::strerror(errno)));
  used_ = 0;
}

void FileWriter::write(const void* data, std::size_t size) {
  if (used_ + size > buffer_.size()) {
    flush();
    if (size > buffer_.size()) {
      if (std::fwrite(data, 1, size, file_) != size)
        throw Error(fmt::format("{}: write failed: {}", display_name(path_), std::strerror(errno)));
      return;
    }
  }
  std::memcpy(buffer_.data() + used_, data, size);
  used_ += size;
}

void FileWriter::write_double(double value, int precision) {
  char text[64];
  std::to_chars_result r;
  if (precision >= 17) r = std::to_chars(text, text + sizeof(text), value);
  else r = std::to_chars(text, text + sizeof(text), value, std::chars_format::general, precision);
  write(text, static_cast<std::size_t>(r.ptr - text));
}

void FileWriter::close() {
  if (!file_) return;
  flush();
  const bool failed = std::fflush(file_) != 0 || std::ferror(file_) != 0;
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (failed || rc != 0) throw Error(fmt::format("{}: write failed: {}", display_name(path_), std::strerror(errno)));
}

TemporaryOutput::TemporaryOutput(const std::filesystem::path& target) : target_(target) {
  const std::filesystem::path dir = target.has_parent_path() ? target.parent_path() : std::filesystem::path(".");
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw Error(fmt::format("{}: cannot write: directory '{}' does not exist", display_name(target), dir.string()));
  std::mt19937_64 rng(std::random_device{}() ^ static_cast<std::uint64_t>(::getpid()));
  temp_ = dir / fmt::format(".{}.tmp-{:08x}", target.filename().string(), static_cast<std::uint32_t>(rng()));
}

TemporaryOutput::~TemporaryOutput() {
  if (!committed_) {
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
  }
}

void TemporaryOutput::commit() {
  std::error_code ec;
  std::filesystem::rename(temp_, target_, ec);
  if (ec) throw Error(fmt::format("{}: cannot rename the finished output into place: {}", display_name(target_), ec.message()));
  committed_ = true;
}

}  // namespace pointsurf::io::detail
