// `overtake serve` (our planners for the original simulator) and `overtake sim --planner`
// (our simulator for any planner written for the original), over the original protocol.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <thread>

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>

#include "overtake/app/cli.hpp"
#include "overtake/app/commands.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/app/io.hpp"
#include "overtake/app/progress.hpp"
#include "overtake/app/viewer.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/core/units.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/protocol/client.hpp"
#include "overtake/protocol/server.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::app {
namespace {

constexpr double kMaxMinutes = 7.0 * 24.0 * 60.0;
constexpr std::size_t kMinFrameBytes = 1024;

std::string policy_names() {
  std::string out;
  for (const auto& p : planner::list_policies()) out += (out.empty() ? "" : ", ") + p.name;
  return out;
}

std::string policy_help() {
  std::string out = "Policy to plan with. Available:";
  for (const auto& p : planner::list_policies()) out += "\n  " + p.name + ": " + p.summary;
  return out;
}

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
  std::string policy = "walkthrough";
  std::size_t max_frame_bytes = std::size_t{1} << 20;
  std::size_t max_path_points = protocol::Limits{}.max_path_points;
  bool quiet = false;
};

int cmd_serve(const ServeArgs& a) {
  if (a.port < 0 || a.port > 65535) {
    throw UsageError("--port must be between 0 and 65535 (got " + std::to_string(a.port) + ")");
  }
  check_limits(a.max_frame_bytes, a.max_path_points);
  const auto policies = planner::list_policies();
  if (std::none_of(policies.begin(), policies.end(),
                   [&](const auto& p) { return p.name == a.policy; })) {
    throw UsageError("--policy: unknown policy '" + a.policy + "' (available: " + policy_names() +
                     ")");
  }
  const Config config = load_config(optional_path(a.config));
  const auto track = load_track(optional_path(a.map));

  protocol::PlannerSetup setup;
  setup.line = std::shared_ptr<const core::ReferenceLine>(track, &track->line);
  setup.params = config.planner;
  setup.policy = a.policy;
  protocol::ServeOptions opts;
  opts.host = a.host;
  opts.port = static_cast<std::uint16_t>(a.port);
  opts.max_frame_bytes = a.max_frame_bytes;
  opts.limits.max_path_points = a.max_path_points;
  opts.status_lines = !a.quiet;
  opts.log = protocol::stderr_log(!a.quiet);

  boost::asio::io_context ioc;
  boost::asio::signal_set signals(ioc, SIGINT, SIGTERM);
  signals.async_wait([&ioc, &a](const boost::system::error_code& ec, int) {
    if (ec) return;
    if (!a.quiet) std::fprintf(stderr, "stopping\n");
    ioc.stop();
  });
  protocol::run_server(ioc, setup, opts);
  return kExitOk;
}

// ---- sim --------------------------------------------------------------------------------

struct SimArgs {
  std::string planner;
  std::string name;
  double minutes = 30.0;
  std::uint64_t seed = 1;
  std::string traffic = "faithful";
  int steps_per_call = 0;
  std::string map, config, json, record;
  bool live = false;
  LiveOptions live_view;
  bool realtime = false;
  double connect_timeout_s = 10.0;
  double reply_timeout_s = 2.0;
  std::size_t max_frame_bytes = std::size_t{1} << 20;
  std::size_t max_path_points = protocol::Limits{}.max_path_points;
  bool quiet = false;
};

std::chrono::milliseconds checked_timeout(double seconds, const char* flag) {
  if (!(seconds > 0.0) || seconds > 3600.0) {
    throw UsageError(std::string(flag) + " must be more than 0 and at most 3600 seconds");
  }
  return std::chrono::milliseconds(std::max<long long>(1, std::llround(seconds * 1000.0)));
}

