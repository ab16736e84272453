// `overtake risk`: the rate of a rare event per 100 miles for one planner, by multilevel
// splitting (batch/risk.hpp).

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "overtake/app/cli.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/planners/catalog.hpp"

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
  std::string map, config, params, out = "risk-out", json;
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
  return spec;
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
  const nlohmann::json j = batch::risk_json(spec, o);
  if (!st.json.empty()) base::write_file_atomic(st.json, j.dump(2) + "\n");
  if (!st.quiet) {
    std::cout << batch::risk_markdown(spec, o);
    std::cout << "written: " << spec.out.string() << "/{risk.json,summary.md,runs.jsonl}\n";
  }
  if (o.interrupted) {
    std::cerr << "risk: interrupted; " << o.runs.size() << " runs kept in " << spec.out.string()
              << " (--resume goes on with them)\n";
    return kExitInterrupted;
  }
  return kExitOk;
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
      "--resume goes on with them (docs/evaluation.md, \"Rare events\").\n"
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
  cmd->add_flag("--resume", st->spec.resume,
                "Go on with the estimate in --out (refused when it is of another planner,\n"
                "event, map, traffic, config or build)");
  cmd->add_option("--json", st->json, "Also write risk.json's contents to this file");
  cmd->add_flag("--quiet,-q", st->quiet, "No progress line or summary");
  return {cmd, [st] { return run_risk_here(*st); }};
}

}  // namespace overtake::app
