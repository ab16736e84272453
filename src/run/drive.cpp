#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "overtake/base/errors.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/planners/external.hpp"
#include "overtake/planners/plan_watch.hpp"
#include "overtake/planners/program_planner.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/map_file.hpp"
#include "overtake/run/pages.hpp"
#include "overtake/run/report.hpp"
#include "overtake/run/resources.hpp"
#include "overtake/run/scenario_file.hpp"
#include "overtake/sim/checkpoint.hpp"
#include "overtake/sim/recorded_traffic.hpp"
#include "overtake/sim/warm_up.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::run {

using base::UsageError;
using planners::ExternalPlanner;
using planners::PlannerCatalog;
using planners::PlannerEntry;
using planners::PlannerKind;
using planners::program_planner;
using planners::watch_policy;
namespace {

static_assert(kMaxMinutes * 60.0 < sim::kMaxCheckpointRunS, "every drive must checkpoint");
constexpr const char* kDefaultTrackName = "tracks/default.csv";

const PlannerCatalog& builtin_catalog() {
  static const PlannerCatalog catalog;
  return catalog;
}

const PlannerCatalog& catalog_of(const DriveOptions& opts) {
  return opts.planners ? *opts.planners : builtin_catalog();
}

/// What a cut scenario starts from, checked against the drive's map.
struct CutStart {
  sim::Checkpoint checkpoint;
  sim::TrafficProfile profile = sim::TrafficProfile::faithful;
  std::optional<sim::RecordedTraffic> recorded;
  std::optional<sim::WarmUp> warm_up;
};

CutStart prepare_cut(const Track& track, const Config& config, const sim::Scenario& scenario) {
  const sim::ScenarioCut& cut = *scenario.cut;
  const std::string name = "scenario '" + scenario.name + "'";
  CutStart out;
  try {
    out.checkpoint = sim::decode_checkpoint(cut.checkpoint, name + ": cut.checkpoint");
    if (cut.replayed) {
      out.recorded =
          sim::decode_recorded_traffic(cut.recorded, name + ": cut.recorded_traffic",
                                       config.road.lane_count, track.map.waypoints.size());
    }
    if (!cut.warm_up.empty()) {
      out.warm_up = sim::decode_warm_up(cut.warm_up, name + ": cut.warm_up.telemetry");
      if (static_cast<long>(out.warm_up->cycles.size()) != cut.warm_up_cycles) {
        throw ConfigError(name + ": cut.warm_up.cycles says " + std::to_string(cut.warm_up_cycles) +
                          ", its telemetry holds " + std::to_string(out.warm_up->cycles.size()));
      }
    }
  } catch (const core::StateError& e) {
    throw ConfigError(e.what());
  }
  const sim::CheckpointInfo& info = out.checkpoint.info;
  const auto profile = sim::parse_traffic_profile(info.traffic);
  if (!profile) {
    throw ConfigError(name + ": cut from " + info.traffic +
                      " traffic; only faithful and calm runs can be cut");
  }
  out.profile = *profile;
  const std::string map_hash = core::hex64(track.map.content_hash);
  if (info.map_hash != map_hash) {
    throw ConfigError(name + ": cut from a run on the map " + info.track + " (hash " +
                      info.map_hash + "), but this drive's map is " + track.map.source + " (hash " +
                      map_hash + ")" +
                      (cut.map.empty() ? std::string() : "; give --map " + cut.map));
  }
  return out;
}

}  // namespace

void validate_drive_options(const DriveOptions& opts) {
  if (!(opts.minutes > 0.0) || opts.minutes > kMaxMinutes || !std::isfinite(opts.minutes)) {
    std::ostringstream os;
    os << "--minutes must be more than 0 and at most " << kMaxMinutes << " (got " << opts.minutes
       << ")";
    throw UsageError(os.str());
  }
  if (opts.steps_per_call < 0 || opts.steps_per_call > 1000) {
    throw UsageError("--steps-per-call must be between 1 and 1000 (got " +
                     std::to_string(opts.steps_per_call) + ")");
  }
  if (!sim::parse_traffic_profile(opts.traffic)) {
    throw UsageError("--traffic: unknown profile '" + opts.traffic +
                     "' (available: faithful, calm)");
  }
  const PlannerCatalog& catalog = catalog_of(opts);
  if (!opts.external) static_cast<void>(catalog.require(opts.policy));
  if (!(opts.checkpoint_every_s >= 0.0) || opts.checkpoint_every_s > 3600.0) {
    throw UsageError("--checkpoint-every must be between 0 (none) and 3600 s (got " +
                     std::to_string(opts.checkpoint_every_s) + ")");
  }
  if (opts.live && (opts.live->port < 0 || opts.live->port > 65535)) {
    throw UsageError("--port must be between 0 and 65535 (got " + std::to_string(opts.live->port) +
                     ")");
  }
}

