#pragma once
// `overtake bench --slurm TASKS` and `overtake hunt --slurm TASKS`: a command as a Slurm job
// array (docs/cluster.md). Task I runs shard I of TASKS into OUT/shards/shard-I; overtake
// follows the tasks (squeue, then scontrol for how each ended), submits again those that
// failed or were cancelled, and merges the shards into OUT when all are done: the same
// results as the command run here.

#include <atomic>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "overtake/base/io.hpp"
#include "overtake/planners/catalog.hpp"

namespace overtake::planners {
class PlannerCatalog;
}  // namespace overtake::planners

namespace overtake::cluster {

/// How the array is submitted and followed (the `--slurm*` flags).
struct SlurmOptions {
  int tasks = 0;                            ///< array size (0: the bench runs here)
  std::string partition;                    ///< sbatch --partition; empty: the default one
  std::string time_limit;                   ///< sbatch --time per task; empty: the partition's
  int cpus_per_task = 1;                    ///< sbatch --cpus-per-task, and each task's --jobs
  std::vector<std::string> sbatch_options;  ///< more sbatch options, as given
  int retries = 2;           ///< submissions of a task after its first, per invocation
  bool submit_only = false;  ///< submit, print how to follow, and return
  double poll_s = 10.0;      ///< between two looks at the queue
};

/// Planner programs in Slurm tasks: what this machine says about namespaces, before anything
/// is submitted (UsageError for `--planner-network isolated` where they cannot be had).
void check_programs_for_slurm(const planners::PlannerCatalog& planners, const std::string& network);

/// Throws UsageError naming the flag when an option is out of range.
void validate_slurm_options(const SlurmOptions& options, std::size_t runs);

/// What a shard folder holds, as the follower sees it.
struct SlurmShardState {
  bool finished = false;  ///< everything its task had to do is there
  std::string so_far;     ///< what is there, for messages ("1 of 4 runs")
};

/// A command (`bench`, `hunt`) to run as an array of shards.
struct SlurmArray {
  std::string command = "bench";  ///< the overtake subcommand each task runs
  std::filesystem::path out;      ///< absolute: the shards, the script, then the merged result
  std::filesystem::path binary;   ///< absolute path of overtake (every node must see it)
  std::filesystem::path workdir;  ///< absolute: the tasks run there (relative paths in the
                                  ///< arguments are read from it)
  /// The command's flags as each task runs them, without --out, --jobs, --shard, --quiet,
  /// --resume, --html and the --slurm flags.
  std::vector<std::string> args;
  /// Flags each task adds after its --shard, --out and --jobs (e.g. --resume --quiet).
  std::vector<std::string> task_flags;
  std::size_t runs = 0;  ///< runs to share out (a task needs at least one)
  bool resume = false;   ///< follow an array submitted before (OUT/slurm/state.json)
  bool quiet = false;    ///< no progress line or summary
  /// Task I's shard (its folder), once its task has left the queue.
  std::function<SlurmShardState(const std::filesystem::path& shard, int task)> shard_state;
  /// What all shards hold so far, for the progress line ("140/280 runs").
  std::function<std::string(const std::vector<std::filesystem::path>& shards)> progress;
  /// Merges the finished shards into `out` and says so; returns the exit status.
  std::function<int(const std::vector<std::filesystem::path>& shards, double wall_s,
                    int resubmitted)>
      merge;
};

/// An array of `command` as run from here: this binary, this folder, `out` made absolute.
[[nodiscard]] SlurmArray slurm_array_here(const std::string& command,
                                          const std::filesystem::path& out);

/// The folder of task I's shard, and of the script, state and logs.
[[nodiscard]] std::filesystem::path slurm_shard_dir(const std::filesystem::path& out, int task);
[[nodiscard]] std::filesystem::path slurm_dir(const std::filesystem::path& out);

/// Submits (or, with `resume`, takes up) the array, follows it until every task is done,
/// submitting again those that end unfinished (at most `retries` times each), and merges
/// the shards. Prints progress and what happened to stderr. Returns the exit status: the
/// merge's; 1 when a task failed every time (the finished shards are kept: --resume submits
/// it again); 130 when stopped by `stop` (the tasks go on in Slurm: --resume follows them
/// again); 0 after --slurm-submit-only. Throws UsageError when OUT holds something else,
/// std::runtime_error when sbatch refuses the array.
[[nodiscard]] int run_slurm_array(const SlurmArray& array, const SlurmOptions& options,
                                  const std::atomic<bool>* stop);

// ----- the pieces, for tests ---------------------------------------------------------------

/// The batch script of the array.
[[nodiscard]] std::string slurm_batch_script(const SlurmArray& array, const SlurmOptions& options);

/// The job id in `sbatch --parsable`'s answer ("123" or "123;cluster"); throws
/// std::runtime_error quoting the answer when it holds none.
[[nodiscard]] std::string parse_sbatch_job_id(std::string_view answer);

/// One array task as `squeue --array --noheader --format='%i %T'` lists it.
struct SlurmQueued {
  std::string job;  ///< the array's job id
  int task = 0;
  std::string state;  ///< PENDING, RUNNING, COMPLETING, ...
};
/// Every line of that listing naming one task ("123_4 RUNNING"); other lines (other jobs,
/// a pending range "123_[5-8]") are skipped, so the caller asks with --array.
[[nodiscard]] std::vector<SlurmQueued> parse_squeue_tasks(std::string_view listing);

/// How a job ended, from `scontrol show job ID_TASK`.
struct SlurmJobEnd {
  std::string state;      ///< JobState: COMPLETED, FAILED, CANCELLED, TIMEOUT, NODE_FAIL, ...
  std::string exit_code;  ///< ExitCode "status:signal"
  std::string reason;     ///< Reason, when not None
};
[[nodiscard]] SlurmJobEnd parse_scontrol_job(std::string_view text);

/// Runs in shard `task` (1-based) of `tasks` for a sweep of `runs`.
[[nodiscard]] std::size_t slurm_shard_runs(std::size_t runs, int tasks, int task);

}  // namespace overtake::cluster
