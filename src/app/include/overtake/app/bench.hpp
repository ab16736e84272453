#pragma once
// `overtake bench`: every combination of policies x traffic profiles x seeds, in parallel,
// each run independent and deterministic; results kept run by run (runs.jsonl), summarised
// per policy and profile (summary.csv, summary.md). Shards split a sweep across machines;
// `merge` joins them into the same summary as one unsharded run.

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

/// What to run.
struct BenchSpec {
  std::vector<std::string> policies;
  std::vector<std::string> traffic;
  std::vector<std::uint64_t> seeds;
  double minutes = 30.0;
  std::optional<std::filesystem::path> map;
  std::optional<std::filesystem::path> config;
  int steps_per_call = 0;
  int jobs = 1;
  std::filesystem::path out = "bench-out";
  int shard_index = 1;  ///< 1-based
  int shard_count = 1;
  bool resume = false;
  /// After the bench, run again with a replay recorded the N runs with most incidents (ties:
  /// lower seed first), into out/replays/<policy>-<traffic>-seed<N>.otr.
  int record_worst = 0;
  /// The planners `policies` are looked up in (plugins, Python planners, planner programs);
  /// null: the built-in policies only.
  std::shared_ptr<const PlannerCatalog> planners;
};

/// One run of the sweep; `index` is its place in the full (unsharded) order.
struct BenchCombo {
  std::size_t index = 0;
  std::string policy;
  std::string traffic;
  std::uint64_t seed = 0;
};

/// Parses "1-20", "3", "1,4,9", "1-5,10-12". Throws UsageError naming --seeds.
[[nodiscard]] std::vector<std::uint64_t> parse_seed_list(const std::string& text);
/// Parses "I/N" (1 <= I <= N). Throws UsageError naming --shard.
[[nodiscard]] std::pair<int, int> parse_shard(const std::string& text);
/// Every combination in the fixed order policy, traffic, seed.
[[nodiscard]] std::vector<BenchCombo> bench_combinations(const BenchSpec& spec);

/// Progress of a bench: runs done of total, simulated metres so far, wall seconds elapsed.
struct BenchProgress {
  std::size_t done = 0;
  std::size_t total = 0;
  double simulated_m = 0.0;
  double simulated_s = 0.0;
  double wall_s = 0.0;
};

/// What a bench produced.
struct BenchOutcome {
  std::size_t runs_done = 0;  ///< runs in runs.jsonl (including resumed ones)
  std::size_t runs_new = 0;   ///< runs made by this call
  bool interrupted = false;
  double wall_s = 0.0;
  double simulated_s = 0.0;                    ///< simulated by this call
  std::string summary_markdown;                ///< also written to summary.md
  std::vector<std::filesystem::path> replays;  ///< recorded by record_worst (merge: copied)
};

/// Checks everything before any run starts (UsageError / ConfigError / MapError), then runs
/// the spec's shard on `jobs` threads, writing out/runs.jsonl as runs finish (so an
/// interrupted bench keeps every finished run) and, at the end, runs.jsonl in sweep order,
/// summary.csv, summary.md and bench.json. `stop` (may be null) is polled: when set, runs in
/// progress are abandoned and the finished ones kept.
[[nodiscard]] BenchOutcome run_bench(const BenchSpec& spec, const std::atomic<bool>* stop,
                                     const std::function<void(const BenchProgress&)>& progress);

/// Joins the outputs of shards of one sweep into `out` (runs.jsonl, summaries), and copies
/// the replays the shards recorded (replays/*.otr, `--record-worst`) into out/replays/
/// (listed in `replays`). Throws UsageError when the directories come from different
/// configurations or a run is missing or doubled.
[[nodiscard]] BenchOutcome merge_bench(const std::vector<std::filesystem::path>& dirs,
                                       const std::filesystem::path& out);

/// The runs of a bench output folder (runs.jsonl), in sweep order; unreadable lines are
/// dropped.
[[nodiscard]] std::vector<nlohmann::json> load_bench_runs(const std::filesystem::path& dir);

/// The summary rows (one per policy and traffic profile, in sweep order) of a set of runs.
[[nodiscard]] nlohmann::json summarize_bench(const std::vector<nlohmann::json>& runs,
                                             const std::vector<std::string>& policies,
                                             const std::vector<std::string>& traffic);
[[nodiscard]] std::string summary_csv(const nlohmann::json& rows);
[[nodiscard]] std::string summary_markdown(const nlohmann::json& rows);

}  // namespace overtake::app
