// Planner programs in processes (and namespaces) of their own: overtake's end, the
// PlannerProcess. It prepares everything the keeper needs, forks it (keeper.cpp), and talks to
// it over the wire (wire.hpp). The keeper and init, forked from a process that may run many
// threads (a bench), never exec and use only async-signal-safe calls: no allocation, no stdio,
// no locks; so everything they use is made here, before the fork.

#include "overtake/sandbox/planner_process.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/pidfd.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <stdexcept>
#include <thread>
#include <vector>

#include "keeper.hpp"
#include "probe.hpp"
#include "wire.hpp"

namespace overtake::sandbox {
namespace {

namespace fs = std::filesystem;

constexpr auto kAnswerTimeout = std::chrono::seconds(10);
// waitid's P_PIDFD (Linux 5.4), which glibc's idtype_t does not name.
constexpr auto kWaitPidfd = static_cast<idtype_t>(3);

std::string status_text(int status) {
  if (WIFEXITED(status)) {
    const int code = WEXITSTATUS(status);
    std::string text = "exited with status " + std::to_string(code);
    // The shell that ran the command reports a program killed by signal N as status 128 + N.
    if (code > 128 && code < 128 + NSIG) {
      const char* name = ::strsignal(code - 128);
      text += " (the shell's account of signal " + std::to_string(code - 128) +
              (name ? std::string(": ") + name : std::string()) + ")";
    }
    return text;
  }
  if (WIFSIGNALED(status)) {
    const int sig = WTERMSIG(status);
    const char* name = ::strsignal(sig);
    return "was killed by signal " + std::to_string(sig) +
           (name ? std::string(" (") + name + ")" : "");
  }
  return "ended (wait status " + std::to_string(status) + ")";
}

void require_directory(const fs::path& cwd) {
  std::error_code ec;
  if (!cwd.empty() && !fs::is_directory(cwd, ec)) {
    throw std::runtime_error("the planner's working directory " + cwd.string() + " does not exist");
  }
}

// The log, created or truncated (its directory made first).
int open_log(const fs::path& path) {
  std::error_code ec;
  if (path.has_parent_path()) fs::create_directories(path.parent_path(), ec);
  const int log = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log < 0) {
    throw std::runtime_error(path.string() + ": cannot write the planner's log (" +
                             std::strerror(errno) + ")");
  }
  return log;
}

// What the keeper is given besides the log: /dev/null and the socket pair (sv[1] is its end).
struct Channel {
  int devnull = -1;
  int sv[2] = {-1, -1};
};

// Opens the channel; on failure closes `log` and throws.
Channel open_channel(int log) {
  Channel c;
  c.devnull = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  if (c.devnull < 0 || ::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, c.sv) != 0) {
    const int err = errno;
    ::close(log);
    if (c.devnull >= 0) ::close(c.devnull);
    throw std::runtime_error(std::string("cannot prepare the planner's process (") +
                             std::strerror(err) + ")");
  }
  return c;
}

// The keeper's texts, made before the fork (the keeper allocates nothing); KeeperPlan points
// into them, so they stay where they are until the fork is done.
struct KeeperTexts {
  char uid_map[64] = {};
  char gid_map[64] = {};
  std::string cwd;
  std::string sh = "sh", dash_c = "-c", command;
  std::vector<char*> argv;

  explicit KeeperTexts(const PlannerProcessOptions& o) {
    self_map(uid_map, sizeof uid_map, ::geteuid());
    self_map(gid_map, sizeof gid_map, ::getegid());
    cwd = o.cwd.string();
    command = o.command;
    argv = {sh.data(), dash_c.data(), command.data(), nullptr};
  }
  KeeperTexts(const KeeperTexts&) = delete;
  KeeperTexts& operator=(const KeeperTexts&) = delete;
};

KeeperPlan keeper_plan(const PlannerProcessOptions& o, const KeeperTexts& texts, int log,
                       const Channel& c, bool namespaces) {
  KeeperPlan plan;
  plan.control = c.sv[1];
  plan.log = log;
  plan.log_max_bytes = o.log_max_bytes;
  plan.devnull = c.devnull;
  plan.parent = ::getpid();
  plan.isolated = o.isolated;
  plan.namespaces = namespaces;
  plan.as_root = ::geteuid() == 0;
  plan.uid_map = texts.uid_map;
  plan.gid_map = texts.gid_map;
  plan.cwd = texts.cwd.empty() ? nullptr : texts.cwd.c_str();
  plan.argv = texts.argv.data();
  return plan;
}

// The go and its answer: "" when the keeper started the program, else why not.
std::string go(int control, unsigned sequence) {
  wire::Message m;
  if (wire::send_request(control, wire::kGo, sequence, 0) &&
      wire::receive_answer(control, sequence, m, nullptr, kAnswerTimeout) &&
      m.kind == wire::kStarted) {
    return "";
  }
  if (m.kind == wire::kFailed) {
    return m.a == kStepUnshare ? namespace_advice(m.a, m.b) : step_text(m.a, m.b);
  }
  return "the planner's keeper process did not start within " +
         std::to_string(kAnswerTimeout.count()) + " s";
}

}  // namespace

