#pragma once
// `overtake cut REPLAY --at T`: a scenario file that starts a little before a moment of a
// recorded run and lasts a little after it (docs/scenarios.md). The world starts from the
// replay's checkpoint; when the run was driven by a built-in policy (whose state is in the
// checkpoint), the run is driven on from the checkpoint to the exact start, checked against
// the recorded frames. Traffic is reactive (it keeps driving by its rules) or replayed (every
// car follows its recorded bodies whatever the ego does).

#include <filesystem>
#include <optional>
#include <string>

#include "overtake/sim/scenario.hpp"
#include "overtake/sim/warm_up.hpp"

namespace overtake::scenarios {

/// The least a cut scenario judges (after its lead-in), in seconds: a shorter one tests
/// nothing (a planner's path reaches a second ahead), and one of 0 s is refused by `drive`.
inline constexpr double kMinCutJudgedS = 1.0;
/// The longest a cut scenario reaches before or after its moment, and its longest lead-in (s):
/// `cut` and `hunt` (which cuts a scenario of each failure it finds) take the same bounds.
inline constexpr double kMaxCutWindowS = 3600.0;
/// The default warm-up of a cut of a run of a planner from outside (s): long enough for the
/// public planner programs' target speeds to climb from 0 to their cap (measured in
/// docs/scenarios.md).
inline constexpr double kDefaultWarmUpS = 60.0;

/// Reads `--warm-up`: seconds (0 to kMaxCutWindowS) or "all". UsageError naming the flag.
void parse_warm_up(const std::string& text, double& seconds, bool& all);

/// Throws UsageError naming the flag (--before, --after, --lead-in) and the value when one is
/// not a time from 0 to kMaxCutWindowS, or when --before and --after together judge less than
/// kMinCutJudgedS.
void check_cut_window(double before_s, double after_s, double lead_in_s = 0.0);

struct CutOptions {
  std::filesystem::path replay;
  double at_s = 0.0;
  double before_s = 15.0;
  double after_s = 5.0;
  /// The scenario starts this much earlier still, for the planner to settle (not judged).
  double lead_in_s = 0.0;
  bool replayed = false;  ///< replayed traffic (else reactive)
  std::filesystem::path out;
  std::optional<std::filesystem::path> config;
  /// The map the run was on, when it is no longer where the replay says.
  std::optional<std::filesystem::path> map;
  std::string name;
  std::string description;
  /// What the scenario expects; default: no at-fault collision.
  std::optional<sim::ScenarioExpect> expect;
  /// For a run of a planner from outside: the seconds before the start whose telemetry the
  /// scenario carries, played to the planner before it drives (0: none) ...
  double warm_up_s = kDefaultWarmUpS;
  /// ... or every cycle from the run's first (`--warm-up all`).
  bool warm_up_all = false;
  /// The answers in a row that bring a planner in step.
  int in_step_cycles = sim::kDefaultInStepCycles;
};

/// What was cut.
struct CutResult {
  double start_s = 0.0;  ///< where the scenario starts (run time)
  double end_s = 0.0;    ///< where it ends
  double asked_start_s = 0.0;
  /// True when the start is exactly the asked one (a built-in policy drove the run on from
  /// the checkpoint); false when it is the checkpoint at or before it.
  bool exact_start = false;
  std::string planner_state;  ///< "restored", or why the planner starts afresh
  std::string incident;       ///< the incident nearest the moment, if any ("collision ...")
  std::string policy;         ///< the planner that drove the run
  /// The command that drives the scenario with that planner (`overtake drive --policy P
  /// --scenario F`, `overtake sim --planner-cmd ... --scenario F`, ...).
  std::string drive_command;
  std::size_t checkpoint_bytes = 0;
  std::size_t file_bytes = 0;
  std::size_t warm_up_cycles = 0;  ///< cycles of the warm-up the scenario carries
  double warm_up_start_s = 0.0;    ///< the run's time at its first
  bool has_warm_up = false;
};

/// Cuts the scenario and writes it to `opts.out` (replacing it atomically). Throws UsageError
/// for bad flags, replay::ReplayError for an unreadable replay, ConfigError when the replay
/// cannot be cut (no checkpoints, another map, a run that does not replay the same).
CutResult cut_replay(const CutOptions& opts);

/// The JSON of `expect` as scenario files write it.
[[nodiscard]] std::string expect_json(const sim::ScenarioExpect& expect);

}  // namespace overtake::scenarios
