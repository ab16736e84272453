#pragma once
// `overtake tune`: a search of a planner's parameters. Each trial is a bench of the planner,
// with one value for each parameter, on the same training seeds (common random numbers: the
// objective the optimiser sees is a deterministic function of the parameters). A
// derivative-free optimiser of NLopt proposes the trials; every finished trial is kept as a
// row of trials.jsonl (so Ctrl-C loses nothing and --resume goes on), and the search ends
// with a paired bench of the best parameters against the starting ones on held-out seeds.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/batch/bench.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/planners/catalog.hpp"

namespace overtake::batch {

/// The files of a tune's output folder.
inline constexpr const char* kTuneManifestFile = "tune.json";
inline constexpr const char* kTuneTrialsFile = "trials.jsonl";
inline constexpr const char* kTuneBestFile = "best.json";
inline constexpr const char* kTuneSummaryFile = "summary.md";
inline constexpr const char* kTunePageFile = "tune.html";
/// The benches: trials/NNNN/, validation/start/ and validation/best/ (with several maps, one
/// folder map-K/ for each inside trials/NNNN/ and validation/).
inline constexpr const char* kTuneTrialsFolder = "trials";
inline constexpr const char* kTuneValidationFolder = "validation";
/// The most trials one search runs (--trials).
inline constexpr int kMaxTuneTrials = 100'000;

/// One parameter searched: a name, its range, where the search starts.
struct TuneParam {
  std::string name;  ///< a config key (dotted), a program's placeholder, a keyword
  double low = 0.0;
  double high = 0.0;
  std::optional<double> start;  ///< unset: the config's value, or the middle of the range
};

/// Parses NAME=LOW:HIGH or NAME=LOW:HIGH@START (--param). Throws UsageError naming --param.
[[nodiscard]] TuneParam parse_tune_param(const std::string& text);

/// A bound on a figure of a trial (--constraint NAME<=VALUE or NAME>=VALUE).
struct TuneConstraint {
  std::string figure;
  bool at_most = true;
  double bound = 0.0;
};
/// Parses NAME<=VALUE or NAME>=VALUE. Throws UsageError naming --constraint and the figures.
[[nodiscard]] TuneConstraint parse_tune_constraint(const std::string& text);

/// The figures of a trial (its bench's runs, every seed and traffic profile together), by
/// name: the metrics of overtake::eval (mean_speed_mph, incidents_per_100mi, ...) and counts
/// (incidents, collisions, at_fault_collisions, near_misses, ended_early, runs).
[[nodiscard]] const std::vector<std::string>& tune_figure_names();
/// Whether a higher value of the figure is better (the objective's direction).
[[nodiscard]] bool tune_figure_higher_is_better(const std::string& name);

/// The figures of a trial's risk estimate (TuneSpec::risk): the rate of its event per 100 mi
/// with the 95% interval's ends, the weighted events, the miles and simulated hours spent.
[[nodiscard]] const std::vector<std::string>& tune_risk_figure_names();

/// The derivative-free optimisers offered (NLopt's local ones, which need no gradient).
[[nodiscard]] const std::vector<std::string>& tune_algorithm_names();

/// The risk each trial is judged by (`tune --max-risk`, `--risk-hours`): the rate of an event
/// per 100 mi, estimated by `overtake risk` (batch/risk.hpp) on every map and traffic profile
/// of the search, the trials on the same runs (common random numbers: a trial's rate is a
/// deterministic function of its parameters), the validation's on runs of their own.
struct TuneRisk {
  RiskEvent event;
  /// --max-risk: a trial is feasible when its estimate (risk_per_100mi) is at most this; the
  /// validation says whether the best's held-out estimate, and its interval's upper end, are.
  std::optional<double> max_per_100mi;
  double hours = 2.0;              ///< each trial's budget, simulated hours over its maps
  double validation_hours = 10.0;  ///< the start's and the best's, each, on held-out runs
  /// The trials' runs are seeded first_seed, first_seed + 1, ... (as risk's --first-seed);
  /// the validation's follow the last one a trial's budget can reach.
  std::uint64_t first_seed = 100001;
  double rel_error = 0.25;  ///< a trial's estimate stops early once this precise
  friend bool operator==(const TuneRisk&, const TuneRisk&) = default;
};

/// What to search.
struct TuneSpec {
  std::string policy;  ///< a name of the catalog (built-in, program, Python)
  std::vector<TuneParam> params;
  std::string objective = "mean_speed_mph";
  std::vector<TuneConstraint> constraints;
  std::vector<std::string> traffic{"faithful"};
  std::vector<std::uint64_t> seeds;             ///< training
  std::vector<std::uint64_t> validation_seeds;  ///< held out; empty: no validation
  double minutes = 10.0;
  /// The maps each trial drives (every seed on each; nullopt: the built-in track). Empty:
  /// the built-in track. With several, a trial's figures are over the runs of all of them.
  std::vector<std::optional<std::filesystem::path>> maps;
  std::optional<std::filesystem::path> config;  ///< the starting config (built-in policies)
  /// Each trial's risk, estimated after its bench; its figures (tune_risk_figure_names) join
  /// the trial's, for --objective and --constraint. nullopt: no risk estimated.
  std::optional<TuneRisk> risk;
  int trials = 40;  ///< the budget
  std::string algorithm = "sbplx";
  int jobs = 1;
  std::filesystem::path out = "tune-out";
  bool resume = false;
  bool force = false;
  std::shared_ptr<const planners::PlannerCatalog> planners;
  /// Runs a bench (a trial's on one map, or a validation's) elsewhere, and says whether it was
  /// interrupted: `overtake tune --slurm` runs each as a Slurm array and merges it into the
  /// bench's folder. Empty: every bench runs here, on `jobs` threads.
  std::function<bool(const BenchSpec& bench, const std::atomic<bool>* stop)> run_bench_elsewhere;
};

/// One trial: the parameters, the figures, and how it scores.
struct TuneTrial {
  int number = 0;  ///< from 1
  std::map<std::string, double> params;
  nlohmann::json figures;  ///< name -> value
  double objective = 0.0;
  bool feasible = true;
  std::vector<std::string> violations;  ///< "incidents = 3 > 0"
  bool resumed = false;                 ///< read from trials.jsonl, not run now
};

/// Progress of a search: trials done of the budget, the current trial's runs.
struct TuneProgress {
  int trial = 0;
  int trials = 0;
  std::size_t runs_done = 0;
  std::size_t runs_total = 0;
  std::optional<double> best;
  double wall_s = 0.0;
};

/// The validation on one map: the best against the start, paired on the held-out seeds.
struct TuneValidation {
  std::string map;            ///< "the built-in track" or the map file
  nlohmann::json comparison;  ///< compare_bench_folders' result
  /// In a sentence: whether the best's gain in the objective holds on the held-out seeds
  /// (its verdict, change and interval), or that it could not be judged.
  std::string verdict;
  /// With TuneSpec::risk: the start's and the best's estimates on held-out runs, compared
  /// (compare_risk_folders; null when not run), and in a sentence whether the best is within
  /// the limit there.
  nlohmann::json risk;
  std::string risk_verdict;
};

/// What a search produced.
struct TuneOutcome {
  std::vector<TuneTrial> trials;
  std::optional<int> best;  ///< the best feasible trial's number
  bool interrupted = false;
  std::string stop_reason;                  ///< the optimiser's, or "the budget of N trials"
  std::vector<TuneValidation> validations;  ///< one per map (empty: none)
  std::string summary_markdown;             ///< also written to summary.md
  nlohmann::json best_config;               ///< also written to best.json
  std::string best_command;                 ///< a program's command with the best parameters
  double wall_s = 0.0;
};

/// Checks everything before the first trial (UsageError / ConfigError / MapError): the policy,
/// that each parameter can be given to it (a number in the config, a placeholder or a
/// variable of a program, a keyword of a Python planner), the ranges and starts, the
/// objective, the constraints, the seeds, the output folder.
void check_tune_spec(const TuneSpec& spec);

/// Runs the search, then the validation. `stop` (may be null) is polled: when set, the
/// trial in progress is abandoned, the finished ones are kept (trials.jsonl, summary.md,
/// tune.html, best.json) and no validation runs.
[[nodiscard]] TuneOutcome run_tune(const TuneSpec& spec, const std::atomic<bool>* stop,
                                   const std::function<void(const TuneProgress&)>& progress);

/// What `overtake tune` prints (its summary, the best command, the files written; unless
/// `quiet`) and its exit status: 130 when interrupted, 1 when no trial met the constraints.
[[nodiscard]] int report_tune(const TuneSpec& spec, const TuneOutcome& outcome, bool quiet);

/// The search's page: the objective of each trial, the best so far, the trials that broke a
/// constraint, the validation. Self-contained HTML.
[[nodiscard]] std::string tune_page(const TuneSpec& spec, const TuneOutcome& outcome);

}  // namespace overtake::batch
