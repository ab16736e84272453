#pragma once
// Scenario suites (`overtake bench --scenarios DIR`): every scenario file of a folder
// (scripted, or cut from a run with reactive or replayed traffic) driven by every policy, and
// each judged by what the scenario expects (sim::ScenarioExpect): a pass/fail table, and exit
// status 1 when any fails, so that a planner's CI can run it.

#include <atomic>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/app/planners.hpp"
#include "overtake/sim/scenario.hpp"
#include "overtake/sim/scorecard.hpp"

namespace overtake::app {

struct SuiteSpec {
  std::filesystem::path dir;  ///< its *.json files, in name order (not recursive)
  std::vector<std::string> policies;
  std::shared_ptr<const PlannerCatalog> planners;  ///< null: built-in policies only
  std::optional<std::filesystem::path> config;
  /// The map of scenarios that do not name theirs (cut scenarios do).
  std::optional<std::filesystem::path> map;
  int jobs = 1;
  /// When set: the table and every verdict are written here (suite.md, suite.json), and a
  /// replay of each failed run (replays/).
  std::optional<std::filesystem::path> out;
};

/// What the ego did that a scenario's expectations read, beyond the report.
struct ScenarioTrace {
  double start_s = 0.0;  ///< the run's time at its first frame
  /// When the ego was first in each lane (its d within the lane), from the start; unset: never.
  std::vector<std::optional<double>> lane_reached_s;
};

/// One scenario driven by one policy, judged.
struct ScenarioVerdict {
  std::string file;  ///< relative to the suite's folder
  std::string name;
  std::string policy;
  bool pass = false;
  /// Why it failed (each expectation not met, or the run failing), or why it could not run.
  std::vector<std::string> failures;
  int incidents = 0;  ///< in the judged part
  int collisions = 0;
  int at_fault_collisions = 0;
  double distance_m = 0.0;
  double duration_s = 0.0;
  std::string replay;  ///< of a failed run, when the suite had an --out
};

/// The expectations of `scenario` checked against a run of it (the judged part starts
/// `cut->lead_in_s` after its start). Empty when it passes.
[[nodiscard]] std::vector<std::string> judge_scenario(const sim::Scenario& scenario,
                                                      const sim::RunReport& report,
                                                      const ScenarioTrace& trace);

struct SuiteOutcome {
  std::vector<ScenarioVerdict> verdicts;  ///< file order, then policy order
  std::size_t passed = 0;
  std::size_t failed = 0;
  bool interrupted = false;
  double wall_s = 0.0;
};

/// Runs the suite on `jobs` threads. Throws UsageError for bad flags and an empty folder; a
/// scenario file that cannot be read fails its rows (the others still run). `stop` (may be
/// null) ends it early, keeping the verdicts reached.
[[nodiscard]] SuiteOutcome run_suite(
    const SuiteSpec& spec, const std::atomic<bool>* stop,
    const std::function<void(std::size_t done, std::size_t total)>& progress);

/// The pass/fail table (markdown).
[[nodiscard]] std::string suite_table(const SuiteOutcome& outcome);
/// Every verdict as JSON.
[[nodiscard]] nlohmann::json suite_json(const SuiteOutcome& outcome);

}  // namespace overtake::app