std::shared_ptr<const Track> load_track(const std::optional<std::filesystem::path>& path) {
  core::Map map;
  if (path) {
    map = load_map_file(*path);
  } else {
    const auto text = resources::embedded_file(kDefaultTrackName);
    if (!text) throw core::MapError("the built-in default track is missing from this build");
    map = core::parse_map(*text, kBuiltinMapSource);
  }
  core::ReferenceLine line(map);
  return std::make_shared<const Track>(Track{std::move(map), std::move(line)});
}

RunProvenance drive_provenance(const Track& track, const Config& config, const DriveOptions& opts,
                               const sim::Scenario* scenario) {
  const auto profile = sim::parse_traffic_profile(opts.traffic);
  RunProvenance p;
  p.seed = opts.seed;
  if (opts.external) {
    p.planner_url = opts.external->address;
    p.policy = opts.external->name.empty() ? opts.external->address : opts.external->name;
  } else {
    p.policy = opts.policy;
    const PlannerEntry* entry = catalog_of(opts).find(opts.policy);
    if (entry && entry->kind != PlannerKind::builtin) p.planner = entry->describe();
    if (entry && entry->program && opts.planner_log) p.planner_log = opts.planner_log->string();
  }
  p.traffic = !scenario                 ? std::string(sim::to_string(*profile))
              : !scenario->cut          ? std::string("scripted")
              : scenario->cut->replayed ? std::string("replayed")
                                        : std::string("reactive");
  if (scenario) p.scenario = scenario->name.empty() ? "unnamed scenario" : scenario->name;
  p.map_path = track.map.source;
  p.map_hash = core::hex64(track.map.content_hash);
  p.params_hash = config_hash(config);
  p.steps_per_call = opts.steps_per_call;
  p.min_steps_per_call = config.world.min_steps_per_call;
  p.max_steps_per_call = config.world.max_steps_per_call;
  p.minutes = opts.minutes;
  return p;
}

namespace {

// The world a drive starts with: a cut scenario's (random traffic restored later from its
// checkpoint), a scripted scenario's, or random traffic from the seed.
std::unique_ptr<sim::World> make_world(const Track& track, const Config& config,
                                       const DriveOptions& opts, const sim::Scenario* scenario,
                                       const std::optional<CutStart>& cut) {
  if (cut) {
    return std::make_unique<sim::World>(track.map, track.line, config.world, cut->profile,
                                        cut->checkpoint.info.seed);
  }
  if (scenario) return std::make_unique<sim::World>(track.map, track.line, config.world, *scenario);
  return std::make_unique<sim::World>(track.map, track.line, config.world,
                                      *sim::parse_traffic_profile(opts.traffic), opts.seed);
}

sim::RunOptions run_options(const DriveOptions& opts,
                            const std::function<void(double, double)>& progress,
                            const std::atomic<bool>* stop, const std::optional<CutStart>& cut) {
  sim::RunOptions run;
  run.duration_s = opts.minutes * 60.0;
  if (opts.steps_per_call > 0) run.steps_per_call = opts.steps_per_call;
  run.seed = opts.seed;
  run.progress = progress;
  run.stop = stop;
  // A live view is watched at real time.
  if (opts.live) run.pace = sim::Pace::real_time;
  if (cut) {
    run.restore = cut->checkpoint.run;
    run.restore_scope = sim::RunOptions::RestoreScope::world;
    if (cut->recorded) run.replayed_traffic = &*cut->recorded;
  }
  return run;
}

// The replay writer of a recorded drive (null when not recorded), with the checkpoints it
// carries, and the live view when asked (into `result`).
std::unique_ptr<replay::ReplayWriter> start_watchers(const Track& track, const Config& config,
                                                     const DriveOptions& opts,
                                                     const sim::Scenario* scenario,
                                                     const std::optional<CutStart>& cut,
                                                     sim::RunOptions& run, DriveResult& result) {
  if (!opts.record && !opts.live) return nullptr;
  const RunProvenance& p = result.provenance;
  const replay::ReplayHeader header = replay_header_for(track, config, p, run.duration_s, scenario,
                                                        cut ? &cut->checkpoint.info : nullptr);
  if (opts.live) result.live = start_live_view(header, *opts.live);
  if (!opts.record) return nullptr;
  // Last: a failure above (a port in use) leaves no replay file behind.
  auto writer = std::make_unique<replay::ReplayWriter>(*opts.record, header);
  // Checkpoints restore into a world made the same way: random traffic, or a reactive cut
  // (its world is random traffic restored); not scripted cars, not replayed ones.
  const bool restorable = !scenario || (cut && !cut->recorded);
  if (restorable && opts.checkpoint_every_s > 0.0) {
    run.checkpoint_every_s = opts.checkpoint_every_s;
    sim::CheckpointInfo info;
    info.traffic = cut ? cut->checkpoint.info.traffic
                       : std::string(sim::to_string(*sim::parse_traffic_profile(opts.traffic)));
    info.seed = cut ? cut->checkpoint.info.seed : opts.seed;
    info.track = track.map.source;
    info.map_hash = p.map_hash;
    info.config_hash = p.params_hash;
    info.policy = p.policy;
    writer->set_checkpoint_info(std::move(info));
  }
  return writer;
}

// Drives a built-in policy, a plugin or a Python planner in this process.
sim::RunReport drive_policy(const Track& track, const Config& config, const DriveOptions& opts,
                            const PlannerEntry& entry, const std::optional<CutStart>& cut,
                            sim::World& world, sim::RunOptions& run) {
  auto policy = entry.make(track.line, config.planner);
  // A built-in policy picks up where it was when the scenario was cut from its own run.
  if (cut && cut->checkpoint.info.policy == opts.policy) {
    try {
      (void)planner::restore_policy_state(*policy, cut->checkpoint.planner);
    } catch (const core::StateError& e) {
      throw ConfigError(e.what());
    }
  }
  if (run.checkpoint_every_s > 0.0) {
    run.planner_state = [&policy] { return planner::save_policy_state(*policy); };
  }
  const auto& tap = opts.telemetry_tap;
  // Planners from outside that share this process are watched: a plan() call past the
  // reply timeout, or still running after Ctrl-C, is interrupted (or the process ends).
  if (entry.watched()) {
    policy = watch_policy(std::move(policy), entry.label(), entry.reply_timeout_s, run.stop);
  }
  return sim::run_drive(
      world,
      [&policy, &tap, &world](const core::Telemetry& t) {
        if (tap) tap(world.time_s(), t);
        return policy->plan(t);
      },
      run);
}

}  // namespace