std::optional<PlannerNetwork> parse_planner_network(std::string_view text) {
  if (text == "auto") return PlannerNetwork::automatic;
  if (text == "isolated") return PlannerNetwork::isolated;
  if (text == "host") return PlannerNetwork::host;
  return std::nullopt;
}

PlannerProcess::PlannerProcess(const PlannerProcessOptions& o) {
  require_directory(o.cwd);
  // Asked as automatic when not isolated: the PID namespace is had wherever the machine allows.
  const NetworkCheck net =
      check_planner_network(o.isolated ? PlannerNetwork::isolated : PlannerNetwork::automatic);
  if (net.refused) throw std::runtime_error(net.why);
  const bool namespaces = net.namespaces && (o.namespaces || o.isolated);
  containment_ = namespaces ? Containment::pid_namespace : Containment::subreaper;
  const int log = open_log(o.log);
  const Channel channel = open_channel(log);
  const KeeperTexts texts(o);  // everything the keeper needs, made before the fork
  const KeeperPlan plan = keeper_plan(o, texts, log, channel, namespaces);

  const pid_t pid = ::fork();
  if (pid == 0) keeper_main(plan);
  const int fork_errno = errno;
  ::close(channel.sv[1]);
  ::close(log);
  ::close(channel.devnull);
  if (pid < 0) {
    ::close(channel.sv[0]);
    throw std::runtime_error(std::string("cannot start the planner program (fork: ") +
                             std::strerror(fork_errno) + ")");
  }
  keeper_ = pid;
  control_ = channel.sv[0];
  // The keeper waits for the go before it can end, so the pid is still its own here; from
  // now on it is signalled and waited for through the pidfd only (no reused pid is hit).
  keeper_fd_ = static_cast<int>(::syscall(SYS_pidfd_open, pid, 0));
  if (keeper_fd_ >= 0) (void)::fcntl(keeper_fd_, F_SETFD, FD_CLOEXEC);
  const std::string failed = go(control_, ++sequence_);
  if (!failed.empty()) {
    stop(0.0);
    throw std::runtime_error(failed);
  }
}

PlannerProcess::~PlannerProcess() {
  stop();
}

void PlannerProcess::kill_keeper() {
  if (control_ >= 0) {
    ::close(control_);
    control_ = -1;
  }
  if (keeper_ < 0) return;
  if (keeper_fd_ >= 0) {
    (void)::syscall(SYS_pidfd_send_signal, keeper_fd_, SIGKILL, nullptr, 0U);
    siginfo_t info{};
    (void)::waitid(kWaitPidfd, static_cast<id_t>(keeper_fd_), &info, WEXITED);
    ::close(keeper_fd_);
    keeper_fd_ = -1;
  } else if (::waitpid(keeper_, nullptr, WNOHANG) == 0) {  // not reaped: still the keeper's pid
    ::kill(keeper_, SIGKILL);
    ::waitpid(keeper_, nullptr, 0);
  }
  keeper_ = -1;
}

bool PlannerProcess::request(char what, int arg, std::string* text, int* fd) {
  if (control_ < 0) return false;
  const unsigned seq = ++sequence_;
  wire::Message m;
  if (!wire::send_request(control_, what, seq, arg) ||
      !wire::receive_answer(control_, seq, m, fd, kAnswerTimeout)) {
    // A keeper that does not answer is of no more use, and its answers could come late.
    if (ended_.empty()) ended_ = "is gone (its keeper process stopped answering)";
    kill_keeper();
    return false;
  }
  if (text && m.kind == wire::kExited) *text = status_text(m.a);
  if (text && m.kind == wire::kGone) *text = "is gone (its init process ended without a status)";
  return m.kind != wire::kNone;
}

int PlannerProcess::open_socket() {
  int fd = -1;
  if (!request(wire::kSocket, 0, nullptr, &fd)) return -1;
  return fd;
}

std::string PlannerProcess::ended() {
  if (!ended_.empty() || control_ < 0) return ended_;
  std::string text;
  if (!request(wire::kStatus, 0, &text, nullptr)) return ended_.empty() ? "is gone" : ended_;
  ended_ = text;
  return ended_;
}

void PlannerProcess::stop(double grace_s) {
  if (keeper_ < 0) return;
  if (control_ >= 0) {
    const int grace_ms = static_cast<int>(std::clamp(grace_s, 0.0, 3600.0) * 1000.0);
    const unsigned seq = ++sequence_;
    wire::Message m;
    if (wire::send_request(control_, wire::kStop, seq, grace_ms) &&
        wire::receive_answer(control_, seq, m, nullptr,
                             std::chrono::milliseconds(grace_ms + 6000)) &&
        m.kind == wire::kDone && m.a == 1 && ended_.empty()) {
      ended_ = status_text(m.b);
    }
    ::close(control_);
    control_ = -1;
  }
  // The keeper exits after stopping the program: wait for it a moment, else end it.
  if (keeper_fd_ >= 0) {
    pollfd pfd{keeper_fd_, POLLIN, 0};
    (void)::poll(&pfd, 1, 2000);
  } else {
    for (int i = 0; i < 200; ++i) {
      const pid_t r = ::waitpid(keeper_, nullptr, WNOHANG);
      if (r == keeper_ || (r < 0 && errno == ECHILD)) {  // ECHILD: SIGCHLD is ignored here
        keeper_ = -1;
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }
  kill_keeper();
}

}  // namespace overtake::sandbox
