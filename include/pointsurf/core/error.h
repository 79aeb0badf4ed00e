// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The error policy of pointsurf.
//
// Every public function reports bad input by throwing a subclass of pointsurf::Error whose
// message says what went wrong, where (file, line, element index or byte offset) and what was
// expected, e.g. "read_ply: scan.ply: vertex 1532: expected 3 values, file ends".
// An outcome that is a valid answer (an ICP that did not converge) is part of the result
// instead. Only the front ends catch: the command-line tool prints and turns the kind into an
// exit code (0 ok, 1 UsageError, 2 InputError, 3 ComputeError and CancelledError), Python
// raises its own classes of the same names.
//
// An error is data: its kind, its message and where it happened (ErrorPlace: the pipeline and
// stage, the parameter key, the data file and the place in it). Code that knows more adds it
// while the error passes (the pipeline names the stage, a reader the file) and rethrows the
// same object, so the kind is kept. Each front end writes the error in its own words from
// those fields (`pointsurf normals` writes the key as --k, Python as the stage's function
// name); what() is the pipeline's wording:
//   "examples/kitten_mesh.json: stage 2 (normals): k: 0 is out of range [1, inf)"
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace pointsurf {

/// What kind of failure: the caller's request, the input data, or the computation.
enum class ErrorKind { Usage, Input, Compute, Cancelled };

/// "usage", "input", "compute", "cancelled".
const char* error_kind_name(ErrorKind kind) noexcept;

/// Where an error happened, as far as the code that threw or passed it on knew. Empty fields
/// are unknown.
struct ErrorPlace {
  std::string origin;           // the pipeline's source: its file, "cli", "pointsurf.normals"
  std::size_t stage_index = 0;  // 1-based position of the stage in the pipeline; 0: none
  std::string stage;            // the stage's type ("normals")
  std::string key;              // the parameter the error is about (a front end writes it its own
                                // way where the message starts with it)
  std::string file;             // the data file being read or written
  std::string offset;           // the place in that file ("line 12", "byte 4096", "vertex 1532")

  ErrorPlace() = default;
  /// The pipeline `origin`, and the stage at 1-based `index` of type `type` when given.
  ErrorPlace(std::string origin_, std::size_t index = 0, std::string type = {})
      : origin(std::move(origin_)), stage_index(index), stage(std::move(type)) {}
};

/// Base of every exception pointsurf throws on purpose.
class Error : public std::runtime_error {
public:
  explicit Error(std::string message, ErrorPlace place = {});
  /// The kind, from the class: UsageError, InputError, ComputeError, CancelledError.
  virtual ErrorKind kind() const noexcept { return ErrorKind::Compute; }
  /// Process exit code of the command-line tool for this kind of error.
  int exit_code() const noexcept;
  /// What went wrong, without the pipeline's prefix (the stage). Messages about a parameter
  /// start with its key ("k: 0 is out of range [1, inf)"), except the library's own checks,
  /// which name their function first ("estimate_normals: k must be >= 1, got 0").
  const std::string& message() const noexcept { return message_; }
  const ErrorPlace& place() const noexcept { return place_; }
  /// The pipeline's wording: "ORIGIN: stage N (TYPE): MESSAGE" with the parts that are known.
  const char* what() const noexcept override { return text_.c_str(); }

  /// Adds the stage the error happened in (the pipeline does, then rethrows with `throw;`).
  /// An origin or index already set is kept: the innermost pipeline knows best.
  void set_stage(std::string origin, std::size_t index, std::string stage);
  /// Names the parameter key.
  void set_key(std::string key);
  /// Names the data file and, when known, the place in it (unless already named).
  void set_file(std::string file, std::string offset = {});

private:
  void update();
  std::string message_;
  ErrorPlace place_;
  std::string text_;
};

/// A parameter out of range or an unknown option (k < 1, negative radius). Exit code 1.
class UsageError : public Error {
public:
  using Error::Error;
  ErrorKind kind() const noexcept override { return ErrorKind::Usage; }
};

/// Unreadable, malformed or unsupported input data. Exit code 2.
class InputError : public Error {
public:
  using Error::Error;
  ErrorKind kind() const noexcept override { return ErrorKind::Input; }
};

/// A failure while computing (cancelled, degenerate data a method cannot handle). Exit code 3.
class ComputeError : public Error {
public:
  using Error::Error;
  ErrorKind kind() const noexcept override { return ErrorKind::Compute; }
};

/// Thrown when a progress callback asked to stop. Exit code 3.
class CancelledError : public ComputeError {
public:
  CancelledError() : ComputeError("cancelled") {}
  using ComputeError::ComputeError;
  ErrorKind kind() const noexcept override { return ErrorKind::Cancelled; }
};

/// A UsageError about parameter `key`: "KEY: TEXT" (or "KEY TEXT" when TEXT starts with a
/// space or a comma), with the key recorded.
UsageError key_error(std::string_view key, const std::string& text);

}  // namespace pointsurf
