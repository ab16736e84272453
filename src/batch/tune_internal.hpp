#pragma once
// What the files of `overtake tune` share (batch/tune*.cpp): the maps of a search, and the
// risk of a trial and of the validation (tune_risk.cpp).

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/batch/risk.hpp"
#include "overtake/batch/tune.hpp"

namespace overtake::batch::tune_detail {

/// A number as a flag gives it (the whole text, finite), or nullopt.
[[nodiscard]] std::optional<double> parse_number(std::string_view text);

/// Whether a --param name is one (letters, digits, _ and .).
[[nodiscard]] bool valid_param_name(std::string_view name);

/// A map of the search: a file, or nullopt for the built-in track.
using MapChoice = std::optional<std::filesystem::path>;

/// The maps a trial drives: those named, or the built-in track.
[[nodiscard]] std::vector<MapChoice> maps_of(const TuneSpec& spec);
[[nodiscard]] std::string map_label(const MapChoice& map);

// A parameter's place: a config key (as a JSON pointer), a program's placeholder or
// environment variable, a Python keyword.
struct Placement {
  enum class Kind { config, placeholder, environment, keyword } kind = Kind::config;
  std::string key;  ///< the config's JSON pointer, the placeholder's or variable's name
};

struct Target {
  std::shared_ptr<const planners::PlannerCatalog> catalog;  ///< holds `entry`
  const planners::PlannerEntry* entry = nullptr;
  nlohmann::json base_config;  ///< built-in policies: the starting config, every key
  /// Built-in policies: the keys the starting config file sets (none without --config). A
  /// trial's config is these and its parameters, so that a key the file leaves to the
  /// defaults is still moved by a knob (planner.reference.assertiveness) a trial turns.
  nlohmann::json file_config = nlohmann::json::object();
  std::vector<Placement> places;
};

/// The planner searched and where each parameter goes (UsageError naming --param when one
/// cannot be given to it).
[[nodiscard]] Target resolve_target(const TuneSpec& spec);
/// A program's command with the trial's parameters: placeholders replaced, variables set
/// before it.
[[nodiscard]] std::string program_command(const Target& t, const std::vector<double>& x);
/// A built-in policy's config for the trial: the starting file's keys and the parameters.
[[nodiscard]] nlohmann::json trial_config(const Target& t, const std::vector<double>& x);
/// The catalog a trial's bench runs: the tuned planner with the trial's parameters.
[[nodiscard]] std::shared_ptr<const planners::PlannerCatalog> trial_catalog(
    const Target& t, const TuneSpec& spec, const std::vector<double>& x);

/// Where the bench of map `k` of `n` goes under a trial's (or a validation's) folder: the
/// folder itself for one map, map-1/, map-2/, ... for several.
[[nodiscard]] std::filesystem::path map_folder(const std::filesystem::path& dir, std::size_t k,
                                               std::size_t n);
/// The bench of one point of the search: the planner with parameters `x` on `seeds` and
/// `map`, into `out` (a built-in policy's config with the values is written beside it, as
/// `config_file`).
[[nodiscard]] BenchSpec bench_of(const TuneSpec& spec, const Target& t,
                                 const std::vector<double>& x,
                                 const std::vector<std::uint64_t>& seeds, const MapChoice& map,
                                 const std::filesystem::path& out,
                                 const std::filesystem::path& config_file);
/// Runs bench `b` here, or where the spec says (Slurm); true when it was interrupted.
[[nodiscard]] bool run_bench_of(const TuneSpec& spec, const BenchSpec& b,
                                const std::atomic<bool>* stop,
                                const std::function<void(const BenchProgress&)>& progress);

/// The constraints a trial is judged by: --constraint's, and --max-risk's on risk_per_100mi.
[[nodiscard]] std::vector<TuneConstraint> constraints_of(const TuneSpec& spec);

/// Refuses a risk the search cannot estimate (UsageError naming the flag): bad numbers, runs
/// shorter than risk takes, risk figures named with no risk estimated, the validation's risk
/// runs on a training seed or the trials' on a held-out one.
void check_tune_risk(const TuneSpec& spec);

/// The planner a trial (or a validation) estimates the risk of: its policy, catalog and
/// config as its bench runs it. The rest of the RiskSpec is filled by the functions below.
struct RiskPlanner {
  std::string policy;
  std::shared_ptr<const planners::PlannerCatalog> planners;
  std::optional<std::filesystem::path> config;
};

/// The planner whose risk a bench of `x` runs, its config file `config_file` (as bench_of
/// writes it).
[[nodiscard]] RiskPlanner risk_planner(const TuneSpec& spec, const Target& t,
                                       const std::vector<double>& x,
                                       const std::filesystem::path& config_file);

/// A trial's risk: an estimate on each map and traffic profile of the search (TuneRisk::hours
/// each, the trials' runs), into `dir` (dir/MAP-TRAFFIC/ for each), pooled into the figures
/// of tune_risk_figure_names. A planner that fails in a run gives null figures and
/// "risk_error" (the trial is then not feasible). nullopt: interrupted.
[[nodiscard]] std::optional<nlohmann::json> trial_risk(const TuneSpec& spec,
                                                       const RiskPlanner& planner,
                                                       const std::filesystem::path& dir,
                                                       const std::atomic<bool>* stop);

/// The validation's risk on one map: the start's and the best's estimates on the held-out
/// runs (TuneRisk::validation_hours each, every traffic profile), into dir/risk-start and
/// dir/risk-best, with their ratio (eval::rate_ratio). Null when interrupted (and
/// `interrupted` set).
[[nodiscard]] nlohmann::json validate_risk_on(const TuneSpec& spec, const RiskPlanner& start,
                                              const RiskPlanner& best, const MapChoice& map,
                                              const std::filesystem::path& dir,
                                              const std::atomic<bool>* stop, bool& interrupted);

/// In a sentence: whether the best is within --max-risk on the held-out runs (its estimate and
/// its interval's upper end), and how its rate compares with the start's.
[[nodiscard]] std::string risk_verdict_of(const TuneSpec& spec, const nlohmann::json& validation);

/// The validation on every map, in validation/ (validation/map-K/ for several maps): the best
/// against the start on the held-out seeds (and their risks). Empty, with `interrupted` set,
/// when stopped.
[[nodiscard]] std::vector<TuneValidation> run_validation(const TuneSpec& spec, const Target& target,
                                                         const std::vector<double>& start,
                                                         const std::vector<double>& best,
                                                         const std::atomic<bool>* stop,
                                                         bool& interrupted);

/// The search's summary (summary.md, and what tune prints).
[[nodiscard]] std::string summary_of(const TuneSpec& spec, const TuneOutcome& o);

}  // namespace overtake::batch::tune_detail
