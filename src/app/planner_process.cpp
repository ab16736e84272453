// Planner programs in processes (and networks) of their own. The keeper, forked from a
// process that may run many threads (a bench), uses only async-signal-safe calls between
// fork and exec: everything it needs is prepared before the fork.

#include "overtake/app/planner_process.hpp"

#include <fcntl.h>
#include <net/if.h>
#include <poll.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

namespace overtake::app {
namespace {

// Requests to the keeper and its answers (one byte each, some with a payload).
constexpr char kSocket = 'S';   // -> kFd with the descriptor, or kNone
constexpr char kStatus = 'W';   // -> kRunning, or kExited with the wait status
constexpr char kStop = 'K';     // (payload: grace in ms) -> kDone, then the keeper exits
constexpr char kStarted = 'O';  // first message: started (payload: the program's pid)
constexpr char kFailed = 'E';   // first message: failed (payload: step, errno)
constexpr char kFd = 'F';
constexpr char kNone = 'N';
constexpr char kRunning = 'R';
constexpr char kExited = 'X';
constexpr char kDone = 'D';

// Steps of the keeper's start that can fail, for the parent's message.
enum Step : int {
  kStepUnshare = 1,
  kStepSetgroups,
  kStepUidMap,
  kStepGidMap,
  kStepLoopback,
  kStepFork,
};

constexpr auto kAnswerTimeout = std::chrono::seconds(10);

struct Message {
  char kind = 0;
  int a = 0;
  int b = 0;
};

// ---- the keeper's side (async-signal-safe only) -------------------------------------------

void send_message(int fd, char kind, int a = 0, int b = 0) {
  char buf[1 + 2 * sizeof(int)];
  buf[0] = kind;
  std::memcpy(buf + 1, &a, sizeof a);
  std::memcpy(buf + 1 + sizeof a, &b, sizeof b);
  (void)::send(fd, buf, sizeof buf, MSG_NOSIGNAL);
}

// A message of one buffer with room for one descriptor beside it.
struct FdMessage {
  iovec iov{};
  alignas(cmsghdr) char space[CMSG_SPACE(sizeof(int))] = {};
  msghdr msg{};
  FdMessage(void* data, std::size_t size) : iov{data, size} {
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = space;
    msg.msg_controllen = sizeof space;
  }
  FdMessage(const FdMessage&) = delete;
  FdMessage& operator=(const FdMessage&) = delete;
};

void send_fd(int control, int fd) {
  char kind = kFd;
  FdMessage m(&kind, 1);
  msghdr& msg = m.msg;
  cmsghdr* c = CMSG_FIRSTHDR(&msg);
  c->cmsg_level = SOL_SOCKET;
  c->cmsg_type = SCM_RIGHTS;
  c->cmsg_len = CMSG_LEN(sizeof(int));
  std::memcpy(CMSG_DATA(c), &fd, sizeof fd);
  (void)::sendmsg(control, &msg, MSG_NOSIGNAL);
}

bool write_all(const char* path, const char* text) {
  const int fd = ::open(path, O_WRONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const std::size_t n = std::strlen(text);
  const bool ok = ::write(fd, text, n) == static_cast<ssize_t>(n);
  ::close(fd);
  return ok;
}

bool loopback_up() {
  const int s = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (s < 0) return false;
  ifreq ifr{};
  std::memcpy(ifr.ifr_name, "lo", 3);
  bool ok = ::ioctl(s, SIOCGIFFLAGS, &ifr) == 0;
  if (ok) {
    ifr.ifr_flags = static_cast<short>(ifr.ifr_flags | IFF_UP | IFF_RUNNING);
    ok = ::ioctl(s, SIOCSIFFLAGS, &ifr) == 0;
  }
  ::close(s);
  return ok;
}

void default_signals() {
  sigset_t none;
  sigemptyset(&none);
  sigprocmask(SIG_SETMASK, &none, nullptr);
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  for (int sig = 1; sig < NSIG; ++sig) {
    if (sig != SIGKILL && sig != SIGSTOP) sigaction(sig, &dfl, nullptr);
  }
}

double now_ms() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) / 1e6;
}

// The program's output: read from its pipe, written to the log up to a budget; past it the
// rest is read and dropped (so that the program never blocks on a full pipe), after a line
// that says so.
struct LogSink {
  int pipe = -1;  // read end, non-blocking; -1 once every writer has closed it
  int file = -1;
  long long left = 0;
  bool cut_noted = false;
};

void drain(LogSink& sink) {
  static char buf[65536];  // the keeper is single-threaded
  while (sink.pipe >= 0) {
    const ssize_t n = ::read(sink.pipe, buf, sizeof buf);
    if (n == 0) {
      ::close(sink.pipe);
      sink.pipe = -1;
      return;
    }
    if (n < 0) {
      if (errno == EINTR) continue;
      return;  // EAGAIN: nothing more for now
    }
    const long long keep = std::min<long long>(n, sink.left);
    if (keep > 0) {
      (void)::write(sink.file, buf, static_cast<std::size_t>(keep));
      sink.left -= keep;
    }
    if (keep < n && !sink.cut_noted) {
      const char note[] =
          "\n[overtake: the log is cut here, at its size limit "
          "(--planner-log-max-mb); the rest of the output was dropped]\n";
      (void)::write(sink.file, note, sizeof note - 1);
      sink.cut_noted = true;
    }
  }
}

// Stops the program's process group: SIGTERM, up to `grace_ms` for it to go, then SIGKILL.
// Returns the program's wait status (kept in `status` when it had already been reaped).
void stop_group(pid_t program, int grace_ms, bool& reaped, int& status, LogSink& sink) {
  ::kill(-program, SIGTERM);
  const double until = now_ms() + grace_ms;
  while (!reaped && now_ms() < until) {
    drain(sink);
    if (::waitpid(program, &status, WNOHANG) == program) {
      reaped = true;
      break;
    }
    ::poll(nullptr, 0, 10);
  }
  ::kill(-program, SIGKILL);  // what is left of the group (children of the shell)
  if (!reaped && ::waitpid(program, &status, 0) == program) reaped = true;
  drain(sink);  // what it wrote last
}

struct KeeperPlan {
  int control = -1;
  int log = -1;
  long long log_max_bytes = 0;
  int devnull = -1;
  pid_t parent = 0;
  bool isolated = false;
  bool as_root = false;
  const char* uid_map = nullptr;
  const char* gid_map = nullptr;
  const char* cwd = nullptr;  // may be null
  char* const* argv = nullptr;
};

[[noreturn]] void keeper_main(const KeeperPlan& p) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != p.parent) _exit(1);  // the parent is already gone
  ::setpgid(0, 0);                        // Ctrl-C at the terminal is the parent's to handle
  default_signals();
  ::signal(SIGINT, SIG_IGN);
  const auto fail = [&](int step) {
    send_message(p.control, kFailed, step, errno);
    _exit(1);
  };
  if (p.isolated) {
    if (::unshare(p.as_root ? CLONE_NEWNET : CLONE_NEWUSER | CLONE_NEWNET) != 0) fail(kStepUnshare);
    if (!p.as_root) {
      if (!write_all("/proc/self/setgroups", "deny")) fail(kStepSetgroups);
      if (!write_all("/proc/self/uid_map", p.uid_map)) fail(kStepUidMap);
      if (!write_all("/proc/self/gid_map", p.gid_map)) fail(kStepGidMap);
    }
    if (!loopback_up()) fail(kStepLoopback);
  }
  int out[2] = {-1, -1};
  if (::pipe2(out, O_CLOEXEC) != 0) fail(kStepFork);
  const pid_t program = ::fork();
  if (program < 0) fail(kStepFork);
  if (program == 0) {
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    ::signal(SIGINT, SIG_DFL);
    ::dup2(p.devnull, 0);
    ::dup2(out[1], 1);
    ::dup2(out[1], 2);
    if (p.cwd && ::chdir(p.cwd) != 0) {
      const char msg[] = "overtake: cannot enter the planner's working directory\n";
      (void)::write(2, msg, sizeof msg - 1);
      _exit(127);
    }
    ::execv("/bin/sh", p.argv);
    const char msg[] = "overtake: cannot run /bin/sh\n";
    (void)::write(2, msg, sizeof msg - 1);
    _exit(127);
  }
  ::setpgid(program, program);  // also here: whichever runs first
  ::close(out[1]);
  ::close(p.devnull);
  ::fcntl(out[0], F_SETFL, ::fcntl(out[0], F_GETFL) | O_NONBLOCK);
  LogSink sink{out[0], p.log, p.log_max_bytes, false};
  send_message(p.control, kStarted, program);

  bool reaped = false;
  int status = 0;
  for (;;) {
    if (!reaped && ::waitpid(program, &status, WNOHANG) == program) reaped = true;
    pollfd pfd[2] = {{p.control, POLLIN, 0}, {sink.pipe, POLLIN, 0}};
    const int r = ::poll(pfd, sink.pipe >= 0 ? 2 : 1, 50);
    if (r <= 0) continue;
    if (sink.pipe >= 0 && (pfd[1].revents & (POLLIN | POLLHUP | POLLERR)) != 0) drain(sink);
    if ((pfd[0].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
    char buf[16];
    const ssize_t n = ::recv(p.control, buf, sizeof buf, 0);
    if (n <= 0) {  // the parent closed its end (or is gone): stop at once
      stop_group(program, 0, reaped, status, sink);
      _exit(0);
    }
    if (buf[0] == kSocket) {
      const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
      if (fd < 0) {
        send_message(p.control, kNone, errno);
      } else {
        send_fd(p.control, fd);
        ::close(fd);
      }
    } else if (buf[0] == kStatus) {
      if (!reaped && ::waitpid(program, &status, WNOHANG) == program) reaped = true;
      send_message(p.control, reaped ? kExited : kRunning, status);
    } else if (buf[0] == kStop) {
      int grace_ms = 0;
      if (n >= static_cast<ssize_t>(1 + sizeof(int))) std::memcpy(&grace_ms, buf + 1, sizeof(int));
      stop_group(program, grace_ms, reaped, status, sink);
      send_message(p.control, kDone, status);
      _exit(0);
    }
  }
}

// ---- the parent's side -----------------------------------------------------------------------

// Receives one message (and a descriptor, when one came with it) within `timeout`.
bool receive(int control, Message& m, int* fd, std::chrono::milliseconds timeout) {
  pollfd pfd{control, POLLIN, 0};
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        until - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    const int r = ::poll(&pfd, 1, static_cast<int>(left.count()));
    if (r > 0) break;
    if (r < 0 && errno != EINTR) return false;
  }
  char buf[1 + 2 * sizeof(int)] = {};
  FdMessage fm(buf, sizeof buf);
  msghdr& msg = fm.msg;
  const ssize_t n = ::recvmsg(control, &msg, MSG_CMSG_CLOEXEC);
  if (n <= 0) return false;
  m.kind = buf[0];
  if (n >= static_cast<ssize_t>(sizeof buf)) {
    std::memcpy(&m.a, buf + 1, sizeof(int));
    std::memcpy(&m.b, buf + 1 + sizeof(int), sizeof(int));
  }
  for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c; c = CMSG_NXTHDR(&msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_RIGHTS) {
      int got = -1;
      std::memcpy(&got, CMSG_DATA(c), sizeof got);
      if (fd)
        *fd = got;
      else
        ::close(got);
    }
  }
  return true;
}

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

