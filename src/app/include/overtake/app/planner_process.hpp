#pragma once
// A planner program run by overtake: started with `sh -c`, its standard output and error in a
// log file, optionally in a network namespace of its own (Linux user and network namespaces),
// and stopped, with everything it started, when the run is over.
//
// How it is put together: a small keeper process is forked; it enters the new namespaces
// (when asked), brings up their loopback, starts the program as its own child in a process
// group of its own, and then serves the parent over a Unix socket pair: it makes TCP sockets
// inside the namespace (the parent connects them: a socket stays in the namespace it was made
// in), writes the program's output to the log up to its size limit, tells whether the program
// still runs, and stops it. The keeper dies with the parent
// (PR_SET_PDEATHSIG), and the program with the keeper, so a killed bench leaves nothing.

#include <sys/types.h>

#include <filesystem>
#include <optional>
#include <string>

namespace overtake::app {

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
  bool isolated = true;  ///< in user + network namespaces of its own
};

/// A running planner program. Not copyable; the destructor stops it.
class PlannerProcess {
 public:
  /// Starts the program. Throws std::runtime_error naming what failed (the log file cannot be
  /// written, the namespaces cannot be made, the working directory is missing).
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
  /// Stops the program and everything in its process group: SIGTERM, then SIGKILL after
  /// `grace_s`. Idempotent.
  void stop(double grace_s = 1.0);

 private:
  bool request(char what, std::string* text, int* fd);
  pid_t keeper_ = -1;
  int control_ = -1;
  std::string ended_;
};

/// Whether this machine lets a process make user and network namespaces of its own (or, as
/// root, a network namespace); when not, `why` says what is missing and how to allow it.
/// Checked once (a forked child tries), then remembered.
[[nodiscard]] bool private_network_available(std::string* why = nullptr);

}  // namespace overtake::app
