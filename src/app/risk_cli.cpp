// `overtake risk`: the rate of a rare event per 100 miles for one planner, by multilevel
// splitting (batch/risk.hpp).

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/app/cli.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/batch/progress.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/cluster/arrays.hpp"
#include "overtake/cluster/slurm.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/config.hpp"

namespace overtake::app {

namespace {

using base::UsageError;

struct RiskState {
  batch::RiskSpec spec;
  planners::PlannerFlags planners;
  CLI::Option* policy_opt = nullptr;
  std::string event = "at-fault";
  std::string map, config, params, out = "risk-out", json, shard;
  std::vector<std::filesystem::path> merge;
  cluster::SlurmOptions slurm;
  bool quiet = false;
};

batch::RiskSpec spec_of(const RiskState& st) {
  batch::RiskSpec spec = st.spec;
  spec.planners = planners::catalog_from_flags(st.planners);
  spec.policy = planners::chosen_policy(*spec.planners, spec.policy, st.policy_opt->count() > 0);
  spec.event = batch::parse_risk_event(st.event);
  if (!st.map.empty() && st.map != "default") spec.map = st.map;
  if (!st.config.empty()) spec.config = st.config;
  if (!st.params.empty()) spec.params = st.params;
  spec.out = st.out;
  if (!st.shard.empty()) spec.shard = batch::parse_shard(st.shard);
  return spec;
}

// What an estimate prints and writes beside --out (--json); its exit status.
int report(const RiskState& st, const batch::RiskSpec& spec, const batch::RiskOutcome& o) {
  return batch::report_risk(spec, o, st.json, st.quiet, "");
}

int run_risk_here(const RiskState& st) {
  const batch::RiskSpec spec = spec_of(st);
  batch::check_risk_spec(spec);
  batch::RiskOutcome o;
  {
    base::StatusLine line(!st.quiet);
    const InterruptScope interrupt;
    o = batch::run_risk(spec, &InterruptScope::flag(),
                        [&](const batch::RiskProgress& p) { line.draw(batch::progress_text(p)); });
  }
  return report(st, spec, o);
}

// --merge: the shards' folders into --out, as one run here with the same flags would write it.
int merge_here(const RiskState& st) {
  const batch::RiskSpec spec = spec_of(st);
  const InterruptScope interrupt;
  const batch::RiskOutcome o = batch::merge_risk(spec, st.merge, &InterruptScope::flag());
  return report(st, spec, o);
}

// `overtake risk --slurm TASKS` (cluster::risk_array).
int run_on_slurm(const RiskState& st, const CLI::App& cmd, const batch::RiskSpec& spec) {
  batch::check_risk_spec(spec);
  cluster::check_programs_for_slurm(*spec.planners, st.planners.network);
  const cluster::SlurmArray a = cluster::risk_array(
      spec, st.slurm.tasks,
      task_arguments(cmd, {"out", "jobs", "resume", "quiet", "shard", "json", "scenarios"}),
      st.json, st.quiet, &InterruptScope::flag());
  const InterruptScope interrupt;
  return cluster::run_slurm_array(a, st.slurm, &InterruptScope::flag());
}

// The flags that do not go together, refused before anything runs.
void check_modes(const RiskState& st, bool on_slurm) {
  if (!st.merge.empty()) {
    if (on_slurm) throw UsageError("--merge joins shards here: not with --slurm");
    if (!st.shard.empty()) throw UsageError("--merge writes the whole estimate: not with --shard");
    if (st.spec.resume) throw UsageError("--merge writes a new folder: not with --resume");
  }
  if (on_slurm && !st.shard.empty())
    throw UsageError("--slurm makes the shards itself; --shard is for arrays of your own");
}

}  // namespace

Subcommand register_risk(CLI::App& app) {
  auto st = std::make_shared<RiskState>();
  st->spec.jobs = batch::default_jobs();
  auto* cmd = app.add_subcommand(
      "risk",
      "Estimate how often a rare event happens to one planner, per 100 miles, with a 95%\n"
      "interval (with none seen: its bound), over runs of the bench's kind (one seed each). With\n"
      "levels that split (--params; a built-in policy), a run is copied with fresh random draws\n"
      "whenever its ego comes nearer a car than a level, the copies' events weighted so that\n"
      "the estimate stays unbiased (multilevel splitting); the shipped levels split nothing,\n"
      "since on this world copies made that late repeat their run's fate. It stops at\n"
      "--rel-error or --budget-hours, prints the estimate, the simulated hours spent, what\n"
      "plain runs would need for the same interval and the ratio (the gain), and writes\n"
      "risk.json, summary.md and runs.jsonl into --out. Ctrl-C keeps the finished runs;\n"
      "--resume goes on with them (docs/evaluation.md, \"Rare events\"). --slurm TASKS shares\n"
      "the runs out as a Slurm array; --shard and --merge do it by hand (docs/cluster.md).\n"
      "A run whose planner fails (crashes, stalls, sends no path) ends there: what it drove\n"
      "until then counts, the failure is listed as the planner's and is never the event.\n"
      "Exit status: 0; 130 when interrupted; 1 when the planner failed in every run so far\n"
      "(nothing to estimate) or a file cannot be written; 2 for bad flags.");
  st->policy_opt =
      cmd->add_option("--policy", st->spec.policy, policy_help())->capture_default_str();
  add_planner_flags(*cmd, st->planners, planners::PlannerFlagSet::all);
  cmd->add_option("--event", st->event,
                  "What is counted: at-fault (contacts that were the ego's fault), contact (any\n"
                  "contact), near-miss (episodes of TTC below the threshold without contact) or\n"
                  "a rubric incident type (collision, speeding, max_acceleration, max_jerk,\n"
                  "outside_lane; counted as the rubric counts them)")
      ->capture_default_str();
  cmd->add_option("--rel-error", st->spec.rel_error,
                  "Stop once the 95% interval's half width is within this share of the\n"
                  "estimate (0: only the budget stops it)")
      ->capture_default_str();
  cmd->add_option("--budget-hours", st->spec.budget_hours,
                  "... or once this many simulated hours are spent (every base run and copy)")
      ->capture_default_str();
  cmd->add_option("--max-runs", st->spec.max_runs, "... or after this many base runs")
      ->capture_default_str();
  cmd->add_option("--first-seed", st->spec.first_seed, "Base run r drives seed first-seed + r")
      ->check(seed_validator())
      ->capture_default_str();
  cmd->add_option("--map", st->map, "A map file (default: the built-in track)");
  cmd->add_option("--traffic", st->spec.traffic, "The traffic profile")->capture_default_str();
  cmd->add_option("--minutes", st->spec.minutes, "Simulated minutes per base run")
      ->capture_default_str();
  cmd->add_option("--config", st->config, "JSON parameter overrides")->check(CLI::ExistingFile);
  cmd->add_option("--params", st->params,
                  "JSON overrides of risk's own parameters (config/risk.json: the score, its\n"
                  "levels and splits)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--jobs,-j", st->spec.jobs, "Base runs in parallel (default: all cores)")
      ->capture_default_str();
  cmd->add_option("--out,-o", st->out, "Output folder")->capture_default_str();
  cmd->add_option("--scenarios", st->spec.scenarios,
                  "Cut the first this many events of the base runs into scenarios in OUT/events\n"
                  "(their runs driven again by a hunt over their seeds: grouped by situation,\n"
                  "each group's scenarios checked to repeat the event; 0: none)")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  cmd->add_flag("--resume", st->spec.resume,
                "Go on with the estimate in --out (refused when it is of another planner,\n"
                "event, map, traffic, config or build); with --slurm, follow the array\n"
                "submitted into --out before");
  cmd->add_option("--json", st->json, "Also write risk.json's contents to this file");
  cmd->add_flag("--quiet,-q", st->quiet, "No progress line or summary");
  cmd->add_option("--shard", st->shard,
                  "Run only shard I of N of the planned runs (run k when k mod N is I - 1): every\n"
                  "one of them, since the stopping rules look at the whole estimate; --merge\n"
                  "joins the shards and applies them");
  cmd->add_option("--merge", st->merge,
                  "Join these shards' folders (--shard I/N, the same flags otherwise) into --out:\n"
                  "the runs from run 0 without a gap, stopped where these flags' stopping rules\n"
                  "stop, so the same estimate as one run here")
      ->check(CLI::ExistingDirectory);
  add_slurm_flags(*cmd, st->slurm, "risk", "risk --merge OUT/shards/shard-* (these flags)");
  CLI::App* c = cmd;
  return {cmd, [st, c] {
            const bool on_slurm = slurm_requested(*c);
            check_modes(*st, on_slurm);
            if (!st->merge.empty()) return merge_here(*st);
            if (on_slurm) return run_on_slurm(*st, *c, spec_of(*st));
            return run_risk_here(*st);
          }};
}

}  // namespace overtake::app
