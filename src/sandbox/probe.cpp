// What the machine allows: the namespace steps a keeper takes, one function each, and the
// probe that goes through them once, in a child, to find out. The steps run in forked
// children (the keeper, the probe's): async-signal-safe only, on buffers made before the fork.

#include "probe.hpp"

#include <fcntl.h>
#include <net/if.h>
#include <sched.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "overtake/sandbox/planner_process.hpp"

namespace overtake::sandbox {
namespace {

// ---- the steps (async-signal-safe) --------------------------------------------------------------

bool write_all(const char* path, const char* text) {
  const int fd = ::open(path, O_WRONLY | O_CLOEXEC);
  if (fd < 0) return false;
  const std::size_t n = std::strlen(text);
  const bool ok = ::write(fd, text, n) == static_cast<ssize_t>(n);
  ::close(fd);
  return ok;
}

// New PID namespace; a network one when `isolated`; a user one when not root.
bool unshare_namespaces(bool isolated, bool as_root) {
  int flags = CLONE_NEWPID;
  if (isolated) flags |= CLONE_NEWNET;
  if (!as_root) flags |= CLONE_NEWUSER;
  return ::unshare(flags) == 0;
}

// Required before an unprivileged gid_map can be written.
bool deny_setgroups() {
  return write_all("/proc/self/setgroups", "deny");
}

bool map_uid(const char* uid_map) {
  return write_all("/proc/self/uid_map", uid_map);
}

bool map_gid(const char* gid_map) {
  return write_all("/proc/self/gid_map", gid_map);
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

// ---- the probe ----------------------------------------------------------------------------------

struct Probe {
  bool ok = false;
  std::string why;
};

// In the probe's child, in the new namespaces: forks the first process of the new PID
// namespace, which checks that it is PID 1. Returns 0, or the errno of what failed.
int check_first_process() {
  const pid_t one = ::fork();
  if (one == 0) _exit(::getpid() == 1 ? 0 : 1);
  int st = 0;
  if (one < 0 || ::waitpid(one, &st, 0) != one || !WIFEXITED(st) || WEXITSTATUS(st) != 0) {
    return one < 0 ? errno : EPERM;
  }
  return 0;
}

// The probe's child: every step a keeper takes; (step, errno) or (0, 0) to `answer_fd`.
[[noreturn]] void probe_child(int answer_fd, bool root, const char* uid_map, const char* gid_map) {
  int answer[2] = {0, 0};
  const int step = enter_namespaces(true, root, uid_map, gid_map);
  if (step != 0) {
    answer[0] = step;
    answer[1] = errno;
  } else if (const int err = check_first_process(); err != 0) {
    answer[0] = kStepFork;
    answer[1] = err;
  }
  (void)::write(answer_fd, answer, sizeof answer);
  _exit(0);
}

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
    probe_child(pipefd[1], root, uid_map, gid_map);
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

int enter_namespaces(bool isolated, bool as_root, const char* uid_map, const char* gid_map) {
  if (!unshare_namespaces(isolated, as_root)) return kStepUnshare;
  if (!as_root) {
    if (!deny_setgroups()) return kStepSetgroups;
    if (!map_uid(uid_map)) return kStepUidMap;
    if (!map_gid(gid_map)) return kStepGidMap;
  }
  if (isolated && !loopback_up()) return kStepLoopback;
  return 0;
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

bool private_network_available(std::string* why) {
  static const Probe answer = probe_namespaces();
  if (why) *why = answer.why;
  return answer.ok;
}

NetworkCheck check_planner_network(PlannerNetwork network) {
  NetworkCheck check;
  if (network == PlannerNetwork::host) return check;
  const bool available = private_network_available(&check.why);
  check.namespaces = available;
  check.own_network = available;
  check.refused = network == PlannerNetwork::isolated && !available;
  return check;
}

}  // namespace overtake::sandbox
