#pragma once
// A planner program run by overtake: started with `sh -c`, its standard output and error in a
// log file, in namespaces of its own where the machine allows them, and stopped, with
// everything it started, when the run is over.
//
// How it is put together (three processes, none of which runs overtake's code after exec):
//
//   overtake ── keeper ── init ── sh -c CMD ── whatever the program starts
//
// - The keeper is forked from overtake. It closes every descriptor it does not need, enters
//   new user (when not root), network (when isolated) and PID namespaces, maps the user to
//   itself and brings up the loopback, then serves overtake over a Unix socket pair: it makes
//   TCP sockets inside the network namespace (overtake connects them: a socket stays in the
//   namespace it was made in), writes the program's output to the log up to its size limit,
//   says whether the program still runs, and stops it. Every answer carries the number of
//   the request it answers.
// - init is the first process of the new PID namespace (PID 1). It starts the program and
//   reaps whatever ends in the namespace. When it goes, the kernel kills every process left
//   in the namespace, daemons included: nothing the program starts outlives the run.
//   Where namespaces cannot be had, init is instead a child subreaper: the orphans of the
//   program become its children, and it kills them one generation at a time.
// - The program gets only standard input (/dev/null), output and error (a pipe to the
//   keeper): no descriptor of overtake (a bench's results file, say) reaches it.
//
// Lifelines: the keeper dies with overtake (PR_SET_PDEATHSIG) and init with the keeper (a
// pipe whose only writer is the keeper; in a PID namespace also PR_SET_PDEATHSIG), so a bench
// killed with SIGKILL still leaves nothing behind.

#include <sys/types.h>

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace overtake::sandbox {

/// Whether a planner program gets a network of its own.
enum class PlannerNetwork {
  automatic,  ///< its own where the machine allows it, else the host's (one run at a time)
  isolated,   ///< its own, or fail saying what is missing
  host,       ///< the host's network (one such run at a time per port)
};

/// Parses auto | isolated | host.
[[nodiscard]] std::optional<PlannerNetwork> parse_planner_network(std::string_view text);

/// What to start.
struct PlannerProcessOptions {
  std::string command;        ///< run by /bin/sh -c
  std::filesystem::path cwd;  ///< empty: the current directory
  std::filesystem::path log;  ///< standard output and error (created or truncated)
  /// The log is cut at this size (a line says so); the rest of the output is dropped.
  long long log_max_bytes = 64LL << 20;
  bool isolated = true;  ///< in a network namespace of its own
  /// Held together by a PID namespace where the machine allows one; false: by a subreaper,
  /// as on a machine without namespaces (host networks only).
  bool namespaces = true;
};

/// How a planner program's processes are held together.
enum class Containment {
  pid_namespace,  ///< a PID namespace of its own: everything in it ends with the run
  subreaper,      ///< no namespaces: a child subreaper kills what the program started
};

/// A running planner program. Not copyable; the destructor stops it.
class PlannerProcess {
 public:
  /// Starts the program. Throws std::runtime_error naming what failed (the log file cannot be
  /// written, the namespaces cannot be made, the working directory is missing, the keeper did
  /// not start in time).
  explicit PlannerProcess(const PlannerProcessOptions& options);
  ~PlannerProcess();
  PlannerProcess(const PlannerProcess&) = delete;
  PlannerProcess& operator=(const PlannerProcess&) = delete;

  /// A new TCP socket (IPv4, not connected) in the program's network; -1 when none can be
  /// made (the keeper is gone). The caller owns it.
  [[nodiscard]] int open_socket();
  /// "" while the program runs; else how it ended ("exited with status 1", "was killed by
  /// signal 11 (Segmentation fault)").
  [[nodiscard]] std::string ended();
  /// Stops the program and everything it started: SIGTERM, then SIGKILL after `grace_s`.
  /// Idempotent.
  void stop(double grace_s = 1.0);
  [[nodiscard]] Containment containment() const { return containment_; }

 private:
  bool request(char what, int arg, std::string* text, int* fd);
  void kill_keeper();
  pid_t keeper_ = -1;
  int keeper_fd_ = -1;  ///< a pidfd of the keeper (-1 where the kernel has none)
  int control_ = -1;
  unsigned sequence_ = 0;
  std::string ended_;
  Containment containment_ = Containment::subreaper;
};

/// Whether this machine lets a process make the namespaces a contained planner program needs
/// (user, network and PID namespaces, the user mapped, the loopback up; as root, network and
/// PID namespaces); when not, `why` says what is missing and how to allow it. Checked once,
/// by a forked child that goes through every step, then remembered.
[[nodiscard]] bool private_network_available(std::string* why = nullptr);

/// What a planner program that asks for a network gets (check_planner_network).
struct NetworkCheck {
  /// The machine allows the user, PID and network namespaces (probed unless host).
  bool namespaces = false;
  bool own_network = false;  ///< the planner gets a network of its own
  bool refused = false;      ///< isolated was asked for and the machine does not allow it
  std::string why;           ///< when the machine was probed and does not allow it: what is missing
};

/// The namespace check, the one every caller makes: host gets the host's network (the machine
/// is not probed); automatic a network of its own where private_network_available(), else the
/// host's; isolated its own, or a refusal saying why.
[[nodiscard]] NetworkCheck check_planner_network(PlannerNetwork network);

}  // namespace overtake::sandbox
