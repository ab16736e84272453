// Slurm's client commands run with a deadline: their output gathered, a controller that does
// not answer stopped.

#include <fcntl.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>

#include "command.hpp"

extern char** environ;  // NOLINT(readability-redundant-declaration): POSIX, for posix_spawnp

namespace overtake::cluster::command_detail {

namespace {

std::string errno_text(int e) {
  return std::strerror(e);
}

}  // namespace

// Runs argv (looked up in PATH) with standard input from /dev/null, gathering its output,
// for at most `timeout_s`.
CommandResult run_command(const std::vector<std::string>& argv, double timeout_s) {
  CommandResult r;
  int out_pipe[2] = {-1, -1};
  int err_pipe[2] = {-1, -1};
  if (::pipe2(out_pipe, O_CLOEXEC) != 0 || ::pipe2(err_pipe, O_CLOEXEC) != 0) {
    r.err = "cannot make a pipe: " + errno_text(errno);
    for (int fd : {out_pipe[0], out_pipe[1]}) {
      if (fd >= 0) ::close(fd);
    }
    return r;
  }
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&files, out_pipe[1], 1);
  posix_spawn_file_actions_adddup2(&files, err_pipe[1], 2);
  std::vector<std::string> args = argv;
  std::vector<char*> cargs;
  cargs.reserve(args.size() + 1);
  for (auto& a : args) cargs.push_back(a.data());
  cargs.push_back(nullptr);
  pid_t pid = -1;
  const int rc = ::posix_spawnp(&pid, cargs[0], &files, nullptr, cargs.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  ::close(out_pipe[1]);
  ::close(err_pipe[1]);
  if (rc != 0) {
    ::close(out_pipe[0]);
    ::close(err_pipe[0]);
    r.err = argv[0] + ": cannot run it (" + errno_text(rc) + ")";
    if (rc == ENOENT) r.err += "; is Slurm's client installed and on PATH?";
    return r;
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  pollfd fds[2] = {{out_pipe[0], POLLIN, 0}, {err_pipe[0], POLLIN, 0}};
  std::string* sinks[2] = {&r.out, &r.err};
  int open_fds = 2;
  bool timed_out = false;
  while (open_fds > 0) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      timed_out = true;
      break;
    }
    const int n = ::poll(fds, 2, static_cast<int>(std::min<long>(left.count(), 1000)));
    if (n < 0 && errno != EINTR) break;
    for (int i = 0; i < 2; ++i) {
      if (fds[i].fd < 0 || (fds[i].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
      char buf[4096];
      const ssize_t got = ::read(fds[i].fd, buf, sizeof buf);
      if (got > 0) {
        sinks[i]->append(buf, static_cast<std::size_t>(got));
      } else if (got == 0 || errno != EINTR) {
        ::close(fds[i].fd);
        fds[i].fd = -1;
        --open_fds;
      }
    }
  }
  for (auto& f : fds) {
    if (f.fd >= 0) ::close(f.fd);
  }
  if (timed_out) ::kill(pid, SIGKILL);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (timed_out) {
    r.err = argv[0] + ": no answer in " + std::to_string(static_cast<int>(timeout_s)) + " s";
    r.status = -1;
  } else if (WIFEXITED(status)) {
    r.status = WEXITSTATUS(status);
  } else {
    r.err += argv[0] + ": ended by signal " + std::to_string(WTERMSIG(status));
  }
  return r;
}

std::string trimmed(std::string_view s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  if (b == std::string_view::npos) return "";
  const auto e = s.find_last_not_of(" \t\r\n");
  return std::string(s.substr(b, e - b + 1));
}

// The last line of `text` that is not empty, at most `max` characters.
std::string last_line(std::string_view text, std::size_t max) {
  std::string line;
  std::size_t end = text.size();
  while (end > 0) {
    const auto start = text.rfind('\n', end - 1);
    const std::size_t from = start == std::string_view::npos ? 0 : start + 1;
    line = trimmed(text.substr(from, end - from));
    if (!line.empty()) break;
    if (start == std::string_view::npos) break;
    end = start;
  }
  if (line.size() > max) line = line.substr(0, max) + "...";
  return line;
}

std::string command_error(const std::vector<std::string>& argv, const CommandResult& r) {
  std::string what = last_line(r.err);
  if (what.empty()) what = last_line(r.out);
  if (what.empty()) what = "exit status " + std::to_string(r.status);
  while (what.rfind(argv[0] + ": ", 0) == 0) what = what.substr(argv[0].size() + 2);
  return argv[0] + ": " + what;
}

}  // namespace overtake::cluster::command_detail
