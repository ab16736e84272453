// `overtake serve` (our planners for the original simulator) and `overtake sim --planner`
// (our simulator for any planner written for the original), over the original protocol.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>

#include "overtake/app/cli.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/core/units.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/planners/external.hpp"
#include "overtake/planners/plan_watch.hpp"
#include "overtake/planners/program_planner.hpp"
#include "overtake/protocol/client.hpp"
#include "overtake/protocol/server.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/finish.hpp"
#include "overtake/run/pages.hpp"
#include "overtake/run/progress.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::app {

using base::kExitOk;
using base::UsageError;
using planners::catalog_from_flags;
using planners::chosen_policy;
using planners::ExternalPlanner;
using planners::PlannerEntry;
using planners::PlannerFlags;
using planners::PlannerFlagSet;
using planners::program_isolated;
using planners::watch_policy;
using run::Config;
using run::drive_loaded;
using run::DriveInputs;
using run::DriveOptions;
using run::DriveOutputs;
using run::DriveResult;
using run::finish_drive;
using run::load_config;
using run::load_drive_inputs;
using run::load_track;
using run::ProgressLine;
using run::validate_drive_options;
namespace {

constexpr std::size_t kMinFrameBytes = 1024;

void check_limits(std::size_t max_frame_bytes, std::size_t max_path_points) {
  if (max_frame_bytes < kMinFrameBytes) {
    throw UsageError("--max-frame-bytes must be at least " + std::to_string(kMinFrameBytes) +
                     " (got " + std::to_string(max_frame_bytes) + ")");
  }
  if (max_path_points < 1) throw UsageError("--max-path-points must be at least 1");
}

std::optional<std::filesystem::path> optional_path(const std::string& s) {
  if (s.empty()) return std::nullopt;
  return std::filesystem::path(s);
}

// ---- serve ------------------------------------------------------------------------------

struct ServeArgs {
  std::string host = "127.0.0.1";
  int port = 4567;
  std::string map, config;
  std::string policy = "reference";
  bool policy_given = false;
  PlannerFlags planners;
  std::size_t max_frame_bytes = std::size_t{1} << 20;
  std::size_t max_path_points = protocol::Limits{}.max_path_points;
  bool quiet = false;
};

int cmd_serve(const ServeArgs& a) {
  if (a.port < 0 || a.port > 65535) {
    throw UsageError("--port must be between 0 and 65535 (got " + std::to_string(a.port) + ")");
  }
  check_limits(a.max_frame_bytes, a.max_path_points);
  const auto catalog = catalog_from_flags(a.planners);
  const std::string policy = chosen_policy(*catalog, a.policy, a.policy_given);
  const PlannerEntry* entry = &catalog->require(policy);
  const Config config = load_config(optional_path(a.config));
  const auto track = load_track(optional_path(a.map));

  protocol::PlannerSetup setup;
  setup.line = std::shared_ptr<const core::ReferenceLine>(track, &track->line);
  setup.params = config.planner;
  setup.policy = policy;
  setup.factory = entry->make;
  // Ctrl-C and SIGTERM set a flag (not an asio signal handler, which the one thread that
  // serves would have to run): a planner from outside that hangs in that thread is then
  // still interrupted, or the process ended, within a second, like a hang past its timeout.
  const InterruptScope interrupt;
  if (entry->watched()) {
    setup.factory = [make = entry->make, label = entry->label(), timeout = entry->reply_timeout_s](
                        const core::ReferenceLine& line, const planner::PlannerParams& params) {
      return watch_policy(make(line, params), label, timeout, &InterruptScope::flag());
    };
  }
  protocol::ServeOptions opts;
  opts.host = a.host;
  opts.port = static_cast<std::uint16_t>(a.port);
  opts.max_frame_bytes = a.max_frame_bytes;
  opts.limits.max_path_points = a.max_path_points;
  opts.status_lines = !a.quiet;
  opts.log = protocol::stderr_log(!a.quiet);

  protocol::serve_until(setup, opts, InterruptScope::flag(), [&a] {
    if (!a.quiet) std::fprintf(stderr, "stopping\n");
  });
  return kExitOk;
}

// ---- sim --------------------------------------------------------------------------------

struct SimArgs {
  RunFlags run;
  PlannerFlags programs;
  std::string planner_log;
  std::string planner;
  std::string name;
  bool realtime = false;
  double connect_timeout_s = 10.0;
  double reply_timeout_s = 2.0;
  std::size_t max_frame_bytes = std::size_t{1} << 20;
  std::size_t max_path_points = protocol::Limits{}.max_path_points;
};

std::chrono::milliseconds checked_timeout(double seconds, const char* flag) {
  if (!(seconds > 0.0) || seconds > 3600.0) {
    throw UsageError(std::string(flag) + " must be more than 0 and at most 3600 seconds");
  }
  return std::chrono::milliseconds(std::max<long long>(1, std::llround(seconds * 1000.0)));
}

// `sim --planner-cmd`: overtake starts the program, drives it and stops it (the program's
// run loop, as in `bench`), the rest as `drive`.
int cmd_sim_program(SimArgs& a) {
  if (a.programs.commands.size() != 1) {
    throw UsageError("--planner-cmd: give one planner program (bench takes several)");
  }
  const auto json_out = apply_run_flags(a.run);
  DriveOptions& opts = a.run.opts;
  PlannerFlags flags = a.programs;
  flags.reply_timeout_s = a.reply_timeout_s;
  flags.start_timeout_s = a.connect_timeout_s;
  flags.realtime = a.realtime;
  auto catalog = catalog_from_flags(flags);
  opts.planners = catalog;
  opts.policy = catalog->added_names().front();
  const PlannerEntry* entry = catalog->find(opts.policy);
  opts.planner_log = a.planner_log.empty()
                         ? std::filesystem::path("planner-" + opts.policy + ".log")
                         : std::filesystem::path(a.planner_log);
  (void)program_isolated(*entry);  // --planner-network isolated where it is impossible: now
  const DriveInputs inputs = load_drive_inputs(opts);
  const bool quiet = a.run.quiet;
  const InterruptScope interrupt;
  ProgressLine progress(!quiet, inputs.options.minutes * 60.0);
  const auto wall0 = std::chrono::steady_clock::now();
  const DriveResult result = drive_loaded(
      inputs, [&progress](double t, double d) { progress.update(t, d); }, &InterruptScope::flag());
  DriveOutputs out;
  out.json = json_out;
  out.quiet = quiet;
  out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  out.mode = std::string(a.realtime ? "real time" : "lock-step") + " over the protocol, program " +
             opts.policy + ", its output in " + opts.planner_log->string();
  progress.clear();
  return finish_drive(result, opts, out, &InterruptScope::flag());
}

int cmd_sim(SimArgs& a) {
  if (!a.programs.commands.empty()) {
    if (!a.planner.empty()) throw UsageError("--planner and --planner-cmd: give one of them");
    if (a.realtime && a.run.opts.steps_per_call > 0) {
      throw UsageError("--steps-per-call applies to lock-step runs only, not with --realtime");
    }
    return cmd_sim_program(a);
  }
  if (a.planner.empty()) {
    throw UsageError("give the planner: --planner ws://HOST:PORT, or --planner-cmd CMD");
  }
  const auto url = protocol::parse_planner_url(a.planner);
  if (!url) throw UsageError("--planner: " + url.error());
  if (a.realtime && a.run.opts.steps_per_call > 0) {
    throw UsageError("--steps-per-call applies to lock-step runs only, not with --realtime");
  }
  const auto json_out = apply_run_flags(a.run);
  DriveOptions& opts = a.run.opts;
  const bool quiet = a.run.quiet;
  protocol::ClientOptions client;
  client.connect_timeout = checked_timeout(a.connect_timeout_s, "--connect-timeout");
  client.reply_timeout = checked_timeout(a.reply_timeout_s, "--reply-timeout");
  check_limits(a.max_frame_bytes, a.max_path_points);
  client.max_frame_bytes = a.max_frame_bytes;
  client.limits.max_path_points = a.max_path_points;
  client.log = protocol::stderr_log(!quiet);

  // The planner, reached over the protocol: the rest is `drive` (the same world, recording,
  // live view, report), so that a lock-step run over the wire and an in-process drive with
  // the same planner give the same report.
  std::optional<protocol::PlannerConnection> connection;
  ExternalPlanner remote;
  remote.address = protocol::to_string(url.value());
  remote.name = a.name;
  remote.lock_step = !a.realtime;
  remote.loop = [&](sim::World& world, const sim::RunOptions& run) {
    return a.realtime ? protocol::run_realtime(world, *connection, client, run)
                      : protocol::run_lock_step(world, *connection, client, run);
  };
  opts.external = std::move(remote);
  validate_drive_options(opts);  // before connecting: a bad flag needs no planner
  const DriveInputs inputs = load_drive_inputs(opts);

  connection.emplace(url.value(), client);
  if (!quiet) std::fprintf(stderr, "connected to %s\n", opts.external->address.c_str());
  // From here on Ctrl-C or SIGTERM stop the run at the next step (or a wait for the planner
  // at once), and the report so far is printed and written as for any early end. (While
  // connecting there is nothing to keep: the signal ends the process.)
  const InterruptScope interrupt;
  client.stop = &InterruptScope::flag();

  ProgressLine progress(!quiet, inputs.options.minutes * 60.0);
  const auto wall0 = std::chrono::steady_clock::now();
  const DriveResult result = drive_loaded(
      inputs, [&progress](double t, double d) { progress.update(t, d); }, &InterruptScope::flag());
  connection->close();
  DriveOutputs out;
  out.json = json_out;
  out.quiet = quiet;
  out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  out.mode = a.realtime ? "real time over the protocol" : "lock-step over the protocol";
  progress.clear();
  return finish_drive(result, opts, out, &InterruptScope::flag());
}

}  // namespace

