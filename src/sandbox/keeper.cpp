// The keeper (see keeper.hpp and planner_process.hpp). Forked from a process that may run
// many threads (a bench), it never execs and uses only async-signal-safe calls (system calls
// on buffers prepared before the fork): no allocation, no stdio, no locks.

#include "keeper.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <csignal>

#include "async_safe.hpp"
#include "init.hpp"
#include "probe.hpp"
#include "wire.hpp"

namespace overtake::sandbox {
namespace {

// ---- what the keeper holds ----------------------------------------------------------------------

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

// The keeper once init runs.
struct Keeper {
  int control = -1;
  int lifeline = -1;  // write end: a grace (ms) to stop; closed, it tells init to stop at once
  LogSink sink;
  ProgramState ps;
};

// The three pipes between the keeper and init.
struct InitPipes {
  int out[2] = {-1, -1};   // the program's output, to the keeper
  int life[2] = {-1, -1};  // the lifeline, to init
  int stat[2] = {-1, -1};  // the program's wait status, to the keeper
};

// ---- the start ----------------------------------------------------------------------------------

// Ties the keeper to overtake (it dies with it) and out of the terminal's reach.
void bind_to_parent(pid_t parent) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) _exit(1);  // the parent is already gone
  ::setpgid(0, 0);                      // Ctrl-C at the terminal is the parent's to handle
}

// Every signal unblocked and to its default, but SIGINT (Ctrl-C at the terminal) and SIGPIPE
// (overtake gone), which are ignored.
void reset_signals() {
  sigset_t none;
  sigemptyset(&none);
  sigprocmask(SIG_SETMASK, &none, nullptr);
  struct sigaction dfl {};
  dfl.sa_handler = SIG_DFL;
  for (int sig = 1; sig < NSIG; ++sig) {
    if (sig != SIGKILL && sig != SIGSTOP) sigaction(sig, &dfl, nullptr);
  }
  ::signal(SIGINT, SIG_IGN);
  ::signal(SIGPIPE, SIG_IGN);
}

// Nothing of overtake's but what the keeper needs (not a bench's open results file): what
// it keeps moves above the standard three, which become /dev/null, and the rest is closed.
// Every descriptor made from here on is then above 2, as init's dup2 calls need.
void keep_own_descriptors(KeeperPlan& p) {
  for (int* fd : {&p.control, &p.log, &p.devnull}) {
    const int moved = ::fcntl(*fd, F_DUPFD_CLOEXEC, 10);
    if (moved >= 0) *fd = moved;
  }
  for (int std_fd = 0; std_fd < 3; ++std_fd) ::dup2(p.devnull, std_fd);
  const int keep[] = {p.control, p.log, p.devnull};
  close_all_but(3, keep, 3);
}

// Waits for the go (overtake holds a pidfd of this process from then on); its sequence.
unsigned wait_for_go(int control) {
  wire::Message go;
  if (wire::receive_request(control, go) <= 0 || go.kind != wire::kGo) _exit(1);
  return go.sequence;
}

// Answers the go with the step that failed (and errno), and exits.
[[noreturn]] void fail(int control, unsigned go, int step) {
  wire::send_answer(control, wire::kFailed, go, step, errno);
  _exit(1);
}

// In init's process, between the fork and init_main: only init's ends of the pipes.
[[noreturn]] void become_init(const KeeperPlan& p, const InitPipes& pipes) {
  ::close(pipes.life[1]);
  ::close(pipes.stat[0]);
  ::close(pipes.out[0]);
  ::close(p.control);
  ::close(p.log);
  InitPlan ip;
  ip.pid_namespace = p.namespaces;
  ip.lifeline = pipes.life[0];
  ip.status = pipes.stat[1];
  ip.out = pipes.out[1];
  ip.devnull = p.devnull;
  ip.cwd = p.cwd;
  ip.argv = p.argv;
  init_main(ip);
}

// Forks init (failing the go when it cannot); the keeper keeps its own ends of the pipes.
Keeper fork_init(const KeeperPlan& p, unsigned go) {
  InitPipes pipes;
  if (::pipe2(pipes.out, O_CLOEXEC) != 0 || ::pipe2(pipes.life, O_CLOEXEC) != 0 ||
      ::pipe2(pipes.stat, O_CLOEXEC) != 0) {
    fail(p.control, go, kStepFork);
  }
  const pid_t init = ::fork();
  if (init < 0) fail(p.control, go, kStepFork);
  if (init == 0) become_init(p, pipes);
  ::close(pipes.out[1]);
  ::close(pipes.life[0]);
  ::close(pipes.stat[1]);
  ::close(p.devnull);
  ::fcntl(pipes.out[0], F_SETFL, ::fcntl(pipes.out[0], F_GETFL) | O_NONBLOCK);
  ::fcntl(pipes.stat[0], F_SETFL, ::fcntl(pipes.stat[0], F_GETFL) | O_NONBLOCK);
  Keeper k;
  k.control = p.control;
  k.lifeline = pipes.life[1];
  k.sink = LogSink{pipes.out[0], p.log, p.log_max_bytes, false};
  k.ps.status_pipe = pipes.stat[0];
  k.ps.init = init;
  return k;
}