int cmd_sim(const SimArgs& a) {
  const auto url = protocol::parse_planner_url(a.planner);
  if (!url) throw UsageError("--planner: " + url.error());
  if (!(a.minutes > 0.0) || a.minutes > kMaxMinutes || !std::isfinite(a.minutes)) {
    throw UsageError("--minutes must be more than 0 and at most " + std::to_string(kMaxMinutes));
  }
  if (a.steps_per_call < 0 || a.steps_per_call > 1000) {
    throw UsageError("--steps-per-call must be between 1 and 1000 (got " +
                     std::to_string(a.steps_per_call) + ")");
  }
  if (a.realtime && a.steps_per_call > 0) {
    throw UsageError("--steps-per-call applies to lock-step runs only, not with --realtime");
  }
  if (a.live && (a.live_view.port < 0 || a.live_view.port > 65535)) {
    throw UsageError("--port must be between 0 and 65535 (got " + std::to_string(a.live_view.port) + ")");
  }
  const auto profile = sim::parse_traffic_profile(a.traffic);
  if (!profile)
    throw UsageError("--traffic: unknown profile '" + a.traffic + "' (available: faithful, calm)");
  protocol::ClientOptions client;
  client.connect_timeout = checked_timeout(a.connect_timeout_s, "--connect-timeout");
  client.reply_timeout = checked_timeout(a.reply_timeout_s, "--reply-timeout");
  check_limits(a.max_frame_bytes, a.max_path_points);
  client.max_frame_bytes = a.max_frame_bytes;
  client.limits.max_path_points = a.max_path_points;
  client.log = protocol::stderr_log(!a.quiet);

  const Config config = load_config(optional_path(a.config));
  const auto track = load_track(optional_path(a.map));

  // The world exactly as drive_on builds it, so that a lock-step run over the wire and an
  // in-process drive with the same planner give the same report.
  sim::World world(track->map, track->line, config.world, *profile, a.seed);
  sim::RunOptions run;
  run.duration_s = a.minutes * 60.0;
  if (a.steps_per_call > 0) run.steps_per_call = a.steps_per_call;
  run.seed = a.seed;
  ProgressLine progress(!a.quiet, run.duration_s);
  run.progress = [&progress](double t, double d) { progress.update(t, d); };

  RunProvenance p;
  p.seed = a.seed;
  p.planner_url = protocol::to_string(url.value());
  p.policy = a.name.empty() ? p.planner_url : a.name;
  p.traffic = std::string(sim::to_string(*profile));
  p.map_path = track->map.source;
  p.map_hash = core::hex64(track->map.content_hash);
  p.params_hash = config_hash(config);
  p.steps_per_call = a.steps_per_call;
  p.min_steps_per_call = config.world.min_steps_per_call;
  p.max_steps_per_call = config.world.max_steps_per_call;
  p.minutes = a.minutes;

  protocol::PlannerConnection connection(url.value(), client);
  if (!a.quiet) std::fprintf(stderr, "connected to %s\n", protocol::to_string(url.value()).c_str());
  // From here on Ctrl-C or SIGTERM stop the run at the next step (or a wait for the planner
  // at once), and the report so far is printed and written as for any early end. (While
  // connecting there is nothing to keep: the signal ends the process.)
  const InterruptScope interrupt;
  run.stop = &InterruptScope::flag();
  client.stop = &InterruptScope::flag();
  // Recording and the live view (which holds a lock-step run to real time), once the
  // planner is there.
  std::unique_ptr<sim::ReplayWriter> writer;
  std::shared_ptr<view::LiveView> live;
  if (!a.record.empty() || a.live) {
    const sim::ReplayHeader header = replay_header_for(*track, config, p, run.duration_s);
    if (a.live) {
      LiveOptions lo = a.live_view;
      lo.on_listening = [](const std::string& url_text) {
        std::fprintf(stderr, "live view at %s (the run goes at real time; Ctrl-C stops it)\n",
                     url_text.c_str());
      };
      live = start_live_view(header, lo, !a.realtime);
    }
    // Last: a failure above (a port in use) leaves no replay file behind.
    if (!a.record.empty()) writer = std::make_unique<sim::ReplayWriter>(a.record, header);
  }
  sim::ObserverList observers({writer.get(), live ? &live->observer() : nullptr});
  run.observer = observers.get();

  const auto wall0 = std::chrono::steady_clock::now();
  sim::RunReport report;
  if (a.realtime) {
    report = protocol::run_realtime(world, connection, client, run);
  } else {
    report = protocol::run_lock_step(world, connection, client, run);
  }
  connection.close();
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  progress.clear();
  if (writer || live) {
    const std::string end = replay_report_json(report, p);
    if (live) live->finish(end);
    if (writer) writer->finish(end);
  }

  std::cout << format_scorecard(report, p);
  if (!a.quiet) {
    std::printf("  wall time          %.2f s (%.1fx real time, %s)\n", wall_s,
                wall_s > 0 ? report.duration_s / wall_s : 0.0,
                a.realtime ? "real time" : "lock-step");
  }
  std::cout.flush();
  if (!a.json.empty()) {
    write_file_atomic(a.json, report_to_json(report, p).dump(2) + "\n");
    if (!a.quiet) std::cout << "  report written to " << a.json << "\n";
  }
  if (writer && !a.quiet) std::cout << "  replay written to " << a.record << "\n";
  std::cout.flush();
  if (report.ended_early == "stopped") return kExitInterrupted;
  if (live) {
    std::fprintf(stderr, "the run is over; the live view stays at %s until Ctrl-C\n",
                 live->url().c_str());
    while (!InterruptScope::flag().load()) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return report.ended_early.empty() ? kExitOk : kExitFailure;
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
  cmd->add_option("--policy", a->policy, policy_help())->capture_default_str();
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
  return {cmd, [a] { return cmd_serve(*a); }};
}

Subcommand register_sim(CLI::App& app) {
  auto a = std::make_shared<SimArgs>();
  auto* cmd = app.add_subcommand(
      "sim",
      "Drive a planner written for the original simulator over its websocket protocol and "
      "print the scorecard.");
  cmd->add_option("--planner", a->planner,
                  "The planner's address, ws://HOST:PORT[/PATH] (default path: "
                  "/socket.io/?EIO=4&transport=websocket)")
      ->required();
  cmd->add_option("--name", a->name, "Name of the planner in the report (default: its address)");
  cmd->add_option("--minutes", a->minutes, "Simulated minutes to drive")->capture_default_str();
  cmd->add_option("--seed", a->seed, "Seed of the traffic and latency draws (0 to 2^64 - 1)")
      ->check(seed_validator())
      ->capture_default_str();
  cmd->add_option("--traffic", a->traffic,
                  "Traffic profile: faithful (the original's rules) or calm")
      ->capture_default_str();
  cmd->add_option("--map", a->map, "Map file (x y s dx dy per line); default: the built-in track")
      ->check(CLI::ExistingFile);
  cmd->add_option("--config", a->config, "JSON file overriding any of the default parameters")
      ->check(CLI::ExistingFile);
  cmd->add_option(
      "--steps-per-call", a->steps_per_call,
      "Lock-step: world steps per reply (1-1000); default: drawn from 1-3 per reply by the seed")
      ->check(CLI::Range(1, 1000));
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
  cmd->add_option("--json", a->json, "Also write the report as JSON to this file");
  cmd->add_option("--record", a->record,
                  "Record a replay of the run to this file; watch it with `overtake view FILE`");
  auto* live = cmd->add_flag(
      "--live", a->live,
      "Serve the run's live view (open the printed address in a browser); a lock-step run then\n"
      "goes at real time, and the page stays served after the run until Ctrl-C");
  cmd->add_option("--port", a->live_view.port, "With --live: TCP port of the page (0: any free port)")
      ->capture_default_str()
      ->needs(live);
  cmd->add_option("--host", a->live_view.host,
                  "With --live: address to serve the page on (loopback by default)")
      ->capture_default_str()
      ->needs(live);
  cmd->add_flag("--quiet,-q", a->quiet, "No progress line or extra messages");
  return {cmd, [a] { return cmd_sim(*a); }};
}

}  // namespace overtake::app
