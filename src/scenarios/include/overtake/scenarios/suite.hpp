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
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/planners/catalog.hpp"
#include "overtake/sim/scenario.hpp"
#include "overtake/sim/scorecard.hpp"

namespace overtake::scenarios {

/// The file names a suite writes into its --out.
inline constexpr const char* kSuiteTableFile = "suite.md";
inline constexpr const char* kSuiteVerdictsFile = "suite.json";
/// The first line of every table a suite writes.
inline constexpr std::string_view kSuiteTableHeader =
    "| scenario | policy | result | incidents | collisions (at fault) | distance m | why |";

/// What the ego did that a scenario's expectations read, beyond the report.
struct ScenarioTrace {
  double start_s = 0.0;  ///< the run's time at its first frame
  /// When the ego was first in each lane (its d within the lane), from the start; unset: never.
  std::vector<std::optional<double>> lane_reached_s;
  /// The distance driven by the end of the lead-in (not judged; 0 without one).
  double lead_in_distance_m = 0.0;
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
  double distance_m = 0.0;  ///< in the judged part
  double duration_s = 0.0;  ///< of the whole run
  std::string replay;       ///< of a failed run, when the suite had an --out
  /// A cut scenario's warm-up, played to a planner from outside: "in step after N of M cycles",
  /// or "NOT IN STEP ..." (its result is then not the recorded run's); empty when none was.
  std::string warm_up;
};

/// The expectations of `scenario` checked against a run of it (the judged part starts
/// `cut->lead_in_s` after its start; a run that ends within the lead-in fails). Empty when it
/// passes.
[[nodiscard]] std::vector<std::string> judge_scenario(const sim::Scenario& scenario,
                                                      const sim::RunReport& report,
                                                      const ScenarioTrace& trace);

/// The incidents of the judged part of a run (after the lead-in).
[[nodiscard]] std::vector<sim::Incident> judged_incidents(const sim::Scenario& scenario,
                                                          const sim::RunReport& report,
                                                          const ScenarioTrace& trace);
/// The collisions of the judged part, as contacts (one per car touched, however long).
[[nodiscard]] std::vector<sim::Incident> judged_contacts(const sim::Scenario& scenario,
                                                         const sim::RunReport& report,
                                                         const ScenarioTrace& trace);

/// The distance the ego drove in the judged part of a run (after the lead-in), in metres.
[[nodiscard]] double judged_distance_m(const sim::RunReport& report, const ScenarioTrace& trace);

struct SuiteOutcome {
  std::vector<ScenarioVerdict> verdicts;  ///< file order, then policy order
  std::size_t passed = 0;
  std::size_t failed = 0;
  bool interrupted = false;
  double wall_s = 0.0;
  /// *.json files of the folder that are not scenarios: a suite's own verdicts (suite.json).
  std::vector<std::string> skipped;
  /// Outputs (suite.json, suite.md) that could not be written, each naming the file; the
  /// verdicts are still returned.
  std::vector<std::string> write_errors;
};

/// The *.json entries of a suite's folder, in name order (not recursive), and the suite
/// verdicts among them that are skipped.
struct ScenarioFolder {
  std::vector<std::filesystem::path> files;
  std::vector<std::string> skipped;  ///< a suite's own suite.json: not a scenario
};
/// Lists a scenarios folder. Throws UsageError when it cannot be listed or holds no *.json.
[[nodiscard]] ScenarioFolder list_scenario_folder(const std::filesystem::path& dir);
/// Why `file` cannot be read as a scenario (a folder, not a regular file, a dangling link, a
/// loop of links), or empty when it can be tried.
[[nodiscard]] std::string unreadable_scenario(const std::filesystem::path& file);
/// Whether `file` is a suite's verdicts / a suite's table, as run_suite writes them.
[[nodiscard]] bool is_suite_verdicts(const std::filesystem::path& file);
[[nodiscard]] bool is_suite_table(const std::filesystem::path& file);

/// The pass/fail table (markdown): one row a verdict, its cells escaped.
[[nodiscard]] std::string suite_table(const SuiteOutcome& outcome);
/// Every verdict as JSON.
[[nodiscard]] nlohmann::json suite_json(const SuiteOutcome& outcome);

}  // namespace overtake::scenarios
