#pragma once
// `overtake hunt`: drives one planner over seeds, maps and traffic profiles in parallel until
// it has failed N times (or a budget of simulated hours is spent), and turns each distinct
// failure into a replay, a cut scenario of both kinds and the commands that reproduce it.
// Failures of the same kind in the same situation are grouped (docs/scenarios.md).

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/batch/shard.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/scenarios/cut.hpp"
#include "overtake/sim/referee.hpp"

namespace overtake::batch {

/// What counts as a failure.
enum class HuntTarget { collisions, at_fault, incidents };

struct HuntSpec {
  std::string policy = "reference";
  std::shared_ptr<const planners::PlannerCatalog> planners;  ///< null: built-in policies only
  /// Maps to drive on (nullopt: the built-in track).
  std::vector<std::optional<std::filesystem::path>> maps = {std::nullopt};
  std::vector<std::string> traffic = {"faithful", "calm"};
  std::uint64_t first_seed = 1;
  /// When not empty, the seeds driven, in this order, instead of first_seed up (the budget
  /// then allows one run per seed, map and traffic profile): `risk` cuts its runs' events so.
  std::vector<std::uint64_t> seeds;
  double minutes = 30.0;     ///< per run
  int failures = 5;          ///< stop once this many are found
  double budget_hours = 10;  ///< ... or once this much is simulated
  HuntTarget target = HuntTarget::collisions;
  /// With target incidents: only incidents of this type are failures.
  std::optional<sim::IncidentType> incident_type;
  double before_s = 15.0;  ///< the cut scenarios' window
  double after_s = 5.0;
  /// The warm-up a cut of a planner from outside carries (CutOptions::warm_up_s, warm_up_all).
  double warm_up_s = scenarios::kDefaultWarmUpS;
  bool warm_up_all = false;
  std::optional<std::filesystem::path> config;
  int jobs = 1;
  std::filesystem::path out = "hunt-out";
  /// Hunt only the runs k with k mod shard_count == shard_index - 1, each shard until it has
  /// found `failures` of its own (or spent the budget's runs of its slice): `merge_hunt` of
  /// all shards then finds what one hunt would (the first failures in run order).
  int shard_index = 1;  ///< 1-based
  int shard_count = 1;
  [[nodiscard]] Shard shard() const { return {shard_index, shard_count}; }
  /// Write into `out` even when it holds a hunt (hunt.json, hunt.md) or files in replays/ or
  /// scenarios/: the new hunt's replace those of the same names.
  bool force = false;
};

/// One failure found.
struct HuntFailure {
  std::size_t run = 0;  ///< index of the run in the hunt's order
  std::uint64_t seed = 0;
  std::string traffic;
  std::string map;  ///< "default" or the map file
  double t_s = 0.0;
  std::string what;       ///< e.g. "collision hit_from_behind (not at fault)"
  std::string situation;  ///< the group's key
  std::string replay;     ///< relative to the hunt's folder
  std::string rerun;      ///< the command that drives the whole run again
};

/// Failures of one kind in one situation.
struct HuntGroup {
  std::string situation;
  std::vector<std::size_t> failures;  ///< indices into HuntOutcome::failures
  std::string reactive;               ///< the first one's cut scenarios (relative paths)
  std::string replayed;
  std::string cut_error;  ///< why a scenario could not be cut (empty when both were)
  /// Each scenario driven again at once by the planner: "yes", or "no: what happened
  /// instead", with the warm-up's account (empty when not cut).
  std::string reproduces_reactive;
  std::string reproduces_replayed;
  bool reproduced = false;  ///< both scenarios repeat the failure at its step
  /// Set when the hunt's warm-up did not bring a planner from outside in step and the scenarios
  /// were cut again from the run's first cycle (`--warm-up all`): says so.
  std::string warm_up;
  /// Set when the planner, told the same twice (the reactive scenario driven a second time),
  /// answered differently: how, from the first cycle that differed.
  std::string nondeterministic;
  /// The one-line command that reproduces it: the reactive scenario, or the whole run.
  std::string repro;
};

struct HuntProgress {
  std::size_t runs = 0;
  double simulated_s = 0.0;
  double budget_s = 0.0;
  std::size_t failures = 0;
  std::size_t groups = 0;
  double wall_s = 0.0;
};

/// What merge_hunt needs of a shard besides its failures.
struct HuntShardInfo {
  bool finished = false;
  std::size_t max_runs = 0;  ///< of the whole hunt (its budget in runs)
  /// The simulated seconds of each run taken, by run index.
  std::vector<std::pair<std::size_t, double>> run_seconds;
  nlohmann::json sweep;  ///< what makes shards one hunt (flags, parameters' hash)
  std::string revision;
};

struct HuntOutcome {
  std::size_t runs = 0;
  double simulated_s = 0.0;
  double wall_s = 0.0;
  bool interrupted = false;
  /// Why the hunt stopped before its end (a run or a file that failed); empty when it did not.
  std::string error;
  std::vector<HuntFailure> failures;
  std::vector<HuntGroup> groups;
  std::optional<HuntShardInfo> shard;  ///< a shard's (shard_count > 1)
};

/// The runs the budget allows (--budget-hours over --minutes, at least one; check_hunt_spec
/// refuses a budget of 10^8 runs or more, where this saturates).
[[nodiscard]] std::size_t hunt_max_runs(const HuntSpec& spec);
/// The name of the files of run `run`'s failures (its replay, before its extension; its
/// scenarios start with it): policy, map, traffic and seed as a slug, unique per map, traffic
/// and seed of the hunt (maps whose slugs are the same, mp/seed_2.csv and mp/seed-2.csv, get a
/// short hash of their whole names).
[[nodiscard]] std::string hunt_run_name(const HuntSpec& spec, std::size_t run);
/// Refuses an output folder that holds a hunt (hunt.json), a hunt.md, or files in replays/ or
/// scenarios/: a hunt would replace them. Throws UsageError starting with `who`, naming the
/// file, and ending with `remedy`; nothing when `force`.
void check_hunt_out(const std::filesystem::path& out, bool force, const std::string& who,
                    const std::string& remedy);
/// Checks everything run_hunt checks before its first run (flags, parameters, maps), and
/// runs nothing: for a hunt that runs elsewhere (`--slurm`).
void check_hunt_spec(const HuntSpec& spec);

/// Runs the hunt (UsageError for bad flags before any run). Runs are taken in a fixed order
/// (seed, then map, then traffic) and their results in that order, so the same options find
/// the same failures whatever the number of jobs. Writes out/hunt.json and out/hunt.md after
/// each failure (Ctrl-C keeps what was found), out/replays/ and out/scenarios/; a scenario
/// that cannot be cut is said in its group (`cut_error`). When a run or a file fails, the
/// workers are stopped and joined, the runs in progress removed, hunt.json written with what
/// was found and the reason (`error`), and std::runtime_error thrown with the reason.
[[nodiscard]] HuntOutcome run_hunt(const HuntSpec& spec, const std::atomic<bool>* stop,
                                   const std::function<void(const HuntProgress&)>& progress);

/// Joins the folders of the shards of one hunt into `out`: the first `failures` failures of
/// all shards in run order, grouped as one hunt groups them, with their replays and cut
/// scenarios copied, and hunt.md and hunt.json as one unsharded hunt writes them (timing
/// aside). Throws UsageError when a shard is missing, unfinished, doubled, of another hunt or
/// of another build, or when `out` is one of them or holds a hunt.
[[nodiscard]] HuntOutcome merge_hunt(const std::vector<std::filesystem::path>& dirs,
                                     const std::filesystem::path& out);

[[nodiscard]] std::string hunt_markdown(const HuntSpec& spec, const HuntOutcome& outcome);

/// What `overtake hunt` prints (its table, its pace, the files written; unless `quiet`) and
/// its exit status: 130 when interrupted (saying what was kept), else 0.
[[nodiscard]] int report_hunt(const HuntSpec& spec, const HuntOutcome& outcome, bool quiet);
[[nodiscard]] nlohmann::json hunt_json(const HuntSpec& spec, const HuntOutcome& outcome);

}  // namespace overtake::batch
