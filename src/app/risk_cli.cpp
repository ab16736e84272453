// `overtake risk`: the rate of a rare event per 100 miles for one planner, by multilevel
// splitting (batch/risk.hpp).

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
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
#include "overtake/batch/risk.hpp"
#include "overtake/cluster/slurm.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/config.hpp"

namespace overtake::app {

namespace {

using base::kExitInterrupted;
using base::kExitOk;
using base::stderr_is_terminal;
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

void draw_progress(const batch::RiskProgress& p) {
  std::fprintf(stderr,
               "\r  risk: %zu runs, %.1f of %.1f simulated h, %.2f weighted events, "
               "%.4f per 100 mi (+-%.0f%%), %.0f s   ",
               p.runs, p.simulated_h, p.budget_h, p.weighted_events, p.rate_per_100mi,
               100.0 * p.rel_half_width, p.wall_s);
  std::fflush(stderr);
}

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
int report(const RiskState& st, const batch::RiskSpec& spec, const batch::RiskOutcome& o,
           const std::string& how) {
  const nlohmann::json j = batch::risk_json(spec, o);
  if (!st.json.empty()) base::write_file_atomic(st.json, j.dump(2) + "\n");
  if (!st.quiet) {
    std::cout << batch::risk_markdown(spec, o) << how;
    std::cout << "written: " << spec.out.string() << "/{risk.json,summary.md,runs.jsonl}"
              << (o.cut ? ", " + (spec.out / "events").string() + "/ (the cut scenarios)" : "")
              << "\n";
  }
  if (o.interrupted) {
    std::cerr << "risk: interrupted; " << o.runs.size() << " runs kept in " << spec.out.string()
              << " (--resume goes on with them)\n";
    return kExitInterrupted;
  }
  return kExitOk;
}

int run_risk_here(const RiskState& st) {
  const batch::RiskSpec spec = spec_of(st);
  batch::check_risk_spec(spec);
  const bool draw = !st.quiet && stderr_is_terminal();
  batch::RiskOutcome o;
  {
    const InterruptScope interrupt;
    try {
      o = batch::run_risk(spec, &InterruptScope::flag(), [&](const batch::RiskProgress& p) {
        if (draw) draw_progress(p);
      });
    } catch (...) {
      if (draw) std::fprintf(stderr, "\n");
      throw;
    }
    if (draw) std::fprintf(stderr, "\n");
  }
  return report(st, spec, o, "");
}

// --merge: the shards' folders into --out, as one run here with the same flags would write it.
int merge_here(const RiskState& st) {
  const batch::RiskSpec spec = spec_of(st);
  const InterruptScope interrupt;
  const batch::RiskOutcome o = batch::merge_risk(spec, st.merge, &InterruptScope::flag());
  return report(st, spec, o, "");
}

// The runs a shard's runs.jsonl holds (lines; a last one cut short counts, as it is redone).
std::size_t runs_in(const std::filesystem::path& shard) {
  std::ifstream in(shard / "runs.jsonl");
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

// `overtake risk --slurm TASKS`: task I runs shard I of the planned runs with --resume (so a
// task submitted again goes on with its runs); a shard is finished when its risk.json says so;
// the shards merge as --merge does, with the stopping rules of these flags.
int run_on_slurm(const RiskState& st, const CLI::App& cmd, batch::RiskSpec spec) {
  namespace fs = std::filesystem;
  batch::check_risk_spec(spec);
  cluster::check_programs_for_slurm(*spec.planners, st.planners.network);
  cluster::SlurmArray a = cluster::slurm_array_here("risk", spec.out);
  if (fs::exists(a.out / "risk-spec.json") || fs::exists(a.out / "runs.jsonl")) {
    throw UsageError("--out: " + a.out.string() +
                     " already holds an estimate (merged, or a local one); choose another --out");
  }
  a.args = task_arguments(cmd, {"out", "jobs", "resume", "quiet", "shard", "json", "scenarios"});
  a.task_flags = {"--resume", "--quiet"};
  a.runs = batch::risk_runs_planned(spec);
  a.resume = spec.resume;
  a.quiet = st.quiet;
  const std::size_t runs = a.runs;
  const int tasks = st.slurm.tasks;
  a.shard_state = [runs, tasks](const fs::path& shard, int task) {
    cluster::SlurmShardState s;
    const std::size_t want = cluster::slurm_shard_runs(runs, tasks, task);
    try {
      const nlohmann::json j = run::read_json_file(shard / "risk.json");
      s.finished = j.contains("shard") && j["shard"].value("finished", false);
    } catch (const std::exception&) {  // not finished: the merge names what is wrong
    }
    s.so_far = std::to_string(runs_in(shard)) + " of " + std::to_string(want) + " runs";
    return s;
  };
  a.progress = [runs](const std::vector<fs::path>& shards) {
    std::size_t have = 0;
    for (const auto& shard : shards) have += runs_in(shard);
    return std::to_string(have) + "/" + std::to_string(runs) + " runs";
  };
  spec.out = a.out;
  spec.resume = false;
  a.merge = [&st, spec](const std::vector<fs::path>& shards, double wall_s, int resubmitted) {
    const batch::RiskOutcome o = batch::merge_risk(spec, shards, &InterruptScope::flag());
    return report(st, spec, o,
                  std::to_string(shards.size()) + " Slurm tasks (" + std::to_string(resubmitted) +
                      " submitted again) in " + base::fixed_text(wall_s, 1) + " s\n");
  };
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
      "Exit status: 0; 130 when interrupted; 1 when a run fails (its planner failed: the\n"
      "planner's failure, not the event) or a file cannot be written; 2 for bad flags.");
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
