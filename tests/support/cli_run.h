// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Runs the built pointsurf command line (POINTSURF_CLI_PATH) for the end-to-end tests.
#include <filesystem>
#include <string>

namespace pointsurf::test {

struct RunResult {
  int exit_code = -1;  // the process's exit status; -1 when it did not exit normally
  std::string out, err;
};

/// Runs `pointsurf ARGS` through the shell with stdout and stderr captured in files under `dir`.
RunResult run_cli(const std::string& args, const std::filesystem::path& dir);
/// Runs the CLI with `args` (split at spaces; no quoting), SIGINT at its default whatever this
/// process inherited, and sends it SIGINT once its stderr holds `after` (as Ctrl-C would). The
/// result's exit code is -1 if the process did not exit normally; `interrupted` says whether the
/// signal was sent before it ended.
struct InterruptedRun {
  RunResult result;
  bool interrupted = false;
};
InterruptedRun run_cli_interrupted(const std::string& args, const std::filesystem::path& dir, const std::string& after);

}  // namespace pointsurf::test