Subcommand register_serve(CLI::App& app) {
  auto a = std::make_shared<ServeArgs>();
  auto* cmd = app.add_subcommand(
      "serve",
      "Serve a planner over the original simulator's websocket protocol (the original "
      "simulator, or `overtake sim --planner`, drives it).");
  cmd->add_option("--port", a->port, "TCP port to listen on (0: any free port)")
      ->capture_default_str();
  cmd->add_option("--host", a->host,
                  "Address to listen on (the old planners listen on all; we do not)")
      ->capture_default_str();
  cmd->add_option("--map", a->map, "Map file (x y s dx dy per line); default: the built-in track")
      ->check(CLI::ExistingFile);
  auto* policy = cmd->add_option("--policy", a->policy, policy_help())->capture_default_str();
  add_planner_flags(*cmd, a->planners, PlannerFlagSet::in_process);
  cmd->add_option("--config", a->config, "JSON file overriding any of the default parameters")
      ->check(CLI::ExistingFile);
  cmd->add_option("--max-frame-bytes", a->max_frame_bytes,
                  "Larger frames are dropped (a telemetry gets manual)")
      ->capture_default_str();
  cmd->add_option("--max-path-points", a->max_path_points,
                  "A telemetry with a longer previous path is refused (manual)")
      ->capture_default_str();
  cmd->add_flag("--quiet,-q", a->quiet,
                "No connection events or status lines (warnings still show)");
  return {cmd, [a, policy] {
            a->policy_given = policy->count() > 0;
            return cmd_serve(*a);
          }};
}

