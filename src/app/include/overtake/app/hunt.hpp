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

#include "overtake/app/planners.hpp"

namespace overtake::app {

/// What counts as a failure.
enum class HuntTarget { collisions, at_fault, incidents };

struct HuntSpec {
  std::string policy = "reference";
  std::shared_ptr<const PlannerCatalog> planners;  ///< null: built-in policies only
  /// Maps to drive on (nullopt: the built-in track).
  std::vector<std::optional<std::filesystem::path>> maps = {std::nullopt};
  std::vector<std::string> traffic = {"faithful", "calm"};
  std::uint64_t first_seed = 1;
  double minutes = 30.0;     ///< per run
  int failures = 5;          ///< stop once this many are found
  double budget_hours = 10;  ///< ... or once this much is simulated
  HuntTarget target = HuntTarget::collisions;
  double before_s = 15.0;  ///< the cut scenarios' window
  double after_s = 5.0;
  std::optional<std::filesystem::path> config;
  int jobs = 1;
  std::filesystem::path out = "hunt-out";
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

struct HuntOutcome {
  std::size_t runs = 0;
  double simulated_s = 0.0;
  double wall_s = 0.0;
  bool interrupted = false;
  std::vector<HuntFailure> failures;
  std::vector<HuntGroup> groups;
};

/// Runs the hunt (UsageError for bad flags before any run). Runs are taken in a fixed order
/// (seed, then map, then traffic) and their results in that order, so the same options find
/// the same failures whatever the number of jobs. Writes out/hunt.md and out/hunt.json after
/// each failure (Ctrl-C keeps what was found), out/replays/ and out/scenarios/.
[[nodiscard]] HuntOutcome run_hunt(const HuntSpec& spec, const std::atomic<bool>* stop,
                                   const std::function<void(const HuntProgress&)>& progress);

[[nodiscard]] std::string hunt_markdown(const HuntSpec& spec, const HuntOutcome& outcome);
[[nodiscard]] nlohmann::json hunt_json(const HuntSpec& spec, const HuntOutcome& outcome);

}  // namespace overtake::app