// ---- the requests -------------------------------------------------------------------------------

// kSocket: a TCP socket made in the keeper's network namespace, or kNone (with errno).
void answer_socket(const Keeper& k, unsigned seq) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    wire::send_answer(k.control, wire::kNone, seq, errno);
  } else {
    wire::send_fd(k.control, seq, fd);
    ::close(fd);
  }
}

// kStatus: kExited with the program's wait status, kRunning, or kGone when init ended
// without telling.
void answer_status(Keeper& k, unsigned seq) {
  ProgramState& ps = k.ps;
  ps.poll_status();
  if (ps.known) {
    wire::send_answer(k.control, wire::kExited, seq, ps.status);
  } else if (ps.init_gone()) {
    ps.poll_status();
    wire::send_answer(k.control, ps.known ? wire::kExited : wire::kGone, seq, ps.status);
  } else {
    wire::send_answer(k.control, wire::kRunning, seq);
  }
}

// kStop (and overtake gone: `answer` false): tells init to stop with `grace_ms`, waits for it
// (still writing the program's output to the log), kills it if it does not end, answers
// kDone (known, status), and exits.
[[noreturn]] void stop_and_exit(Keeper& k, int grace_ms, unsigned sequence, bool answer) {
  ProgramState& ps = k.ps;
  (void)::write(k.lifeline, &grace_ms, sizeof grace_ms);
  ::close(k.lifeline);
  const double until = now_ms() + grace_ms + 4000.0;
  while (!ps.init_gone() && now_ms() < until) {
    drain(k.sink);
    sleep_ms(5);
  }
  if (!ps.init_gone()) {
    ::kill(ps.init, SIGKILL);  // not reaped yet: the pid is still init's
    ::waitpid(ps.init, nullptr, 0);
    ps.init_reaped = true;
  }
  ps.poll_status();
  drain(k.sink);  // what it wrote last
  if (answer) wire::send_answer(k.control, wire::kDone, sequence, ps.known ? 1 : 0, ps.status);
  _exit(0);
}

// ---- the service loop ---------------------------------------------------------------------------

// Waits (50 ms at most) for a request, writing the program's output to the log meanwhile;
// whether one may be there.
bool wait_for_request(Keeper& k) {
  pollfd pfd[2] = {{k.control, POLLIN, 0}, {k.sink.pipe, POLLIN, 0}};
  const int r = ::poll(pfd, k.sink.pipe >= 0 ? 2 : 1, 50);
  if (r <= 0) return false;
  if (k.sink.pipe >= 0 && (pfd[1].revents & (POLLIN | POLLHUP | POLLERR)) != 0) drain(k.sink);
  return (pfd[0].revents & (POLLIN | POLLHUP | POLLERR)) != 0;
}

// Receives one request and answers it.
void serve_request(Keeper& k) {
  wire::Message req;
  const ssize_t n = wire::receive_request(k.control, req);
  if (n <= 0) {  // the parent closed its end (or is gone): stop at once
    stop_and_exit(k, 0, 0, false);
  }
  if (n < static_cast<ssize_t>(wire::kRequestSize)) return;
  if (req.kind == wire::kSocket) {
    answer_socket(k, req.sequence);
  } else if (req.kind == wire::kStatus) {
    answer_status(k, req.sequence);
  } else if (req.kind == wire::kStop) {
    stop_and_exit(k, std::max(0, req.a), req.sequence, true);
  }
}

}  // namespace

void keeper_main(KeeperPlan p) {
  bind_to_parent(p.parent);
  reset_signals();
  keep_own_descriptors(p);
  const unsigned go = wait_for_go(p.control);
  if (p.namespaces) {
    const int step = enter_namespaces(p.isolated, p.as_root, p.uid_map, p.gid_map);
    if (step != 0) fail(p.control, go, step);
  }
  Keeper k = fork_init(p, go);
  wire::send_answer(k.control, wire::kStarted, go);
  for (;;) {
    if (wait_for_request(k)) serve_request(k);
  }
}

}  // namespace overtake::sandbox
