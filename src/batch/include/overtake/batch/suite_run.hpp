#pragma once
// A scenario suite (`bench --scenarios DIR`): every scenario of a folder driven by every
// policy, each judged against what its file expects (scenarios::judge_scenario).

#include <atomic>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "overtake/planners/catalog.hpp"
#include "overtake/scenarios/suite.hpp"

namespace overtake::batch {

struct SuiteSpec {
  std::filesystem::path dir;  ///< its *.json files, in name order (not recursive)
  std::vector<std::string> policies;
  std::shared_ptr<const planners::PlannerCatalog> planners;  ///< null: built-in policies only
  std::optional<std::filesystem::path> config;
  /// The map of scenarios that do not name theirs (cut scenarios do).
  std::optional<std::filesystem::path> map;
  int jobs = 1;
  /// When set: the table and every verdict are written here (suite.md, suite.json), and a
  /// replay of each failed run (replays/). Not the scenarios folder itself; a suite.md or
  /// suite.json already there must be a suite's own (it is replaced).
  std::optional<std::filesystem::path> out;
};

/// Runs the suite on `jobs` threads. Throws UsageError for bad flags, an empty folder, and an
/// --out that is the scenarios folder or holds a suite.md or suite.json that no suite wrote.
/// A scenario file that cannot be read (a folder, a loop of links, bad JSON) fails its rows
/// and the others still run. `stop` (may be null) ends it early, keeping the verdicts
/// reached.
[[nodiscard]] scenarios::SuiteOutcome run_suite(
    const SuiteSpec& spec, const std::atomic<bool>* stop,
    const std::function<void(std::size_t done, std::size_t total)>& progress);

/// What `bench --scenarios` prints (the skipped files, the table, where it was written) and
/// the exit status: 1 when a scenario failed or a file could not be written, 130 when
/// interrupted, else 0.
[[nodiscard]] int report_suite(const SuiteSpec& suite, const scenarios::SuiteOutcome& outcome,
                               bool quiet);

}  // namespace overtake::batch
