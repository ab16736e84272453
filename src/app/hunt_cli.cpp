#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/app/cli.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/batch/hunt.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/batch/progress.hpp"
#include "overtake/cluster/arrays.hpp"
#include "overtake/cluster/slurm.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/config.hpp"
#include "overtake/scenarios/cut.hpp"

namespace overtake::app {

using base::fixed_text;
using base::kExitOk;
using base::read_file;
using base::split_list;
using base::UsageError;
using batch::check_hunt_spec;
using batch::HuntOutcome;
using batch::HuntProgress;
using batch::HuntSpec;
using batch::HuntTarget;
using batch::merge_hunt;
using batch::parse_shard;
using batch::run_hunt;
using batch::Shard;
using cluster::check_programs_for_slurm;
using cluster::hunt_array;
using cluster::run_slurm_array;
using cluster::SlurmArray;
using cluster::SlurmOptions;
using planners::catalog_from_flags;
using planners::chosen_policy;
using planners::PlannerFlags;
using planners::PlannerFlagSet;
using scenarios::kDefaultWarmUpS;
using scenarios::parse_warm_up;
namespace {

using nlohmann::json;

// The flags of `overtake hunt` and `overtake hunt merge`.
struct HuntState {
  HuntSpec spec;
  PlannerFlags planners;
  std::string maps, traffic = "faithful,calm", find = "collisions", config, out = "hunt-out";
  CLI::Option* policy_opt = nullptr;
  bool quiet = false;
  bool resume = false;
  std::string shard;
  SlurmOptions slurm;
  std::vector<std::string> merge_dirs;
  std::string merge_out;
  std::string warm_up = fixed_text(kDefaultWarmUpS, 0);
};

// `overtake hunt merge`.
int run_merge(const HuntState& st) {
  const std::filesystem::path out = st.merge_out;
  (void)merge_hunt(std::vector<std::filesystem::path>(st.merge_dirs.begin(), st.merge_dirs.end()),
                   out);
  std::cout << read_file(out / "hunt.md") << "written: " << st.merge_out
            << "/{hunt.md,hunt.json,replays,scenarios}\n";
  return kExitOk;
}

// Refuses the flags a hunt on Slurm does not take, and --resume without it.
void check_modes(const HuntState& st, bool on_slurm) {
  if (st.resume && !on_slurm) throw UsageError("--resume goes with --slurm TASKS");
  if (on_slurm && !st.shard.empty())
    throw UsageError("--slurm makes the shards itself; --shard is for arrays of your own");
  if (on_slurm && st.spec.force)
    throw UsageError(
        "--force: a hunt on Slurm merges into --out, which must not hold a "
        "hunt; choose another --out");
}

HuntTarget target_of(const std::string& find) {
  if (find == "collisions") return HuntTarget::collisions;
  if (find == "at-fault") return HuntTarget::at_fault;
  if (find == "incidents") return HuntTarget::incidents;
  throw UsageError("--find: '" + find + "' is none of collisions, at-fault, incidents");
}

// --maps: "default" is the built-in track, anything else a map file.
std::vector<std::optional<std::filesystem::path>> maps_of(const std::string& list) {
  std::vector<std::optional<std::filesystem::path>> maps;
  std::string cur;
  std::istringstream in(list);
  while (std::getline(in, cur, ',')) {
    if (cur.empty()) continue;
    if (cur == "default") {
      maps.emplace_back(std::nullopt);
    } else {
      if (!std::filesystem::is_regular_file(cur)) {
        throw UsageError("--maps: " + cur + " is not a file");
      }
      maps.emplace_back(cur);
    }
  }
  return maps;
}

// The hunt the flags name.
HuntSpec hunt_spec_of(const HuntState& st) {
  HuntSpec spec = st.spec;
  spec.planners = catalog_from_flags(st.planners);
  spec.policy = chosen_policy(*spec.planners, spec.policy, st.policy_opt->count() > 0);
  spec.target = target_of(st.find);
  if (!st.maps.empty()) spec.maps = maps_of(st.maps);
  spec.traffic = split_list(st.traffic);
  parse_warm_up(st.warm_up, spec.warm_up_s, spec.warm_up_all);
  if (!st.config.empty()) spec.config = st.config;
  spec.out = st.out;
  if (!st.shard.empty()) {
    const Shard shard = parse_shard(st.shard);
    spec.shard_index = shard.index;
    spec.shard_count = shard.count;
  }
  return spec;
}

// `overtake hunt --slurm TASKS`: everything the tasks would refuse is refused here.
int run_on_slurm(const HuntState& st, const CLI::App& cmd, const HuntSpec& spec) {
  check_hunt_spec(spec);
  check_programs_for_slurm(*spec.planners, st.planners.network);
  const SlurmArray array =
      hunt_array(spec, task_arguments(cmd, {"out", "jobs", "resume", "quiet", "shard", "force"}),
                 st.resume, st.quiet);
  const InterruptScope interrupt;
  return run_slurm_array(array, st.slurm, &InterruptScope::flag());
}

// `overtake hunt` here, under Ctrl-C: its table and exit status.
int run_here(const HuntState& st, const HuntSpec& spec) {
  HuntOutcome o;
  {
    base::StatusLine line(!st.quiet);
    const InterruptScope interrupt;
    o = run_hunt(spec, &InterruptScope::flag(),
                 [&](const HuntProgress& p) { line.draw(batch::progress_text(p)); });
  }
  return batch::report_hunt(spec, o, st.quiet);
}

// What the hunt drives: the planner, the budget, the runs' seeds, maps, traffic and length.
void add_run_flags(CLI::App& cmd, HuntState& st) {
  st.policy_opt = cmd.add_option("--policy", st.spec.policy, policy_help())->capture_default_str();
  add_planner_flags(cmd, st.planners, PlannerFlagSet::all);
  cmd.add_option("--failures,-n", st.spec.failures, "Stop after this many failures")
      ->capture_default_str();
  cmd.add_option("--budget-hours", st.spec.budget_hours,
                 "... or after this many simulated hours (more than 0, at most 100000)")
      ->capture_default_str();
  cmd.add_option("--find", st.find,
                 "What counts as a failure: collisions (each contact with a car once, however\n"
                 "long), at-fault (those contacts that were the ego's fault) or incidents (any\n"
                 "of the rubric's; one counted again each second it lasts is one failure)")
      ->capture_default_str();
  cmd.add_option("--first-seed", st.spec.first_seed, "Seeds go up from this one")
      ->check(seed_validator())
      ->capture_default_str();
  cmd.add_option("--maps,--map", st.maps,
                 "Comma-separated map files to drive on, each once (\"default\" for the\n"
                 "built-in track; default: the built-in track)");
  cmd.add_option("--traffic", st.traffic, "Comma-separated traffic profiles, each once")
      ->capture_default_str();
  cmd.add_option("--minutes", st.spec.minutes, "Simulated minutes per run")->capture_default_str();
}

// How failures are cut, the parameters and jobs, and where the hunt's results go.
void add_output_flags(CLI::App& cmd, HuntState& st) {
  cmd.add_option("--before", st.spec.before_s,
                 "The cut scenarios start this long before (0-3600 s, as `overtake cut`)")
      ->capture_default_str();
  cmd.add_option("--after", st.spec.after_s, "... and end this long after the failure (0-3600 s)")
      ->capture_default_str();
  cmd.add_option("--warm-up", st.warm_up,
                 "A failure of a planner from outside (a program, a plugin, Python) is cut with\n"
                 "this many seconds of what the planner was told before the scenario, played\n"
                 "to it first so that it comes in step (`all`: from the run's first cycle; 0:\n"
                 "none), as `overtake cut --warm-up`")
      ->capture_default_str();
  cmd.add_option("--config", st.config, "JSON parameter overrides")->check(CLI::ExistingFile);
  cmd.add_option("--jobs,-j", st.spec.jobs, "Runs in parallel (default: all cores)")
      ->capture_default_str();
  cmd.add_option("--out,-o", st.out, "Output folder")->capture_default_str();
  cmd.add_flag("--force", st.spec.force,
               "Write into --out even when it holds a hunt (hunt.json, hunt.md) or files in\n"
               "its replays/ or scenarios/: the new hunt's files replace those of the same names");
  cmd.add_flag("--quiet,-q", st.quiet, "No progress line or table");
  cmd.add_option("--shard", st.shard,
                 "Hunt only slice I of N (e.g. 3/8) of the runs, until this slice has found\n"
                 "--failures; `overtake hunt merge` of all N finds what one hunt would");
}

}  // namespace

Subcommand register_hunt(CLI::App& app) {
  auto st = std::make_shared<HuntState>();
  st->spec.jobs = batch::default_jobs();
  auto* cmd = app.add_subcommand(
      "hunt",
      "Drive one planner over seeds, maps and traffic profiles in parallel until it has failed\n"
      "--failures times or --budget-hours of simulation are spent. For each distinct failure\n"
      "(grouped by kind and situation) it keeps the replay, cuts a scenario with reactive and\n"
      "one with replayed traffic, and prints the command that reproduces it (hunt.md,\n"
      "hunt.json in --out). Ctrl-C keeps what was found (docs/scenarios.md).\n"
      "Exit status: 0; 130 when interrupted; 1 when a run, a replay or a report cannot be\n"
      "made (the reason is printed; what was found is kept in hunt.json); 2 for bad flags.");
  add_run_flags(*cmd, *st);
  add_output_flags(*cmd, *st);
  add_slurm_flags(*cmd, st->slurm, "hunt");
  cmd->add_flag("--resume", st->resume,
                "With --slurm: take up the array submitted into --out before (follow it,\n"
                "submit again what did not finish, merge)");
  auto* merge = cmd->add_subcommand(
      "merge", "Join the folders of the shards of one hunt (--shard I/N) into --out.");
  merge->add_option("dirs", st->merge_dirs, "Shard folders")
      ->required()
      ->check(CLI::ExistingDirectory);
  merge->add_option("--out,-o", st->merge_out, "Folder for the joined hunt")->required();
  return {cmd, [st, cmd, merge] {
            if (merge->parsed()) return run_merge(*st);
            const bool on_slurm = slurm_requested(*cmd);
            check_modes(*st, on_slurm);
            const HuntSpec spec = hunt_spec_of(*st);
            if (on_slurm) return run_on_slurm(*st, *cmd, spec);
            return run_here(*st, spec);
          }};
}

}  // namespace overtake::app
