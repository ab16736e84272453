#pragma once
// The commands that run as Slurm arrays (bench, hunt, risk, tune's benches): for each, what a
// task runs, when its shard is finished, what the shards hold so far and how they merge.

#include <atomic>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "overtake/batch/bench.hpp"
#include "overtake/batch/hunt.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/cluster/slurm.hpp"

namespace overtake::cluster {

/// Told of a bench's merge (the outcome, the folder merged into, the shards, the wall time,
/// the tasks submitted again); returns the exit status.
using BenchMerged =
    std::function<int(const batch::BenchOutcome& outcome, const std::filesystem::path& out,
                      std::size_t shards, double wall_s, int resubmitted)>;

/// A bench as a Slurm array of `tasks`: task I runs shard I with --resume; a shard is finished
/// when it holds every run of its slice and its summary; the shards merge as `bench merge`,
/// then `merged` is told. `args`: the bench's flags as each task runs them. Throws
/// UsageError when --out holds a bench already, or what the merge would refuse.
[[nodiscard]] SlurmArray bench_array(const batch::BenchSpec& spec, int tasks,
                                     std::vector<std::string> args, BenchMerged merged);

/// A hunt as a Slurm array: task I hunts slice I (starting over when submitted again: the
/// same runs find the same failures); a shard is finished when its hunt.json says so; the
/// shards merge as `hunt merge`, which prints the hunt's table unless `quiet`.
[[nodiscard]] SlurmArray hunt_array(const batch::HuntSpec& spec, std::vector<std::string> args,
                                    bool resume, bool quiet);

/// `overtake risk --slurm TASKS`: task I runs shard I of the planned runs with --resume (so a
/// task submitted again goes on with its runs); a shard is finished when its risk.json says
/// so; the shards merge as --merge does, with the stopping rules of `spec`, and are reported
/// as batch::report_risk reports (to `json_out` too).
[[nodiscard]] SlurmArray risk_array(const batch::RiskSpec& spec, int tasks,
                                    std::vector<std::string> args,
                                    const std::filesystem::path& json_out, bool quiet,
                                    const std::atomic<bool>* stop);

/// The flags a bench task runs `bench` with: its sweep, map and config, and its planners as
/// the spec holds them (a program's command with a trial's values in it), then
/// `planner_flags` (the timeouts, network, ... given to the command that made it).
[[nodiscard]] std::vector<std::string> bench_task_flags(
    const batch::BenchSpec& bench, const std::vector<std::string>& planner_flags);

/// What runs each bench of `tune --slurm`: the bench as a Slurm array, merged into its
/// folder. A bench already merged (a trial cut off after its merge) is not run again; one
/// whose array was submitted before (cut off by Ctrl-C) is followed again, not submitted
/// again. Returns true when stopped; throws std::runtime_error when the array did not finish.
[[nodiscard]] std::function<bool(const batch::BenchSpec&, const std::atomic<bool>*)>
tune_bench_runner(const SlurmOptions& options, std::vector<std::string> planner_flags);

}  // namespace overtake::cluster
