// Planner programs in processes (and namespaces) of their own. The keeper and init, forked
// from a process that may run many threads (a bench), never exec and use only
// async-signal-safe calls (system calls on buffers prepared before the fork): no allocation,
// no stdio, no locks.

#include "overtake/app/planner_process.hpp"

#include <fcntl.h>
#include <net/if.h>
#include <poll.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/pidfd.h>
#include <sys/prctl.h>
#include <sys/resource.h>
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

namespace overtake::app {
namespace {

// Requests to the keeper: kind, sequence number, argument.
constexpr char kSocket = 'S';  // -> kFd with the descriptor, or kNone
constexpr char kStatus = 'W';  // -> kRunning, kExited with the wait status, or kGone
constexpr char kStop = 'K';    // (argument: grace in ms) -> kDone, then the keeper exits
constexpr char kGo = 'G';      // the first request: overtake holds a pidfd of the keeper now
// Answers: kind, the request's sequence number, two numbers.
constexpr char kStarted = 'O';  // to kGo: started
constexpr char kFailed = 'E';   // to kGo: failed (step, errno)
constexpr char kFd = 'F';
constexpr char kNone = 'N';
constexpr char kRunning = 'R';
constexpr char kExited = 'X';
constexpr char kGone = 'Z';  // init ended without telling how the program did
constexpr char kDone = 'D';  // (known, status)

constexpr std::size_t kRequestSize = 1 + 2 * sizeof(int);
constexpr std::size_t kAnswerSize = 1 + 3 * sizeof(int);

// Steps of the start that can fail, for the parent's message.
enum Step : int {
  kStepUnshare = 1,
  kStepSetgroups,
  kStepUidMap,
  kStepGidMap,
  kStepLoopback,
  kStepFork,
};

constexpr auto kAnswerTimeout = std::chrono::seconds(10);
// waitid's P_PIDFD (Linux 5.4), which glibc's idtype_t does not name.
constexpr auto kWaitPidfd = static_cast<idtype_t>(3);

struct Message {
  char kind = 0;
  unsigned sequence = 0;
  int a = 0;
  int b = 0;
};

// ---- shared by the keeper, init and the probe (async-signal-safe only) -----------------------

void put_int(char* at, int v) {
  std::memcpy(at, &v, sizeof v);
}
int get_int(const char* at) {
  int v = 0;
  std::memcpy(&v, at, sizeof v);
  return v;
}

void send_answer(int fd, char kind, unsigned sequence, int a = 0, int b = 0) {
  char buf[kAnswerSize];
  buf[0] = kind;
  put_int(buf + 1, static_cast<int>(sequence));
  put_int(buf + 1 + sizeof(int), a);
  put_int(buf + 1 + 2 * sizeof(int), b);
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

void send_fd(int control, unsigned sequence, int fd) {
  char buf[kAnswerSize] = {};
  buf[0] = kFd;
  put_int(buf + 1, static_cast<int>(sequence));
  FdMessage m(buf, sizeof buf);
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

void sleep_ms(int ms) {
  (void)::poll(nullptr, 0, ms);
}

// Closes every descriptor from `from` up, except those in keep[0..n) (n <= 8).
void close_all_but(int from, const int* keep, int n) {
  int sorted[8];
  int m = 0;
  for (int i = 0; i < n && m < 8; ++i) {
    if (keep[i] >= from) sorted[m++] = keep[i];
  }
  std::sort(sorted, sorted + m);
  bool ok = true;
  unsigned next = static_cast<unsigned>(from);
  for (int i = 0; i < m && ok; ++i) {
    const auto k = static_cast<unsigned>(sorted[i]);
    if (k > next) ok = ::syscall(SYS_close_range, next, k - 1, 0U) == 0;
    next = std::max(next, k + 1);
  }
  if (ok && ::syscall(SYS_close_range, next, ~0U, 0U) == 0) return;
  // Kernels before 5.9: one close per possible descriptor.
  rlimit lim{};
  const long top = ::getrlimit(RLIMIT_NOFILE, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY
                       ? std::min<long>(static_cast<long>(lim.rlim_cur), 1L << 20)
                       : 65536L;
  for (long fd = from; fd < top; ++fd) {
    if (std::find(keep, keep + n, static_cast<int>(fd)) == keep + n) ::close(static_cast<int>(fd));
  }
}

// "UID UID 1\n": the user mapped to itself (so that files, `id` and tools see the user, not
// root; the keeper keeps the capabilities the new namespace gives its maker, and loses them
// with the program's exec).
void self_map(char* out, std::size_t size, unsigned id) {
  char digits[16];
  int n = 0;
  do {
    digits[n++] = static_cast<char>('0' + id % 10);
    id /= 10;
  } while (id != 0 && n < 15);
  std::size_t k = 0;
  for (int rep = 0; rep < 2; ++rep) {
    for (int i = n - 1; i >= 0 && k + 1 < size; --i) out[k++] = digits[i];
    if (k + 1 < size) out[k++] = ' ';
  }
  for (const char c : {'1', '\n'}) {
    if (k + 1 < size) out[k++] = c;
  }
  out[k] = '\0';
}

// Enters the namespaces (`isolated`: a network one too) and makes them usable. Returns 0, or
// the step that failed (errno tells why).
int enter_namespaces(bool isolated, bool as_root, const char* uid_map, const char* gid_map) {
  int flags = CLONE_NEWPID;
  if (isolated) flags |= CLONE_NEWNET;
  if (!as_root) flags |= CLONE_NEWUSER;
  if (::unshare(flags) != 0) return kStepUnshare;
  if (!as_root) {
    if (!write_all("/proc/self/setgroups", "deny")) return kStepSetgroups;
    if (!write_all("/proc/self/uid_map", uid_map)) return kStepUidMap;
    if (!write_all("/proc/self/gid_map", gid_map)) return kStepGidMap;
  }
  if (isolated && !loopback_up()) return kStepLoopback;
  return 0;
}

// ---- init: the program's parent ---------------------------------------------------------------

struct InitPlan {
  bool pid_namespace = false;
  int lifeline = -1;  // read end: a grace (ms) to stop, or EOF when the keeper is gone
  int status = -1;    // write end: the program's wait status
  int out = -1;       // write end of the program's output pipe
  int devnull = -1;
  const char* cwd = nullptr;
  char* const* argv = nullptr;
};

// The pids of this process's children, from /proc (-1 when they cannot be read).
int read_children(pid_t self, pid_t* pids, int capacity) {
  char path[64] = "/proc/self/task/";
  std::size_t k = std::strlen(path);
  char digits[16];
  int n = 0;
  for (auto v = static_cast<unsigned>(self); n == 0 || v != 0; v /= 10)
    digits[n++] = static_cast<char>('0' + v % 10);
  while (n > 0) path[k++] = digits[--n];
  std::memcpy(path + k, "/children", 10);
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return -1;
  static char buf[8192];  // init is single-threaded
  const ssize_t got = ::read(fd, buf, sizeof buf - 1);
  ::close(fd);
  if (got < 0) return -1;
  int count = 0;
  long value = -1;
  for (ssize_t i = 0; i <= got && count < capacity; ++i) {
    const char c = i < got ? buf[i] : ' ';
    if (c >= '0' && c <= '9') {
      value = (value < 0 ? 0 : value * 10) + (c - '0');
    } else if (value >= 0) {
      pids[count++] = static_cast<pid_t>(value);
      value = -1;
    }
  }
  return count;
}

// Sends `sig` to everything init has started (and, as a subreaper, adopted).
void signal_all(const InitPlan& p, pid_t program, bool program_done, int sig) {
  if (p.pid_namespace) {
    ::kill(-1, sig);  // from PID 1: every other process of the namespace
    return;
  }
  // The program's group while its leader is not reaped (its id cannot be anyone else's
  // then); then each child not yet reaped, by pid (the same holds for them).
  if (!program_done) ::kill(-program, sig);
  pid_t kids[512];
  const int n = read_children(::getpid(), kids, 512);
  for (int i = 0; i < n; ++i) ::kill(kids[i], sig);
}

// Reaps what has ended; true when the program is among it (its status in `status`).
bool reap(pid_t program, bool& program_done, int& status) {
  bool now = false;
  int st = 0;
  for (;;) {
    const pid_t pid = ::waitpid(-1, &st, WNOHANG);
    if (pid <= 0) break;
    if (pid == program && !program_done) {
      program_done = true;
      status = st;
      now = true;
    }
  }
  return now;
}

[[noreturn]] void finish_init(const InitPlan& p, pid_t program, int grace_ms, bool& program_done,
                              int& status) {
  const auto tell = [&] {
    if (program_done) (void)::write(p.status, &status, sizeof status);
  };
  const bool was_done = program_done;
  if (grace_ms > 0) {
    signal_all(p, program, program_done, SIGTERM);
    const double until = now_ms() + grace_ms;
    while (!program_done && now_ms() < until) {
      reap(program, program_done, status);
      if (!program_done) sleep_ms(5);
    }
  }
  // What is left: killed, one generation at a time for a subreaper (a killed process's
  // children become init's), at once by the kernel for a PID namespace when init exits.
  const double until = now_ms() + 3000.0;
  for (;;) {
    signal_all(p, program, program_done, SIGKILL);
    reap(program, program_done, status);
    siginfo_t info{};
    if (::waitid(P_ALL, 0, &info, WEXITED | WNOHANG | WNOWAIT) < 0 && errno == ECHILD) break;
    if (p.pid_namespace && program_done) break;
    if (now_ms() > until) break;
    sleep_ms(2);
  }
  if (!was_done) tell();
  _exit(0);
}

[[noreturn]] void init_main(const InitPlan& p) {
  if (p.pid_namespace) {
    // PID 1: when it goes, the kernel ends the namespace. Going with the keeper is enough.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  } else {
    // No namespace: orphans of the program become this process's children, so that it can
    // find and end them. It must outlive the keeper to do so, hence the lifeline pipe.
    ::prctl(PR_SET_CHILD_SUBREAPER, 1);
  }
  const pid_t program = ::fork();
  if (program == 0) {
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    ::dup2(p.devnull, 0);
    ::dup2(p.out, 1);
    ::dup2(p.out, 2);
    close_all_but(3, nullptr, 0);  // only standard input, output and error reach the program
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
  if (program < 0) _exit(1);    // the keeper reports it: init ended without a status
  ::setpgid(program, program);  // also here: whichever runs first
  ::close(p.out);
  ::close(p.devnull);
  bool program_done = false;
  int status = 0;
  for (;;) {
    if (reap(program, program_done, status)) (void)::write(p.status, &status, sizeof status);
    pollfd pfd{p.lifeline, POLLIN, 0};
    if (::poll(&pfd, 1, 20) <= 0) continue;
    int grace_ms = 0;
    const ssize_t n = ::read(p.lifeline, &grace_ms, sizeof grace_ms);
    if (n < 0 && errno == EINTR) continue;
    // A grace: stop. EOF: the keeper is gone (overtake was killed): stop at once.
    finish_init(p, program, n == static_cast<ssize_t>(sizeof grace_ms) ? grace_ms : 0, program_done,
                status);
  }
}

// ---- the keeper --------------------------------------------------------------------------------

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

struct KeeperPlan {
  int control = -1;
  int log = -1;
  long long log_max_bytes = 0;
  int devnull = -1;
  pid_t parent = 0;
  bool isolated = false;
  bool namespaces = false;  // PID (and user) namespaces; else a subreaper init
  bool as_root = false;
  const char* uid_map = nullptr;
  const char* gid_map = nullptr;
  const char* cwd = nullptr;  // may be null
  char* const* argv = nullptr;
};

// What the keeper knows of the program, from init.
struct ProgramState {
  int status_pipe = -1;  // read end, non-blocking
  pid_t init = -1;
  bool init_reaped = false;
  bool known = false;  // the program's wait status came
  int status = 0;

  void poll_status() {
    if (known || status_pipe < 0) return;
    int st = 0;
    if (::read(status_pipe, &st, sizeof st) == static_cast<ssize_t>(sizeof st)) {
      known = true;
      status = st;
    }
  }
  // Whether init has ended (reaped here).
  bool init_gone() {
    if (!init_reaped && ::waitpid(init, nullptr, WNOHANG) == init) init_reaped = true;
    return init_reaped;
  }
};

[[noreturn]] void stop_and_exit(int lifeline, int grace_ms, ProgramState& ps, LogSink& sink,
                                int control, unsigned sequence, bool answer) {
  (void)::write(lifeline, &grace_ms, sizeof grace_ms);
  ::close(lifeline);
  const double until = now_ms() + grace_ms + 4000.0;
  while (!ps.init_gone() && now_ms() < until) {
    drain(sink);
    sleep_ms(5);
  }
  if (!ps.init_gone()) {
    ::kill(ps.init, SIGKILL);  // not reaped yet: the pid is still init's
    ::waitpid(ps.init, nullptr, 0);
    ps.init_reaped = true;
  }
  ps.poll_status();
  drain(sink);  // what it wrote last
  if (answer) send_answer(control, kDone, sequence, ps.known ? 1 : 0, ps.status);
  _exit(0);
}

[[noreturn]] void keeper_main(KeeperPlan p) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != p.parent) _exit(1);  // the parent is already gone
  ::setpgid(0, 0);                        // Ctrl-C at the terminal is the parent's to handle
  default_signals();
  ::signal(SIGINT, SIG_IGN);
  ::signal(SIGPIPE, SIG_IGN);
  // Nothing of overtake's but what the keeper needs (not a bench's open results file): what
  // it keeps moves above the standard three, which become /dev/null, and the rest is closed.
  // Every descriptor made from here on is then above 2, as init's dup2 calls need.
  for (int* fd : {&p.control, &p.log, &p.devnull}) {
    const int moved = ::fcntl(*fd, F_DUPFD_CLOEXEC, 10);
    if (moved >= 0) *fd = moved;
  }
  for (int std_fd = 0; std_fd < 3; ++std_fd) ::dup2(p.devnull, std_fd);
  const int keep[] = {p.control, p.log, p.devnull};
  close_all_but(3, keep, 3);

  // Wait for the go: overtake holds a pidfd of this process from then on.
  char req[kRequestSize];
  if (::recv(p.control, req, sizeof req, 0) <= 0 || req[0] != kGo) _exit(1);
  const auto go = static_cast<unsigned>(get_int(req + 1));
  const auto fail = [&](int step) {
    send_answer(p.control, kFailed, go, step, errno);
    _exit(1);
  };
  if (p.namespaces) {
    const int step = enter_namespaces(p.isolated, p.as_root, p.uid_map, p.gid_map);
    if (step != 0) fail(step);
  }
  int out[2] = {-1, -1}, life[2] = {-1, -1}, stat[2] = {-1, -1};
  if (::pipe2(out, O_CLOEXEC) != 0 || ::pipe2(life, O_CLOEXEC) != 0 ||
      ::pipe2(stat, O_CLOEXEC) != 0) {
    fail(kStepFork);
  }
  const pid_t init = ::fork();
  if (init < 0) fail(kStepFork);
  if (init == 0) {
    ::close(life[1]);
    ::close(stat[0]);
    ::close(out[0]);
    ::close(p.control);
    ::close(p.log);
    InitPlan ip;
    ip.pid_namespace = p.namespaces;
    ip.lifeline = life[0];
    ip.status = stat[1];
    ip.out = out[1];
    ip.devnull = p.devnull;
    ip.cwd = p.cwd;
    ip.argv = p.argv;
    init_main(ip);
  }
  ::close(out[1]);
  ::close(life[0]);
  ::close(stat[1]);
  ::close(p.devnull);
  ::fcntl(out[0], F_SETFL, ::fcntl(out[0], F_GETFL) | O_NONBLOCK);
  ::fcntl(stat[0], F_SETFL, ::fcntl(stat[0], F_GETFL) | O_NONBLOCK);
  LogSink sink{out[0], p.log, p.log_max_bytes, false};
  ProgramState ps;
  ps.status_pipe = stat[0];
  ps.init = init;
  send_answer(p.control, kStarted, go);

  for (;;) {
    pollfd pfd[2] = {{p.control, POLLIN, 0}, {sink.pipe, POLLIN, 0}};
    const int r = ::poll(pfd, sink.pipe >= 0 ? 2 : 1, 50);
    if (r <= 0) continue;
    if (sink.pipe >= 0 && (pfd[1].revents & (POLLIN | POLLHUP | POLLERR)) != 0) drain(sink);
    if ((pfd[0].revents & (POLLIN | POLLHUP | POLLERR)) == 0) continue;
    const ssize_t n = ::recv(p.control, req, sizeof req, 0);
    if (n <= 0) {  // the parent closed its end (or is gone): stop at once
      stop_and_exit(life[1], 0, ps, sink, p.control, 0, false);
    }
    if (n < static_cast<ssize_t>(kRequestSize)) continue;
    const auto seq = static_cast<unsigned>(get_int(req + 1));
    const int arg = get_int(req + 1 + sizeof(int));
    if (req[0] == kSocket) {
      const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
      if (fd < 0) {
        send_answer(p.control, kNone, seq, errno);
      } else {
        send_fd(p.control, seq, fd);
        ::close(fd);
      }
    } else if (req[0] == kStatus) {
      ps.poll_status();
      if (ps.known) {
        send_answer(p.control, kExited, seq, ps.status);
      } else if (ps.init_gone()) {
        ps.poll_status();
        send_answer(p.control, ps.known ? kExited : kGone, seq, ps.status);
      } else {
        send_answer(p.control, kRunning, seq);
      }
    } else if (req[0] == kStop) {
      stop_and_exit(life[1], std::max(0, arg), ps, sink, p.control, seq, true);
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
  char buf[kAnswerSize] = {};
  FdMessage fm(buf, sizeof buf);
  msghdr& msg = fm.msg;
  const ssize_t n = ::recvmsg(control, &msg, MSG_CMSG_CLOEXEC);
  if (n <= 0) return false;
  m.kind = buf[0];
  m.sequence = static_cast<unsigned>(get_int(buf + 1));
  m.a = get_int(buf + 1 + sizeof(int));
  m.b = get_int(buf + 1 + 2 * sizeof(int));
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

// Receives the answer to request `sequence`, dropping late answers to earlier ones (and the
// descriptors they carry).
bool receive_answer(int control, unsigned sequence, Message& m, int* fd,
                    std::chrono::milliseconds timeout) {
  const auto until = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        until - std::chrono::steady_clock::now());
    int got = -1;
    if (left.count() <= 0 || !receive(control, m, &got, left)) return false;
    if (m.sequence == sequence) {
      if (fd)
        *fd = got;
      else if (got >= 0)
        ::close(got);
      return true;
    }
    if (got >= 0) ::close(got);
  }
}

bool send_request(int control, char kind, unsigned sequence, int arg) {
  char buf[kRequestSize];
  buf[0] = kind;
  put_int(buf + 1, static_cast<int>(sequence));
  put_int(buf + 1 + sizeof(int), arg);
  return ::send(control, buf, sizeof buf, MSG_NOSIGNAL) == static_cast<ssize_t>(sizeof buf);
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
      what = "cannot make namespaces for the planner";
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

std::string namespace_advice(int step, int err) {
  if (step != kStepUnshare) {
    return step_text(step, err) +
           "; run as root, or use --planner-network host (one run at a time, on the host's "
           "network; what the program starts is still ended with the run)";
  }
  return std::string(
             "a network and a PID namespace of their own for each planner program need "
             "unprivileged user namespaces, or root (unshare: ") +
         std::strerror(err) +
         "). Allow them (sysctl user.max_user_namespaces=15000; on Debian before 11 "
         "kernel.unprivileged_userns_clone=1; on Ubuntu 24.04 "
         "kernel.apparmor_restrict_unprivileged_userns=0), run as root, or use "
         "--planner-network host (one run at a time)";
}

struct Probe {
  bool ok = false;
  std::string why;
};

// Goes through every step a keeper takes, in a child, with a PID 1 of its own.
Probe probe_namespaces() {
  Probe a;
  int pipefd[2];
  if (::pipe2(pipefd, O_CLOEXEC) != 0) {
    a.why = "cannot test for namespaces (pipe)";
    return a;
  }
  const bool root = ::geteuid() == 0;
  char uid_map[64], gid_map[64];
  self_map(uid_map, sizeof uid_map, ::geteuid());
  self_map(gid_map, sizeof gid_map, ::getegid());
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::close(pipefd[0]);
    int answer[2] = {0, 0};
    const int step = enter_namespaces(true, root, uid_map, gid_map);
    if (step != 0) {
      answer[0] = step;
      answer[1] = errno;
    } else {
      const pid_t one = ::fork();  // the first process of the new PID namespace
      if (one == 0) _exit(::getpid() == 1 ? 0 : 1);
      int st = 0;
      if (one < 0 || ::waitpid(one, &st, 0) != one || !WIFEXITED(st) || WEXITSTATUS(st) != 0) {
        answer[0] = kStepFork;
        answer[1] = one < 0 ? errno : EPERM;
      }
    }
    (void)::write(pipefd[1], answer, sizeof answer);
    _exit(0);
  }
  ::close(pipefd[1]);
  int answer[2] = {kStepFork, ECHILD};
  if (pid > 0) {
    if (::read(pipefd[0], answer, sizeof answer) != static_cast<ssize_t>(sizeof answer)) {
      answer[0] = kStepFork;
      answer[1] = ECHILD;
    }
    ::waitpid(pid, nullptr, 0);
  }
  ::close(pipefd[0]);
  a.ok = answer[0] == 0;
  if (!a.ok) a.why = namespace_advice(answer[0], answer[1]);
  return a;
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
  std::string why;
  const bool available = private_network_available(&why);
  if (o.isolated && !available) throw std::runtime_error(why);
  const bool namespaces = available && (o.namespaces || o.isolated);
  containment_ = namespaces ? Containment::pid_namespace : Containment::subreaper;
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
  char uid_map[64], gid_map[64];
  self_map(uid_map, sizeof uid_map, ::geteuid());
  self_map(gid_map, sizeof gid_map, ::getegid());
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
  plan.namespaces = namespaces;
  plan.as_root = ::geteuid() == 0;
  plan.uid_map = uid_map;
  plan.gid_map = gid_map;
  plan.cwd = cwd.empty() ? nullptr : cwd.c_str();
  plan.argv = argv.data();

  const pid_t pid = ::fork();
  if (pid == 0) keeper_main(plan);
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
  // The keeper waits for the go before it can end, so the pid is still its own here; from
  // now on it is signalled and waited for through the pidfd only (no reused pid is hit).
  keeper_fd_ = static_cast<int>(::syscall(SYS_pidfd_open, pid, 0));
  if (keeper_fd_ >= 0) (void)::fcntl(keeper_fd_, F_SETFD, FD_CLOEXEC);
  const unsigned go = ++sequence_;
  Message m;
  if (!send_request(control_, kGo, go, 0) ||
      !receive_answer(control_, go, m, nullptr, kAnswerTimeout) || m.kind != kStarted) {
    const std::string reason =
        m.kind == kFailed ? (m.a == kStepUnshare ? namespace_advice(m.a, m.b) : step_text(m.a, m.b))
                          : "the planner's keeper process did not start within " +
                                std::to_string(kAnswerTimeout.count()) + " s";
    stop(0.0);
    throw std::runtime_error(reason);
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
  Message m;
  if (!send_request(control_, what, seq, arg) ||
      !receive_answer(control_, seq, m, fd, kAnswerTimeout)) {
    // A keeper that does not answer is of no more use, and its answers could come late.
    if (ended_.empty()) ended_ = "is gone (its keeper process stopped answering)";
    kill_keeper();
    return false;
  }
  if (text && m.kind == kExited) *text = status_text(m.a);
  if (text && m.kind == kGone) *text = "is gone (its init process ended without a status)";
  return m.kind != kNone;
}

int PlannerProcess::open_socket() {
  int fd = -1;
  if (!request(kSocket, 0, nullptr, &fd)) return -1;
  return fd;
}

std::string PlannerProcess::ended() {
  if (!ended_.empty() || control_ < 0) return ended_;
  std::string text;
  if (!request(kStatus, 0, &text, nullptr)) return ended_.empty() ? "is gone" : ended_;
  ended_ = text;
  return ended_;
}

void PlannerProcess::stop(double grace_s) {
  if (keeper_ < 0) return;
  if (control_ >= 0) {
    const int grace_ms = static_cast<int>(std::clamp(grace_s, 0.0, 3600.0) * 1000.0);
    const unsigned seq = ++sequence_;
    Message m;
    if (send_request(control_, kStop, seq, grace_ms) &&
        receive_answer(control_, seq, m, nullptr, std::chrono::milliseconds(grace_ms + 6000)) &&
        m.kind == kDone && m.a == 1 && ended_.empty()) {
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

bool private_network_available(std::string* why) {
  static const Probe answer = probe_namespaces();
  if (why) *why = answer.why;
  return answer.ok;
}

}  // namespace overtake::app
