#pragma once
// One drive, from its options to its report: the track, the config, the planner (a built-in
// policy, one of the catalog, or a planner from outside), the world, the recording and the
// live view.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "overtake/core/map.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/planners/external.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/report.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/scenario.hpp"

namespace overtake::view {
class LiveView;
}  // namespace overtake::view

namespace overtake::run {

/// The map source of the built-in default track (a run's `map_path`, a checkpoint's track).
inline constexpr const char* kBuiltinMapSource = "builtin:default";

/// A loaded map and its reference line (the line does not refer to the map; the world does).
struct Track {
  core::Map map;
  core::ReferenceLine line;
};

/// The map file at `path`, or the built-in default track. Throws core::MapError.
[[nodiscard]] std::shared_ptr<const Track> load_track(
    const std::optional<std::filesystem::path>& path);

/// Where the live view of a run is served (`--live`).
struct LiveOptions {
  std::string host = "127.0.0.1";
  int port = 8080;  ///< 0: any free port
  /// Called with the page's address once the server listens, before the run starts.
  std::function<void(const std::string& url)> on_listening;
};

/// Options of `overtake drive` (and, with `external`, of `overtake sim --planner`).
struct DriveOptions {
  std::optional<std::filesystem::path> map;
  double minutes = 30.0;
  std::uint64_t seed = 1;
  std::string traffic = "faithful";
  std::string policy = "reference";
  int steps_per_call = 0;  ///< 0: drawn per call by the seed
  std::optional<std::filesystem::path> config;
  /// A scripted scenario (JSON, see docs/scenarios.md) instead of random traffic.
  std::optional<std::filesystem::path> scenario;
  /// Take the duration from the scenario file when it gives one (the CLI sets this when
  /// --minutes is not given).
  bool minutes_from_scenario = false;
  /// Record a replay (docs/replay.md) to this file.
  std::optional<std::filesystem::path> record;
  /// A recorded replay carries a world checkpoint this often (simulated seconds; 0: none), so
  /// that `overtake cut` can start a scenario at any moment of it.
  double checkpoint_every_s = 10.0;
  /// Serve the live view of the run, which then goes at 1x real time.
  std::optional<LiveOptions> live;
  /// Sees every telemetry the planner receives, with the world time (not a flag: for
  /// `calibrate` and tests; in-process policies only).
  std::function<void(double t_s, const core::Telemetry& telemetry)> telemetry_tap;
  /// When set, the planner is this instead of `policy` (`sim --planner`).
  std::optional<planners::ExternalPlanner> external;
  /// The planners `policy` is looked up in (plugins, Python planners, planner programs);
  /// null: the built-in policies only.
  std::shared_ptr<const planners::PlannerCatalog> planners;
  /// Where a planner program's standard output and error go (`--planner-cmd`).
  std::optional<std::filesystem::path> planner_log;
  /// Also watches the run (not a flag: scenario suites; not owned).
  sim::RunObserver* watcher = nullptr;
  /// A cut scenario's warm-up is played to a planner from outside before it starts
  /// (`--no-warm-up`: the planner starts afresh at the scenario's start).
  bool warm_up = true;
};

/// Checks flag values and names (UsageError naming the flag).
void validate_drive_options(const DriveOptions& opts);

/// A finished drive.
struct DriveResult {
  sim::RunReport report;
  RunProvenance provenance;
  /// With DriveOptions::live: the view, still serving the page (the run is over).
  std::shared_ptr<view::LiveView> live;
};

/// What the report's `config` says of a drive with these inputs (`scenario` may be null).
[[nodiscard]] RunProvenance drive_provenance(const Track& track, const Config& config,
                                             const DriveOptions& opts,
                                             const sim::Scenario* scenario);

/// Checks the options (UsageError naming the flag), loads everything and runs the drive.
/// `progress` (may be empty) is called now and then with simulated time and distance;
/// `stop` (may be null) ends the run early when set.
[[nodiscard]] DriveResult drive(
    const DriveOptions& opts,
    const std::function<void(double t_s, double distance_m)>& progress = {},
    const std::atomic<bool>* stop = nullptr);

/// What a drive loads before it runs: the config, the track, the scenario (when one is
/// given), and the options with the scenario's duration applied.
struct DriveInputs {
  Config config;
  std::shared_ptr<const Track> track;
  std::optional<sim::Scenario> scenario;
  DriveOptions options;
};

/// Loads what `opts` names (ConfigError, core::MapError naming the file).
[[nodiscard]] DriveInputs load_drive_inputs(const DriveOptions& opts);

/// drive() on inputs already loaded (`sim --planner` loads them before it connects).
[[nodiscard]] DriveResult drive_loaded(
    const DriveInputs& inputs,
    const std::function<void(double t_s, double distance_m)>& progress = {},
    const std::atomic<bool>* stop = nullptr);

/// Like drive(), with the map and config already loaded.
/// `stop` (may be null) ends the run early when set; `scenario` (may be null) replaces the
/// random traffic (opts.scenario is not read here). With opts.record the replay is written
/// (also when the run fails: it ends with the report so far); with opts.live the run is
/// served live and paced at real time.
[[nodiscard]] DriveResult drive_on(
    const Track& track, const Config& config, const DriveOptions& opts,
    const std::function<void(double t_s, double distance_m)>& progress = {},
    const std::atomic<bool>* stop = nullptr, const sim::Scenario* scenario = nullptr);

}  // namespace overtake::run
