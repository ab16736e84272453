// init: the program's parent (see init.hpp). Forked from the keeper, it never execs overtake's
// code and uses only async-signal-safe calls (system calls on buffers prepared before the
// fork): no allocation, no stdio, no locks.

#include "init.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstring>

#include "async_safe.hpp"

namespace overtake::sandbox {
namespace {

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

// What init knows of the program.
struct Watch {
  pid_t program = -1;
  bool done = false;  // reaped
  int status = 0;     // its wait status, once done
};

// Reaps what has ended; true when the program is among it (its status in `w`).
bool reap(Watch& w) {
  bool now = false;
  int st = 0;
  for (;;) {
    const pid_t pid = ::waitpid(-1, &st, WNOHANG);
    if (pid <= 0) break;
    if (pid == w.program && !w.done) {
      w.done = true;
      w.status = st;
      now = true;
    }
  }
  return now;
}

// SIGTERM to everything, then up to `grace_ms` for the program to end.
void terminate(const InitPlan& p, Watch& w, int grace_ms) {
  signal_all(p, w.program, w.done, SIGTERM);
  const double until = now_ms() + grace_ms;
  while (!w.done && now_ms() < until) {
    reap(w);
    if (!w.done) sleep_ms(5);
  }
}

// What is left: killed, one generation at a time for a subreaper (a killed process's
// children become init's), at once by the kernel for a PID namespace when init exits.
void kill_the_rest(const InitPlan& p, Watch& w) {
  const double until = now_ms() + 3000.0;
  for (;;) {
    signal_all(p, w.program, w.done, SIGKILL);
    reap(w);
    siginfo_t info{};
    if (::waitid(P_ALL, 0, &info, WEXITED | WNOHANG | WNOWAIT) < 0 && errno == ECHILD) break;
    if (p.pid_namespace && w.done) break;
    if (now_ms() > until) break;
    sleep_ms(2);
  }
}

// Stops everything (SIGTERM and a grace first when `grace_ms` > 0), tells the keeper how the
// program ended if it had not yet, and exits.
[[noreturn]] void finish(const InitPlan& p, Watch& w, int grace_ms) {
  const bool was_done = w.done;
  if (grace_ms > 0) terminate(p, w, grace_ms);
  kill_the_rest(p, w);
  if (!was_done && w.done) (void)::write(p.status, &w.status, sizeof w.status);
  _exit(0);
}

// The program's process, between fork and exec: its own group, dying with init, standard
// input /dev/null, output and error the pipe to the keeper, no other descriptor.
[[noreturn]] void exec_program(const InitPlan& p) {
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

// How init holds the program's processes together.
void hold_together(const InitPlan& p) {
  if (p.pid_namespace) {
    // PID 1: when it goes, the kernel ends the namespace. Going with the keeper is enough.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  } else {
    // No namespace: orphans of the program become this process's children, so that it can
    // find and end them. It must outlive the keeper to do so, hence the lifeline pipe.
    ::prctl(PR_SET_CHILD_SUBREAPER, 1);
  }
}

// Reaps (telling the keeper the program's status when it ends) until the lifeline says stop:
// a grace, or EOF when the keeper is gone (overtake was killed): stop at once.
[[noreturn]] void watch(const InitPlan& p, Watch& w) {
  for (;;) {
    if (reap(w)) (void)::write(p.status, &w.status, sizeof w.status);
    pollfd pfd{p.lifeline, POLLIN, 0};
    if (::poll(&pfd, 1, 20) <= 0) continue;
    int grace_ms = 0;
    const ssize_t n = ::read(p.lifeline, &grace_ms, sizeof grace_ms);
    if (n < 0 && errno == EINTR) continue;
    finish(p, w, n == static_cast<ssize_t>(sizeof grace_ms) ? grace_ms : 0);
  }
}

}  // namespace

void init_main(const InitPlan& p) {
  hold_together(p);
  const pid_t program = ::fork();
  if (program == 0) exec_program(p);
  if (program < 0) _exit(1);    // the keeper reports it: init ended without a status
  ::setpgid(program, program);  // also here: whichever runs first
  ::close(p.out);
  ::close(p.devnull);
  Watch w;
  w.program = program;
  watch(p, w);
}

}  // namespace overtake::sandbox
