#pragma once
// Starting the `overtake` binary from a test and waiting for it (for what only a separate
// process shows: signals, exit statuses, standard output that cannot be written).

#include <chrono>
#include <csignal>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;  // NOLINT(readability-redundant-declaration): POSIX, for posix_spawn

namespace overtake::test {

/// The binary built beside the tests.
inline std::filesystem::path overtake_binary() {
  return std::filesystem::path(OVERTAKE_BINARY_DIR) / "overtake";
}

/// Starts the program all[0] (a path) with arguments all[1..], its stdout into `out` (a path, e.g.
/// /dev/full) and its stderr into `err`; returns its pid. With `out_fd` >= 0, stdout is that
/// descriptor instead (e.g. a pipe's write end).
inline pid_t start_command(std::vector<std::string> all, const std::filesystem::path& out,
                           const std::filesystem::path& err, int out_fd = -1) {
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  if (out_fd >= 0) {
    posix_spawn_file_actions_adddup2(&files, out_fd, 1);
  } else {
    posix_spawn_file_actions_addopen(&files, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  }
  posix_spawn_file_actions_addopen(&files, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &files, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  if (rc != 0) throw std::runtime_error("cannot start " + all.front());
  return pid;
}

/// start_command of the overtake binary with these arguments.
inline pid_t start_overtake(const std::vector<std::string>& args, const std::filesystem::path& out,
                            const std::filesystem::path& err, int out_fd = -1) {
  std::vector<std::string> all = {overtake_binary().string()};
  all.insert(all.end(), args.begin(), args.end());
  return start_command(std::move(all), out, err, out_fd);
}

/// The child's exit status (1000 + the signal when one killed it), or nullopt when it is
/// still running after `timeout` (it is then killed).
inline std::optional<int> exit_status(pid_t pid, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      if (WIFEXITED(status)) return WEXITSTATUS(status);
      return 1000 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
    }
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      return std::nullopt;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace overtake::test