Subcommand register_sim(CLI::App& app) {
  auto a = std::make_shared<SimArgs>();
  auto* cmd = app.add_subcommand(
      "sim",
      "Drive a planner written for the original simulator over its websocket protocol and "
      "print the scorecard.");
  cmd->add_option("--planner", a->planner,
                  "The planner's address, ws://HOST:PORT[/PATH] (default path: "
                  "/socket.io/?EIO=4&transport=websocket)");
  add_planner_flags(*cmd, a->programs, PlannerFlagSet::programs);
  cmd->add_option("--planner-log", a->planner_log,
                  "With --planner-cmd: the program's output goes here (default:\n"
                  "planner-NAME.log)");
  cmd->add_option("--name", a->name, "Name of the planner in the report (default: its address)");
  add_run_flags(*cmd, a->run);
  cmd->add_flag(
      "--realtime", a->realtime,
      "Step at 50 Hz of wall time and keep driving while the planner thinks, as the original");
  cmd->add_option("--connect-timeout", a->connect_timeout_s, "Seconds to keep trying to connect")
      ->capture_default_str();
  cmd->add_option("--reply-timeout", a->reply_timeout_s, "Seconds to wait for each reply")
      ->capture_default_str();
  cmd->add_option("--max-frame-bytes", a->max_frame_bytes, "A larger reply ends the run")
      ->capture_default_str();
  cmd->add_option("--max-path-points", a->max_path_points, "A longer path in a reply ends the run")
      ->capture_default_str();
  return {cmd, [a] { return cmd_sim(*a); }};
}

}  // namespace overtake::app
