// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/cli_run.h"

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <sstream>
#include <thread>
#include <vector>

#include "support/files.h"

namespace pointsurf::test {

RunResult run_cli(const std::string& args, const std::filesystem::path& dir) {
  const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string command = std::string(POINTSURF_CLI_PATH) + " " + args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(command.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = read_bytes(out);
  r.err = read_bytes(err);
  return r;
}

InterruptedRun run_cli_interrupted(const std::string& args, const std::filesystem::path& dir, const std::string& after) {
  const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  std::vector<std::string> words{POINTSURF_CLI_PATH};
  std::istringstream split(args);
  for (std::string w; split >> w;) words.push_back(w);
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&files, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawnattr_t attributes;
  posix_spawnattr_init(&attributes);
  sigset_t defaults;
  sigemptyset(&defaults);
  sigaddset(&defaults, SIGINT);
  posix_spawnattr_setsigdefault(&attributes, &defaults);  // a ctest in a background job inherits SIGINT ignored
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF);
  pid_t pid = 0;
  InterruptedRun run;
  const int spawned = posix_spawn(&pid, argv[0], &files, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  posix_spawnattr_destroy(&attributes);
  if (spawned != 0) return run;
  int status = 0;
  bool ended = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(120);
  while (!ended && std::chrono::steady_clock::now() < deadline) {
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      ended = true;  // before the text appeared
    } else if (read_bytes(err).find(after) != std::string::npos) {
      run.interrupted = ::kill(pid, SIGINT) == 0;
      ended = ::waitpid(pid, &status, 0) == pid;
    } else {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  if (!ended) {  // the text never came: no process is left behind
    ::kill(pid, SIGKILL);
    ::waitpid(pid, &status, 0);
  }
  run.result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  run.result.out = read_bytes(out);
  run.result.err = read_bytes(err);
  return run;
}

}  // namespace pointsurf::test
