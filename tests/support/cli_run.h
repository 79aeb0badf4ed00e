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

}  // namespace pointsurf::test
