#pragma once
// `overtake risk`: the rate of a rare event (an at-fault contact, any contact, a near miss, a
// rubric incident) per 100 miles for one planner, by multilevel splitting of plain runs
// (eval/splitting.hpp) from world checkpoints: a run whose ego comes near a car is copied
// there, each copy going on with fresh random draws from the world's own distributions, and
// the events of copies count by their weights. docs/evaluation.md, "Rare events", states the
// estimator, its variance, its assumptions and what its calibration measured.
//
// The runs are those of a bench (one seed a run, the same map, traffic and length), so the
// rate means what the bench's rate means. Run r's seed is first_seed + r; its copies' draws
// come from a seed derived from it, so the estimate does not depend on --jobs.

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/batch/hunt.hpp"
#include "overtake/batch/shard.hpp"
#include "overtake/eval/splitting.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/sim/proximity.hpp"
#include "overtake/sim/referee.hpp"

namespace overtake::batch {

/// What is counted.
enum class RiskEventKind : std::uint8_t { at_fault, contact, near_miss, incident };
struct RiskEvent {
  RiskEventKind kind = RiskEventKind::at_fault;
  sim::IncidentType incident = sim::IncidentType::collision;  ///< for kind incident
  /// "at-fault", "contact", "near-miss" or the rubric's name of the incident type.
  [[nodiscard]] std::string name() const;
  friend bool operator==(const RiskEvent&, const RiskEvent&) = default;
};
/// The --event names; UsageError naming the choices for any other.
[[nodiscard]] RiskEvent parse_risk_event(const std::string& name);

/// Risk's own parameters (config/risk.json; a file given by --params overrides its keys).
struct RiskParams {
  /// The importance score is the ego's predicted margin to the nearest car (metres,
  /// sim/proximity.hpp), negated: a copy is made each time it falls below one of these.
  sim::ProximityParams score;
  std::vector<double> margins_m = {4.0, 2.0, 0.25, 0.0};  ///< decreasing
  /// Paths that go on from each up-crossing (1: none). The shipped ones split nothing: on the
  /// simulator, copies made where this score sees danger (1-2 s before a contact) repeat
  /// their path's fate, and splitting measured a gain below 1 (docs/evaluation.md, "Rare
  /// events"); the levels are still counted, as the score's measurement.
  std::vector<int> splits = {1, 1, 1, 1};
  /// A base run making more paths than this is an error (eval::SplitLimits).
  std::size_t max_paths = 20000;
  /// The stopping rules are looked at after every this many base runs (in run order, so
  /// that --jobs does not change where an estimate stops).
  int batch_runs = 16;
  /// --rel-error stops no estimate with fewer base runs holding an event than this: an
  /// interval from fewer is too rough to stop on.
  int min_runs_with_events = 10;
  friend bool operator==(const RiskParams&, const RiskParams&) = default;
  /// The splitting levels on the score (-margin): increasing thresholds.
  [[nodiscard]] eval::SplitLevels levels() const;
  /// Throws ConfigError naming the key.
  void validate() const;
};

/// The risk parameters of config/risk.json, with `path`'s keys over them (ConfigError naming
/// the file and key).
[[nodiscard]] RiskParams load_risk_params(const std::optional<std::filesystem::path>& path);
[[nodiscard]] nlohmann::json risk_params_json(const RiskParams& params);

struct RiskSpec {
  std::string policy = "reference";
  std::shared_ptr<const planners::PlannerCatalog> planners;  ///< null: built-in policies only
  std::optional<std::filesystem::path> map;                  ///< nullopt: the built-in track
  std::string traffic = "faithful";
  std::uint64_t first_seed = 1;
  double minutes = 10.0;  ///< per base run
  RiskEvent event;
  /// Stop once the interval's half width is within this share of the estimate (0: never).
  double rel_error = 0.25;
  double budget_hours = 20.0;  ///< ... or once this many simulated hours are spent
  std::size_t max_runs = 100000;
  std::optional<std::filesystem::path> config;
  std::optional<std::filesystem::path> params;
  int jobs = 1;
  std::filesystem::path out = "risk-out";
  /// The first this many events of the base runs (in run order) are cut into scenarios in
  /// OUT/events by a hunt over their runs' seeds (batch/hunt.hpp: grouped by situation, each
  /// group's scenarios checked to repeat the event); 0: none.
  int scenarios = 5;
  bool resume = false;  ///< take up the runs of --out (refused when they are of another estimate)
  /// A slice of the runs (--shard I/N, a Slurm task): run k is this shard's when k mod N is
  /// I - 1, and a shard runs every one of its runs among the planned ones (risk_runs_planned):
  /// the stopping rules look at the whole estimate, so only the merge applies them. Its
  /// events are cut by the merge.
  Shard shard;
};

/// The base runs an estimate can take before a stopping rule must stop it: every run the
/// budget buys at a base run's cost (--minutes; copies cost more, so the budget stops no
/// later), to the end of that block of batch_runs, and at most --max-runs. The shards of a
/// Slurm array run these between them.
[[nodiscard]] std::size_t risk_runs_planned(const RiskSpec& spec);

/// A path of a run that its planner ended: it failed (threw, crashed, stalled, sent what is
/// not a path). The path ends there; its miles and events up to then count, the failure is the
/// planner's, never the event.
struct RiskFailure {
  std::size_t path = 0;  ///< 0: the base run itself; else a copy
  double t_s = 0.0;      ///< simulated time of the failure
  std::string reason;
  friend bool operator==(const RiskFailure&, const RiskFailure&) = default;
};

/// One base run and its copies.
struct RiskRun {
  std::size_t index = 0;
  std::uint64_t seed = 0;
  eval::SplitTally tally;  ///< exposure in metres, cost in simulated seconds
  double wall_s = 0.0;
  std::vector<RiskFailure> failures;  ///< the paths its planner ended, in the order they ended
  /// True when the base run itself was ended by its planner.
  [[nodiscard]] bool base_failed() const {
    return std::any_of(failures.begin(), failures.end(),
                       [](const RiskFailure& f) { return f.path == 0; });
  }
};

/// Where an estimate stands.
struct RiskProgress {
  std::size_t runs = 0;
  double simulated_h = 0.0;
  double budget_h = 0.0;
  double weighted_events = 0.0;
  double rate_per_100mi = 0.0;
  double rel_half_width = 0.0;  ///< 0 with no event
  double wall_s = 0.0;
};

/// What an estimate found.
struct RiskOutcome {
  std::vector<RiskRun> runs;     ///< in run order
  eval::SplitEstimate estimate;  ///< per metre
  double miles = 0.0;            ///< of the base runs
  double simulated_h = 0.0;      ///< everything: base runs and copies
  double base_h = 0.0;
  double plain_mc_h = 0.0;  ///< what plain runs would need for the same variance
  double gain = 0.0;
  std::string stopped_by;  ///< "rel-error", "budget", "max-runs", "interrupted"
  bool interrupted = false;
  double wall_s = 0.0;
  std::size_t resumed_runs = 0;
  RiskParams params;  ///< the levels it used
  /// The events cut into scenarios (RiskSpec::scenarios), when a hunt ran; `cut_note` says
  /// why not, or how the hunt ended when it did not end well.
  std::optional<HuntOutcome> cut;
  std::string cut_note;
  /// Of a merge (merge_risk): the shards and runs it found, and the runs it kept.
  std::string merged_note;
};

/// Refuses what cannot be estimated (UsageError naming the flag): bad numbers, a planner
/// kind splitting cannot branch, an --out that holds another estimate.
void check_risk_spec(const RiskSpec& spec);

/// Runs the estimate; `stop` (may be null) ends it keeping the finished runs (runs.jsonl in
/// --out, written as each finishes). A path whose planner fails ends there (RiskRun::failures:
/// the planner's failure, never the event). Throws std::runtime_error naming the first failure
/// when the planner failed in every run so far (checked after each block of runs), and
/// naming the run and seed when a run cannot be run at all.
[[nodiscard]] RiskOutcome run_risk(const RiskSpec& spec, const std::atomic<bool>* stop,
                                   const std::function<void(const RiskProgress&)>& progress);

/// Merges the shards of one estimate into `spec.out` (`overtake risk --merge`, and the end of
/// a Slurm array): each must be a shard of the estimate `spec` describes (its planner, event,
/// map, traffic, length, config, levels and build; UsageError naming the shard and what
/// differs), the shards of one count with none twice. The estimate is that of the runs from
/// run 0 that the shards hold without a gap, with the stopping rules of `spec` looked at after
/// each block as the estimate looks at them: the same runs, and so the same estimate, as one
/// run here with the same flags. Writes --out as run_risk does (and cuts the events).
[[nodiscard]] RiskOutcome merge_risk(const RiskSpec& spec,
                                     const std::vector<std::filesystem::path>& shards,
                                     const std::atomic<bool>* stop);

/// The outcome's figures as risk.json holds them.
[[nodiscard]] nlohmann::json risk_json(const RiskSpec& spec, const RiskOutcome& outcome);
/// The summary (summary.md, and what the command prints).
[[nodiscard]] std::string risk_markdown(const RiskSpec& spec, const RiskOutcome& outcome);

/// What an estimate's command prints (unless `quiet`: the summary, `how` it ran, the files
/// written) and writes to `json_out` (`--json`, when given); the exit status: 130 when it was
/// interrupted (saying so on stderr, with what was kept), else 0.
[[nodiscard]] int report_risk(const RiskSpec& spec, const RiskOutcome& outcome,
                              const std::filesystem::path& json_out, bool quiet,
                              const std::string& how);

/// True when `dir` holds a risk estimate (risk.json).
[[nodiscard]] bool holds_risk(const std::filesystem::path& dir);
/// Two risk estimates compared (`overtake compare A B` of two risk --out folders): the ratio of
/// the candidate's rate to the base's with its interval and verdict (eval::rate_ratio), and
/// notes where their map, traffic or run length differ. Throws std::runtime_error naming the
/// file when one cannot be read, and when the two count different events.
[[nodiscard]] nlohmann::json compare_risk_folders(const std::filesystem::path& base,
                                                  const std::filesystem::path& candidate);
[[nodiscard]] std::string compare_risk_text(const nlohmann::json& comparison);

/// An at-fault estimate of a risk folder as the bench page's speed-against-safety chart
/// draws it beside the bench's rows: folder, label, policy, config, traffic, map, rate and
/// interval per 100 mi, upper_bound_only, mean_speed_mph and base_miles. Throws
/// std::runtime_error naming the file when it cannot be read or counts another event.
[[nodiscard]] nlohmann::json risk_chart_point(const std::filesystem::path& dir);

}  // namespace overtake::batch
