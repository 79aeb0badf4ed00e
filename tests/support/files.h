// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// File and error helpers shared by the io and cli tests.
#include <cstddef>
#include <cstring>
#include <exception>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace pointsurf::test {

/// Stores `value` at byte `at` of `s` in host byte order (hand-built binary files).
template <typename T>
void put(std::string& s, std::size_t at, T value) {
  std::memcpy(s.data() + at, &value, sizeof(T));
}
/// The value of type T at byte `at` of `s`, in host byte order.
template <typename T>
T get(const std::string& s, std::size_t at) {
  T value;
  std::memcpy(&value, s.data() + at, sizeof(T));
  return value;
}
/// Writes `bytes` to `path` (binary) and returns the path.
std::filesystem::path write_bytes(const std::filesystem::path& path, const std::string& bytes);
/// The whole content of `path` ("" when it cannot be read).
std::string read_bytes(const std::filesystem::path& path);
/// Whether `text` contains `part`.
inline bool contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

/// Runs `f` and returns the message of the exception of type E it throws; records a test
/// failure (and returns "") when it throws nothing or another type.
template <typename E, typename F>
std::string error_of(F&& f) {
  try {
    f();
  } catch (const E& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type: " << e.what();
    return {};
  }
  ADD_FAILURE() << "no exception";
  return {};
}

/// Expects `fn` to throw E with a message containing `part`.
template <typename E, typename Fn>
void expect_error(Fn fn, const std::string& part) {
  try {
    fn();
    ADD_FAILURE() << "no exception; expected one containing: " << part;
  } catch (const E& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << "message: " << e.what() << "\nexpected to contain: " << part;
  }
}

}  // namespace pointsurf::test