std::string step_text(int step, int err) {
  std::string what;
  switch (step) {
    case kStepUnshare:
      what = "cannot make a network namespace for the planner";
      break;
    case kStepSetgroups:
    case kStepUidMap:
    case kStepGidMap:
      what = "cannot map the user into the planner's user namespace";
      break;
    case kStepLoopback:
      what = "cannot bring up the loopback of the planner's network namespace";
      break;
    case kStepFork:
      what = "cannot start the planner program";
      break;
    default:
      what = "cannot start the planner program";
  }
  return what + " (" + std::strerror(err) + ")";
}

std::string namespace_advice(int err) {
  return std::string(
             "a network namespace of its own for each planner program needs unprivileged "
             "user namespaces, or root (unshare: ") +
         std::strerror(err) +
         "). Allow them (sysctl user.max_user_namespaces=15000; on Debian before 11 "
         "kernel.unprivileged_userns_clone=1; on Ubuntu 24.04 "
         "kernel.apparmor_restrict_unprivileged_userns=0), run as root, or use "
         "--planner-network host (one run at a time)";
}

}  // namespace

std::optional<PlannerNetwork> parse_planner_network(std::string_view text) {
  if (text == "auto") return PlannerNetwork::automatic;
  if (text == "isolated") return PlannerNetwork::isolated;
  if (text == "host") return PlannerNetwork::host;
  return std::nullopt;
}

