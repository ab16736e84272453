#include "overtake/planners/program_planner.hpp"

#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "overtake/base/errors.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/planners/external.hpp"
#include "overtake/protocol/client.hpp"
#include "overtake/sandbox/planner_process.hpp"

namespace overtake::planners {

using base::UsageError;
using sandbox::PlannerNetwork;
using sandbox::PlannerProcess;
using sandbox::PlannerProcessOptions;
namespace {

constexpr auto kPortFreeWait = std::chrono::seconds(3);
constexpr auto kEndedWait = std::chrono::milliseconds(500);

std::chrono::milliseconds ms_of(double seconds) {
  return std::chrono::milliseconds(std::max<long long>(1, std::llround(seconds * 1000.0)));
}

// Runs on the host's network take turns, one per port: two programs cannot both listen on
// it, and a run must not reach another run's planner. The lock is the process's, as the port
// is the machine's.
std::mutex& host_port_lock(int port) {
  static std::mutex guard;
  static std::map<int, std::mutex> locks;
  const std::lock_guard lock(guard);
  return locks[port];
}

// Whether something on this machine already accepts connections on 127.0.0.1:port.
bool port_taken(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return false;
  sockaddr_in to{};
  to.sin_family = AF_INET;
  to.sin_port = htons(static_cast<std::uint16_t>(port));
  to.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool taken = ::connect(fd, reinterpret_cast<const sockaddr*>(&to), sizeof to) == 0;
  ::close(fd);
  return taken;
}

// A run that ends before its first step, with `reason`: the report of a planner that failed
// at once (its run is still a row of the bench).
sim::RunReport failed_at_start(sim::World& world, const sim::RunOptions& run,
                               const std::string& reason) {
  return sim::run_drive(
      world,
      [&reason](const core::Telemetry&) -> core::PlanResult { throw sim::PlannerFailure(reason); },
      run);
}

// On the host's network: whether the port stays taken by another process. The program of the
// run before may still be going away (a killed process closes its sockets as it exits, a moment
// after the signal): a short wait before calling it taken.
bool host_port_stays_taken(int port) {
  const auto until = std::chrono::steady_clock::now() + kPortFreeWait;
  while (port_taken(port) && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  return port_taken(port);
}

// Why the program could not be reached, from the connection's error.
std::string connect_failure(const protocol::ConnectionError& e, const std::string& gave_up,
                            const ProgramSpec& spec, const protocol::ClientOptions& client) {
  std::string why = e.what();
  if (!gave_up.empty()) return gave_up;
  if (why.find(" within ") != std::string::npos) {
    const std::size_t last = why.rfind(": ");
    why = "the planner program did not listen on port " + std::to_string(spec.port) + " within " +
          protocol::seconds_text(client.connect_timeout) +
          (last == std::string::npos ? "" : " (the last attempt: " + why.substr(last + 2) + ")");
  }
  return why;
}

// A failed run's reason says how the program ended and where its output is. A program that
// crashed drops the connection as it dies: its keeper gets a moment to see it end.
void say_how_it_ended(sim::RunReport& report, PlannerProcess& process, const std::string& see_log) {
  if (report.outcome.end != sim::RunEnd::planner_failed ||
      report.outcome.reason.find(see_log) != std::string::npos)
    return;
  std::string ended = process.ended();
  const auto until = std::chrono::steady_clock::now() + kEndedWait;
  while (ended.empty() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
    ended = process.ended();
  }
  if (!ended.empty() && report.outcome.reason.find("the planner program") == std::string::npos)
    report.outcome.reason += "; the planner program " + ended;
  report.outcome.reason += see_log;
}

sim::RunReport run_program(const PlannerEntry& entry, const std::filesystem::path& log,
                           sim::World& world, const sim::RunOptions& run) {
  const ProgramSpec& spec = *entry.program;
  const bool isolated = program_isolated(entry);
  std::unique_lock<std::mutex> turn;
  if (!isolated) {
    turn = std::unique_lock(host_port_lock(spec.port));
    if (host_port_stays_taken(spec.port)) {
      return failed_at_start(
          world, run,
          "port " + std::to_string(spec.port) +
              " on this machine is already in use by another process, so the planner program "
              "cannot listen there (runs on the host's network need the port free)");
    }
  }
  PlannerProcessOptions po;
  po.command = spec.command;
  po.cwd = spec.cwd;
  po.log = log;
  po.isolated = isolated;
  po.log_max_bytes = static_cast<long long>(spec.log_max_mb * 1024.0 * 1024.0);
  // A start that fails (namespaces refused after the probe passed, a keeper too slow on a
  // loaded machine) fails this run only: the bench goes on with the others.
  std::optional<PlannerProcess> started;
  try {
    started.emplace(po);
  } catch (const std::runtime_error& e) {
    return failed_at_start(world, run,
                           std::string("cannot start the planner program: ") + e.what());
  }
  PlannerProcess& process = *started;
  const std::string see_log = " (its output: " + log.string() + ")";

  protocol::ClientOptions client;
  client.connect_timeout = ms_of(spec.start_timeout_s);
  client.reply_timeout = ms_of(spec.reply_timeout_s);
  client.log = [](protocol::LogLevel, std::string_view) {};  // the report says what went wrong
  client.stop = run.stop;
  if (isolated) client.open_socket = [&process] { return process.open_socket(); };
  std::string gave_up;
  client.give_up = [&process, &gave_up]() -> std::string {
    const std::string ended = process.ended();
    if (!ended.empty()) gave_up = "the planner program " + ended + " before it listened";
    return gave_up;
  };
  const auto url = protocol::parse_planner_url("ws://127.0.0.1:" + std::to_string(spec.port));

  sim::RunReport report;
  try {
    protocol::PlannerConnection connection(url.value(), client);
    report = spec.realtime ? protocol::run_realtime(world, connection, client, run)
                           : protocol::run_lock_step(world, connection, client, run);
    connection.close();
  } catch (const protocol::ConnectionError& e) {
    report = failed_at_start(world, run, connect_failure(e, gave_up, spec, client) + see_log);
  }
  say_how_it_ended(report, process, see_log);
  process.stop();
  return report;
}

}  // namespace

bool program_isolated(const PlannerEntry& entry) {
  const PlannerNetwork network = entry.program ? entry.program->network : PlannerNetwork::host;
  const sandbox::NetworkCheck check = sandbox::check_planner_network(network);
  if (check.refused) throw UsageError("--planner-network isolated: " + check.why);
  return check.own_network;
}

ExternalPlanner program_planner(const PlannerEntry& entry, const std::filesystem::path& log) {
  ExternalPlanner ext;
  ext.name = entry.name;
  ext.address = "ws://127.0.0.1:" + std::to_string(entry.program->port) + " (" + entry.source + ")";
  ext.loop = [entry, log](sim::World& world, const sim::RunOptions& run) {
    return run_program(entry, log, world, run);
  };
  return ext;
}

}  // namespace overtake::planners