DriveResult drive_on(const Track& track, const Config& config, const DriveOptions& opts,
                     const std::function<void(double, double)>& progress,
                     const std::atomic<bool>* stop, const sim::Scenario* scenario) {
  validate_drive_options(opts);
  std::optional<CutStart> cut;
  if (scenario && scenario->cut) cut = prepare_cut(track, config, *scenario);
  const std::unique_ptr<sim::World> world = make_world(track, config, opts, scenario, cut);
  DriveResult result;
  result.provenance = drive_provenance(track, config, opts, scenario);
  if (cut) result.provenance.seed = cut->checkpoint.info.seed;  // the run it was cut from
  sim::RunOptions run = run_options(opts, progress, stop, cut);
  // Recording and the live view watch the run; without them it has no observer.
  const std::unique_ptr<replay::ReplayWriter> writer =
      start_watchers(track, config, opts, scenario, cut, run, result);
  sim::ObserverList observers(
      {writer.get(), result.live ? &result.live->observer() : nullptr, opts.watcher});
  run.observer = observers.get();

  const PlannerEntry* entry = opts.external ? nullptr : catalog_of(opts).find(opts.policy);
  // A planner from outside keeps state no checkpoint holds. Driven in lock-step, its answers
  // are recorded exactly (a cut of the run drives the world on with them), and a cut
  // scenario's warm-up is played to it before it drives.
  const bool outside = opts.external || entry->kind != PlannerKind::builtin;
  const bool lock_step =
      opts.external ? opts.external->lock_step : !(entry->program && entry->program->realtime);
  if (writer && outside && lock_step) writer->set_exact_paths(true);
  if (cut && cut->warm_up && outside && lock_step && opts.warm_up) run.warm_up = &*cut->warm_up;
  if (opts.external) {
    result.report = opts.external->loop(*world, run);
  } else if (entry->program) {
    const ExternalPlanner program = program_planner(
        *entry,
        opts.planner_log.value_or(std::filesystem::path("planner-" + entry->name + ".log")));
    result.report = program.loop(*world, run);
  } else {
    result.report = drive_policy(track, config, opts, *entry, cut, *world, run);
  }
  if (writer || result.live) {
    const std::string end = replay_report_json(result.report, result.provenance);
    if (result.live) result.live->finish(end);
    if (writer) writer->finish(end);
  }
  return result;
}

DriveInputs load_drive_inputs(const DriveOptions& opts) {
  DriveInputs in;
  in.config = load_config(opts.config);
  in.options = opts;
  if (opts.scenario) {
    in.scenario = load_scenario(*opts.scenario, in.config.road);
    // A cut scenario names the map it was cut on (relative to the scenario file).
    if (!opts.map && in.scenario->cut && !in.scenario->cut->map.empty()) {
      in.options.map = opts.scenario->parent_path() / in.scenario->cut->map;
    }
    if (in.scenario->name.empty()) in.scenario->name = opts.scenario->filename().string();
    if (opts.minutes_from_scenario && in.scenario->duration_s) {
      in.options.minutes = *in.scenario->duration_s / 60.0;
    }
  }
  in.track = load_track(in.options.map);
  return in;
}

DriveResult drive_loaded(const DriveInputs& in, const std::function<void(double, double)>& progress,
                         const std::atomic<bool>* stop) {
  return drive_on(*in.track, in.config, in.options, progress, stop,
                  in.scenario ? &*in.scenario : nullptr);
}

DriveResult drive(const DriveOptions& opts, const std::function<void(double, double)>& progress,
                  const std::atomic<bool>* stop) {
  return drive_loaded(load_drive_inputs(opts), progress, stop);
}

}  // namespace overtake::run