PlannerProcess::PlannerProcess(const PlannerProcessOptions& o) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!o.cwd.empty() && !fs::is_directory(o.cwd, ec)) {
    throw std::runtime_error("the planner's working directory " + o.cwd.string() +
                             " does not exist");
  }
  if (o.log.has_parent_path()) fs::create_directories(o.log.parent_path(), ec);
  const int log = ::open(o.log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log < 0) {
    throw std::runtime_error(o.log.string() + ": cannot write the planner's log (" +
                             std::strerror(errno) + ")");
  }
  const int devnull = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  int sv[2] = {-1, -1};
  if (devnull < 0 || ::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv) != 0) {
    const int err = errno;
    ::close(log);
    if (devnull >= 0) ::close(devnull);
    throw std::runtime_error(std::string("cannot prepare the planner's process (") +
                             std::strerror(err) + ")");
  }
  // Everything the keeper needs, made before the fork.
  const std::string uid_map = "0 " + std::to_string(::geteuid()) + " 1\n";
  const std::string gid_map = "0 " + std::to_string(::getegid()) + " 1\n";
  const std::string cwd = o.cwd.string();
  std::string sh = "sh", dash_c = "-c", command = o.command;
  std::vector<char*> argv{sh.data(), dash_c.data(), command.data(), nullptr};
  KeeperPlan plan;
  plan.control = sv[1];
  plan.log = log;
  plan.log_max_bytes = o.log_max_bytes;
  plan.devnull = devnull;
  plan.parent = ::getpid();
  plan.isolated = o.isolated;
  plan.as_root = ::geteuid() == 0;
  plan.uid_map = uid_map.c_str();
  plan.gid_map = gid_map.c_str();
  plan.cwd = cwd.empty() ? nullptr : cwd.c_str();
  plan.argv = argv.data();

  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(sv[0]);
    keeper_main(plan);
  }
  const int fork_errno = errno;
  ::close(sv[1]);
  ::close(log);
  ::close(devnull);
  if (pid < 0) {
    ::close(sv[0]);
    throw std::runtime_error(std::string("cannot start the planner program (fork: ") +
                             std::strerror(fork_errno) + ")");
  }
  keeper_ = pid;
  control_ = sv[0];
  Message m;
  if (!receive(control_, m, nullptr, kAnswerTimeout) || m.kind != kStarted) {
    const std::string why =
        m.kind == kFailed ? (m.a == kStepUnshare ? namespace_advice(m.b) : step_text(m.a, m.b))
                          : "the planner's keeper process did not start";
    stop(0.0);
    throw std::runtime_error(why);
  }
}

