// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The error policy of pointsurf.
//
// Every public function reports bad input by throwing a subclass of pointsurf::Error whose
// message says what went wrong, where (file, line, element index or byte offset) and what was
// expected, e.g. "read_ply: scan.ply: vertex 1532: expected 3 values, file ends".
// An outcome that is a valid answer (an ICP that did not converge) is part of the result
// instead. Only the command-line tool catches, prints and turns these into exit codes:
//   0 ok, 1 UsageError, 2 InputError, 3 ComputeError.
#include <stdexcept>
#include <string>

namespace pointsurf {

/// Base of every exception pointsurf throws on purpose.
class Error : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
  /// Process exit code the CLI uses for this kind of error.
  virtual int exit_code() const noexcept { return 3; }
};

/// A parameter out of range or an unknown option (k < 1, negative radius). Exit code 1.
class UsageError : public Error {
public:
  using Error::Error;
  int exit_code() const noexcept override { return 1; }
};

/// Unreadable, malformed or unsupported input data. Exit code 2.
class InputError : public Error {
public:
  using Error::Error;
  int exit_code() const noexcept override { return 2; }
};

/// A failure while computing (cancelled, degenerate data a method cannot handle). Exit code 3.
class ComputeError : public Error {
public:
  using Error::Error;
  int exit_code() const noexcept override { return 3; }
};

/// Thrown when a progress callback asked to stop.
class CancelledError : public ComputeError {
public:
  CancelledError() : ComputeError("cancelled") {}
  using ComputeError::ComputeError;
};

}  // namespace pointsurf
