#pragma once
// `overtake bench`: every combination of policies x traffic profiles x seeds, in parallel,
// each run independent and deterministic; results kept run by run (runs.jsonl), summarised
// per policy and profile with intervals, and paired between policies (summary.md,
// summary.csv, summary.json, pairs.csv; the figures are overtake::eval's). Shards split a
// sweep across machines;
// `merge` joins them into the same summary as one unsharded run.

#include <array>
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
#include "overtake/eval/compare.hpp"
#include "overtake/planners/catalog.hpp"

namespace overtake::batch {

/// The files of a bench's output folder: every finished run, and what was run.
inline constexpr const char* kBenchRunsFile = "runs.jsonl";
inline constexpr const char* kBenchManifestFile = "bench.json";
/// The summaries a bench writes beside them (overtake::eval's figures).
inline constexpr const char* kBenchSummaryMarkdownFile = "summary.md";
inline constexpr const char* kBenchSummaryCsvFile = "summary.csv";
inline constexpr const char* kBenchSummaryJsonFile = "summary.json";
inline constexpr const char* kBenchPairsFile = "pairs.csv";
/// Every file a bench writes into its folder, in the order the command line names them.
inline constexpr std::array<const char*, 6> kBenchFiles = {
    kBenchRunsFile,        kBenchSummaryMarkdownFile, kBenchSummaryCsvFile,
    kBenchSummaryJsonFile, kBenchPairsFile,           kBenchManifestFile};
/// The folder of planner programs' output, one file per run (the bench's runs, and as
/// <run>.recorded.log their re-runs with a replay); replays go into kReplaysFolder.
inline constexpr const char* kBenchLogsFolder = "logs";
/// The most runs one bench holds: a million 30-minute runs are some 20 days of one core's time.
inline constexpr std::size_t kMaxBenchRuns = 1'000'000;

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
  [[nodiscard]] Shard shard() const { return {shard_index, shard_count}; }
  bool resume = false;
  /// Write into `out` even when it holds files of the names a bench writes (summary.md,
  /// summary.csv, summary.json, pairs.csv, replays/, logs/) that no bench wrote there (it has
  /// no bench.json or runs.jsonl); a bench's own results are never replaced (--resume
  /// continues them).
  bool force = false;
  /// After the bench, run again with a replay recorded the N runs with most incidents (ties:
  /// lower seed first), into out/replays/<policy>-<traffic>-seed<N>.otr (a planner program's
  /// output into logs/, as <policy>-<traffic>-seed<N>.recorded.log beside its bench run's).
  int record_worst = 0;
  /// The planners `policies` are looked up in (plugins, Python planners, planner programs);
  /// null: the built-in policies only.
  std::shared_ptr<const planners::PlannerCatalog> planners;
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
/// Every combination in the fixed order policy, traffic, seed. Throws UsageError when they are
/// more than kMaxBenchRuns.
[[nodiscard]] std::vector<BenchCombo> bench_combinations(const BenchSpec& spec);

/// Progress of a bench: runs done of total, simulated metres so far, wall seconds elapsed.
struct BenchProgress {
  std::size_t done = 0;
  std::size_t total = 0;
  double simulated_m = 0.0;
  double simulated_s = 0.0;
  double wall_s = 0.0;
};

/// A bench's evaluation: the summary rows (one per policy and traffic profile, in sweep
/// order, with intervals) and the paired comparisons of every two policies.
struct BenchSummary {
  nlohmann::json rows;
  nlohmann::json pairs;
};

/// What a bench produced.
struct BenchOutcome {
  std::size_t runs_done = 0;  ///< runs in runs.jsonl (including resumed ones)
  std::size_t runs_new = 0;   ///< runs made by this call
  bool interrupted = false;
  double wall_s = 0.0;
  double simulated_s = 0.0;                    ///< simulated by this call
  std::string summary_markdown;                ///< also written to summary.md
  BenchSummary summary;                        ///< also written to summary.json, .csv, pairs.csv
  std::vector<std::filesystem::path> replays;  ///< recorded by record_worst (merge: copied)
};

/// Refuses an output folder that holds no bench (no runs.jsonl, no bench.json) but files of the
/// names a bench writes (summary.md, summary.csv, summary.json, pairs.csv) or a folder it
/// writes into (replays/, logs/) that is not empty: no bench wrote them, and a bench would
/// replace them. Throws UsageError starting with `who`, naming the file, and ending with
/// `remedy`; nothing when `force`.
void check_bench_out(const std::filesystem::path& out, bool force, const std::string& who,
                     const std::string& remedy);

/// Checks everything run_bench checks before its first run (UsageError / ConfigError /
/// MapError), and runs nothing: for a bench that runs elsewhere (`--slurm`).
void check_bench_spec(const BenchSpec& spec);

/// Checks everything before any run starts (UsageError / ConfigError / MapError), then runs
/// the spec's shard on `jobs` threads, writing out/runs.jsonl as runs finish (so an
/// interrupted bench keeps every finished run) and, at the end, runs.jsonl in sweep order,
/// summary.md, summary.csv, summary.json, pairs.csv and bench.json. `stop` (may be null) is polled:
/// when set, runs in progress are abandoned and the finished ones kept.
[[nodiscard]] BenchOutcome run_bench(const BenchSpec& spec, const std::atomic<bool>* stop,
                                     const std::function<void(const BenchProgress&)>& progress);

/// Joins the outputs of shards of one sweep into `out` (runs.jsonl, summaries), and copies
/// the replays the shards recorded (replays/*.otr, `--record-worst`) into out/replays/
/// (listed in `replays`). Throws UsageError when the directories come from different
/// configurations or a run is missing or doubled.
[[nodiscard]] BenchOutcome merge_bench(const std::vector<std::filesystem::path>& dirs,
                                       const std::filesystem::path& out);

/// A row of runs.jsonl and the line it is on (from 1).
struct BenchRow {
  nlohmann::json run;
  std::size_t line = 0;
};

/// What a runs.jsonl holds: its rows in file order, and the line a kill cut off at its end
/// (the last line, without its newline and not a whole run; 0: none).
struct BenchRowsFile {
  std::vector<BenchRow> rows;
  std::size_t cut_off_line = 0;
};

/// Reads runs.jsonl: each line a run (a JSON object with a run number, `index`). Throws
/// UsageError listing FILE:LINE and what is wrong for every line that is not one (not JSON, a
/// number out of range, no run number), but for a last line cut off by a kill when
/// `allow_cut_off_end` (`bench --resume` drops it and runs that run again).
[[nodiscard]] BenchRowsFile read_bench_rows(const std::filesystem::path& file,
                                            bool allow_cut_off_end);

/// The build whose runs a bench holds: its revision (build_revision()) and where it was
/// read, for messages ("this overtake", a bench.json, a line of runs.jsonl).
struct BenchBuild {
  std::string revision;
  std::string where;
};

/// The check `bench --resume`, `bench merge` and `compare` make of a bench's rows (read from
/// `file`) against its manifest (bench.json): each row is the run its number names in the
/// manifest's sweep and shard (policy, traffic, seed), there once; driven on the manifest's
/// map, for its minutes, with its parameters; and by one build: `build` when set, else the
/// manifest's revision (or, in a bench.json older than revisions, the first row's), which
/// `build` is then set to. Fields a row of an older build lacks are not checked. Throws
/// UsageError starting with `who` ("--resume: "), naming the file, the line and the run, and
/// ending with `hint`.
void check_bench_rows(const std::vector<BenchRow>& rows, const nlohmann::json& manifest,
                      const std::filesystem::path& file, std::optional<BenchBuild>& build,
                      const std::string& who, const std::string& hint);

/// The runs of a bench output folder (runs.jsonl), in sweep order; a last line cut off by a
/// kill is dropped (counted in `dropped` when given), any other line that is not a run is
/// refused (read_bench_rows).
[[nodiscard]] std::vector<nlohmann::json> load_bench_runs(const std::filesystem::path& dir,
                                                          std::size_t* dropped = nullptr);

/// The evaluation of a set of runs (rows of runs.jsonl; sorted into sweep order here). Throws
/// UsageError naming `where` and the key when a row lacks what the summary needs.
[[nodiscard]] BenchSummary summarize_bench(std::vector<nlohmann::json> runs,
                                           const std::vector<std::string>& policies,
                                           const std::vector<std::string>& traffic,
                                           const std::string& where);

/// A bench output folder read for `overtake compare`: its manifest and runs. Throws
/// std::runtime_error naming the folder when it holds no bench (no bench.json or runs.jsonl),
/// and naming the file and line when a line is not a run or a row is not one the bench can
/// vouch for (check_bench_rows: a duplicate, another sweep's run, another map, length or
/// build); `notes` gets what the comparison should say (an unfinished bench).
[[nodiscard]] eval::BenchData load_bench_for_compare(const std::filesystem::path& dir,
                                                     std::vector<std::string>& notes);

/// `overtake compare`: the benches in two output folders compared (eval::compare_benches),
/// with the notes of loading them added to the result's "notes".
[[nodiscard]] nlohmann::json compare_bench_folders(const std::filesystem::path& base,
                                                   const std::filesystem::path& candidate,
                                                   const eval::CompareOptions& options);
/// What `overtake compare` is asked (its arguments and flags, as given).
struct CompareRequest {
  std::filesystem::path before, after;  ///< the base's and the candidate's --out folders
  std::vector<std::string> pairs;       ///< --pair OLD=NEW, each once
  std::string figures;                  ///< --figures, comma-separated; empty: all
  std::filesystem::path json;           ///< --json; empty: none
  bool fail_if_worse = false;
  bool quiet = false;
};

/// `overtake compare` whole: two bench folders compared (compare_bench_folders) or two risk
/// estimates (compare_risk_folders), printed unless quiet and written to `json`. Returns the
/// exit status: 0; with fail_if_worse 1 when a figure is worse (a rate higher), 2 when a
/// comparison has too few seeds for a verdict. UsageError for bad flags, a --json that is a
/// bench's own file, or a bench compared with a risk estimate.
[[nodiscard]] int compare_folders(const CompareRequest& request);

/// Parses "OLD=NEW" (a --pair). Throws UsageError naming --pair.
[[nodiscard]] eval::PolicyPair parse_policy_pair(const std::string& text);
/// Parses a comma-separated list of metric names (--figures). Throws UsageError naming them.
[[nodiscard]] std::vector<eval::Metric> parse_metric_list(const std::string& text);

}  // namespace overtake::batch