PlannerProcess::~PlannerProcess() {
  stop();
}

bool PlannerProcess::request(char what, std::string* text, int* fd) {
  if (control_ < 0) return false;
  if (::send(control_, &what, 1, MSG_NOSIGNAL) != 1) return false;
  Message m;
  if (!receive(control_, m, fd, kAnswerTimeout)) return false;
  if (text && m.kind == kExited) *text = status_text(m.a);
  return m.kind != kNone;
}

int PlannerProcess::open_socket() {
  int fd = -1;
  if (!request(kSocket, nullptr, &fd)) return -1;
  return fd;
}

std::string PlannerProcess::ended() {
  if (!ended_.empty() || control_ < 0) return ended_;
  std::string text;
  if (!request(kStatus, &text, nullptr)) return "is gone (its keeper process ended)";
  ended_ = text;
  return ended_;
}

void PlannerProcess::stop(double grace_s) {
  if (keeper_ < 0) return;
  if (control_ >= 0) {
    char buf[1 + sizeof(int)];
    buf[0] = kStop;
    const int grace_ms = static_cast<int>(grace_s * 1000.0);
    std::memcpy(buf + 1, &grace_ms, sizeof grace_ms);
    if (::send(control_, buf, sizeof buf, MSG_NOSIGNAL) == static_cast<ssize_t>(sizeof buf)) {
      Message m;
      if (receive(control_, m, nullptr,
                  std::chrono::milliseconds(static_cast<int>(grace_s * 1000.0) + 5000)) &&
          m.kind == kDone && ended_.empty()) {
        ended_ = status_text(m.a);
      }
    }
    ::close(control_);
    control_ = -1;
  }
  // The keeper exits after stopping the program; make sure, then reap it.
  int status = 0;
  for (int i = 0; i < 100; ++i) {
    if (::waitpid(keeper_, &status, WNOHANG) == keeper_) {
      keeper_ = -1;
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(keeper_, SIGKILL);
  ::waitpid(keeper_, &status, 0);
  keeper_ = -1;
}

bool private_network_available(std::string* why) {
  struct Answer {
    bool ok = false;
    std::string why;
  };
  static const Answer answer = [] {
    Answer a;
    int pipefd[2];
    if (::pipe2(pipefd, O_CLOEXEC) != 0) {
      a.why = "cannot test for namespaces (pipe)";
      return a;
    }
    const bool root = ::geteuid() == 0;
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::close(pipefd[0]);
      int err = 0;
      if (::unshare(root ? CLONE_NEWNET : CLONE_NEWUSER | CLONE_NEWNET) != 0) err = errno;
      (void)::write(pipefd[1], &err, sizeof err);
      _exit(0);
    }
    ::close(pipefd[1]);
    int err = ECHILD;
    if (pid > 0) {
      if (::read(pipefd[0], &err, sizeof err) != static_cast<ssize_t>(sizeof err)) err = ECHILD;
      int status = 0;
      ::waitpid(pid, &status, 0);
    }
    ::close(pipefd[0]);
    a.ok = err == 0;
    if (!a.ok) a.why = namespace_advice(err);
    return a;
  }();
  if (why) *why = answer.why;
  return answer.ok;
}

}  // namespace overtake::app
