#include <CLI/CLI.hpp>
#include <algorithm>
#include <set>
#include <string>
#include <vector>

#include "overtake/app/cli.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/cluster/slurm.hpp"

namespace overtake::app {

using base::UsageError;
using cluster::SlurmOptions;

namespace {

const std::vector<std::string> kSlurmFlags = {"slurm-partition",  "slurm-time",    "slurm-cpus",
                                              "slurm-opt",        "slurm-retries", "slurm-poll",
                                              "slurm-submit-only"};

}  // namespace

void add_slurm_flags(CLI::App& cmd, SlurmOptions& o, const std::string& what,
                     const std::string& merge) {
  cmd.add_option(
      "--slurm", o.tasks,
      "Run the " + what +
          " as a Slurm job array of this many tasks (docs/cluster.md): writes the\n"
          "batch script into --out/slurm/, submits it with sbatch, follows the tasks (squeue),\n"
          "submits again those that fail or are cancelled, and merges their shards into --out\n"
          "(the same results as here). The tasks run this binary with these flags in this\n"
          "folder: every node must see them. Ctrl-C stops following only; --resume follows\n"
          "again");
  cmd.add_option("--slurm-partition", o.partition, "sbatch --partition of the tasks");
  cmd.add_option("--slurm-time", o.time_limit,
                 "sbatch --time of each task (e.g. 2:00:00); default: the partition's");
  cmd.add_option("--slurm-cpus", o.cpus_per_task,
                 "CPUs per task (sbatch --cpus-per-task); each task runs that many at a time")
      ->capture_default_str();
  cmd.add_option("--slurm-opt", o.sbatch_options,
                 "One more sbatch option for the tasks, e.g. --slurm-opt=--account=NAME\n"
                 "(repeat for more)");
  cmd.add_option("--slurm-retries", o.retries,
                 "Submit a task that fails or is cancelled again at most this many times")
      ->capture_default_str();
  cmd.add_option("--slurm-poll", o.poll_s, "Seconds between two looks at the queue")
      ->capture_default_str();
  cmd.add_flag("--slurm-submit-only", o.submit_only,
               "Submit and return (a login node that may not keep a process): follow later\n"
               "with --resume instead, or run `" +
                   (merge.empty() ? what + " merge" : merge) + "` once every task is done");
}

bool slurm_requested(const CLI::App& cmd) {
  if (cmd.count("--slurm") > 0) return true;
  for (const auto& f : kSlurmFlags) {
    if (cmd.count("--" + f) > 0) throw UsageError("--" + f + " goes with --slurm TASKS");
  }
  return false;
}

std::vector<std::string> task_arguments(const CLI::App& cmd,
                                        const std::set<std::string>& leave_out) {
  std::vector<std::string> args;
  for (const CLI::Option* opt : cmd.get_options()) {
    if (opt->count() == 0 || opt->get_lnames().empty()) continue;
    const std::string& name = opt->get_lnames().front();
    if (leave_out.count(name) > 0 || name == "slurm" ||
        std::find(kSlurmFlags.begin(), kSlurmFlags.end(), name) != kSlurmFlags.end())
      continue;
    if (opt->get_type_size() == 0) {
      for (std::size_t i = 0; i < opt->count(); ++i) args.push_back("--" + name);
    } else {
      for (const auto& value : opt->results()) args.push_back("--" + name + "=" + value);
    }
  }
  return args;
}

}  // namespace overtake::app
