// The `overtake tune` command line.

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <optional>
#include <set>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "overtake/app/cli.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/batch/progress.hpp"
#include "overtake/batch/tune.hpp"
#include "overtake/cluster/arrays.hpp"

namespace overtake::app {

using base::split_list;
using base::UsageError;
using batch::parse_seed_list;
using batch::TuneOutcome;
using batch::TuneProgress;
using batch::TuneSpec;

namespace {

struct TuneFlags {
  std::vector<std::string> params;
  std::vector<std::string> constraints{"at_fault_collisions<=0", "incidents<=0", "ended_early<=0"};
  std::string traffic = "faithful";
  std::string seeds = "1-8";
  std::string validate_seeds;
  std::vector<std::string> maps;
  std::string config;
  double hours = 0.0;
  bool quiet = false;
  std::optional<double> max_risk;
  std::optional<double> risk_hours;
  std::string risk_event = "at-fault";
  batch::TuneRisk risk;
  planners::PlannerFlags planners;
  cluster::SlurmOptions slurm;
  std::set<std::string> planner_options;  ///< the long names of the planner flags
};

// A terminal gets one line drawn over; anything else (a log) a line as each trial starts.
void show_progress(base::StatusLine& line, const TuneProgress& p, int& shown) {
  if (line.on()) return line.draw(batch::progress_text(p));
  if (p.trial <= shown) return;
  const std::string best = p.best ? ", best " + base::fixed_text(*p.best, 3) : std::string();
  std::fprintf(stderr, "tune: trial %d of %d%s\n", p.trial, p.trials, best.c_str());
  shown = p.trial;
}

// `tune --slurm`: what the tasks could not do is refused before anything is submitted.
std::function<bool(const batch::BenchSpec&, const std::atomic<bool>*)> slurm_for(
    const CLI::App& cmd, const TuneSpec& spec, const TuneFlags& f) {
  if (f.slurm.submit_only) {
    throw UsageError(
        "--slurm-submit-only: a search reads each trial's bench before it asks for the next, "
        "so it follows every array; leave the flag out");
  }
  // Each bench (a trial's on one map, a validation's) shares its runs out among the tasks.
  std::size_t seeds = spec.seeds.size();
  if (!spec.validation_seeds.empty()) seeds = std::min(seeds, spec.validation_seeds.size());
  cluster::validate_slurm_options(f.slurm, seeds * spec.traffic.size());
  cluster::check_programs_for_slurm(*spec.planners, f.planners.network);
  // The planner flags as given, but the programs' commands and names: each trial has its own.
  std::set<std::string> leave_out;
  for (const CLI::Option* o : cmd.get_options()) {
    if (o->get_lnames().empty()) continue;
    const std::string& name = o->get_lnames().front();
    if (f.planner_options.count(name) == 0 || name == "planner-cmd" || name == "planner-name" ||
        name == "policy-py" || name == "policy-lib" || name == "planner-params")
      leave_out.insert(name);
  }
  return cluster::tune_bench_runner(f.slurm, task_arguments(cmd, leave_out));
}

TuneSpec spec_of(TuneSpec spec, const TuneFlags& f) {
  for (const auto& p : f.params) spec.params.push_back(batch::parse_tune_param(p));
  spec.constraints.clear();
  for (const auto& c : f.constraints) {
    if (c != "none") spec.constraints.push_back(batch::parse_tune_constraint(c));
  }
  spec.traffic = split_list(f.traffic);
  spec.seeds = parse_seed_list(f.seeds);
  if (!f.validate_seeds.empty()) spec.validation_seeds = parse_seed_list(f.validate_seeds);
  for (const auto& m : f.maps) {
    // "default" is the built-in track (as in hunt's --maps), anything else a map file.
    if (m == "default") {
      spec.maps.emplace_back(std::nullopt);
    } else {
      spec.maps.emplace_back(m);
    }
  }
  if (!f.config.empty()) spec.config = f.config;
  if (f.max_risk || f.risk_hours) {
    spec.risk = f.risk;
    try {
      spec.risk->event = batch::parse_risk_event(f.risk_event);
    } catch (const UsageError& e) {
      // risk's words name its own flag, --event
      std::string what = e.what();
      if (what.starts_with("--event")) what.insert(2, "risk-");
      throw UsageError(what);
    }
    spec.risk->max_per_100mi = f.max_risk;
    if (f.risk_hours) spec.risk->hours = *f.risk_hours;
  }
  if (f.hours > 0.0) {
    // Simulated hours: each trial costs seeds x traffic profiles x minutes.
    const double trial_h =
        static_cast<double>(spec.seeds.size() * spec.traffic.size()) * spec.minutes / 60.0;
    spec.trials = std::max(1, static_cast<int>(f.hours / trial_h));
  }
  spec.planners = planners::catalog_from_flags(f.planners);
  if (spec.policy.empty()) {
    // One planner from outside and no --policy: that planner is the one searched.
    const std::vector<std::string> added = spec.planners->added_names();
    if (added.size() != 1) {
      throw UsageError(
          "--policy: name the planner searched (a built-in policy, or the name of a "
          "--planner-cmd, --policy-py or --policy-lib); it may be left out only when one "
          "planner comes from outside");
    }
    spec.policy = added.front();
  }
  return spec;
}

// What is searched, by which figure, on which runs.
void add_search_flags(CLI::App& cmd, TuneSpec& spec, TuneFlags& f) {
  cmd.add_option("--param", f.params,
                 "NAME=LOW:HIGH[@START], repeatable: a built-in policy's config key (full path\n"
                 "or a unique ending; starts at its config value), a program's {NAME}\n"
                 "placeholder in --planner-cmd (else the environment variable NAME), or a\n"
                 "Python planner's keyword argument (starts mid-range unless @START)")
      ->required();
  cmd.add_option("--objective", spec.objective,
                 "The figure optimised (mean_speed_mph: higher is better; counts and rates:\n"
                 "lower)")
      ->capture_default_str();
  cmd.add_option("--constraint", f.constraints,
                 "FIGURE<=VALUE or FIGURE>=VALUE, repeatable, over a trial's runs together\n"
                 "(`none`: no constraint)")
      ->capture_default_str();
  cmd.add_option("--seeds", f.seeds, "Training seeds (1-8, 1,4,9)")->capture_default_str();
  cmd.add_option("--validate-seeds", f.validate_seeds,
                 "Held-out seeds for the validation (none: no validation)");
  cmd.add_option("--traffic", f.traffic, "Traffic profiles, comma-separated")
      ->capture_default_str();
  cmd.add_option("--minutes", spec.minutes, "Simulated minutes per run")
      ->check(CLI::Range(0.1, 24.0 * 60.0))
      ->capture_default_str();
  cmd.add_option("--map", f.maps,
                 "A map file (the original's format; default: the built-in track), repeatable:\n"
                 "each trial drives every seed on every map, and its figures are over them\n"
                 "all (`default`: the built-in track)");
  cmd.add_option("--config", f.config, "A config file the search starts from");
}

// --max-risk and the flags of each trial's risk estimate (batch::TuneRisk).
void add_risk_flags(CLI::App& cmd, TuneFlags& f) {
  cmd.add_option("--max-risk", f.max_risk,
                 "RATE: a trial is feasible when its rate of --risk-event per 100 mi, estimated\n"
                 "by `overtake risk` after its bench (--risk-hours, the same runs for every\n"
                 "trial), is at most RATE; the validation estimates the start's and the best's\n"
                 "again on runs of their own and says whether the best is within it")
      ->check(CLI::Range(0.0, 1e6));
  cmd.add_option("--risk-event", f.risk_event,
                 "The event of the risk: at-fault, contact, near-miss or a rubric incident type")
      ->capture_default_str();
  cmd.add_option("--risk-hours", f.risk_hours,
                 "Each trial's risk budget, simulated hours per map and traffic profile (also\n"
                 "turns on the risk figures without --max-risk, for --objective/--constraint)\n"
                 "[default: 2]")
      ->check(CLI::Range(0.001, 1e6));
  cmd.add_option("--risk-validation-hours", f.risk.validation_hours,
                 "The validation's risk budget, for the start and the best each, per map and\n"
                 "traffic profile")
      ->check(CLI::Range(0.001, 1e6))
      ->capture_default_str();
  cmd.add_option("--risk-first-seed", f.risk.first_seed,
                 "The trials' risk runs are seeded from this one on; the validation's follow\n"
                 "the last a trial's budget can reach (a training or held-out seed in either\n"
                 "range is refused)")
      ->capture_default_str();
  cmd.add_option("--risk-rel-error", f.risk.rel_error,
                 "A trial's risk estimate stops early once its interval's half width is\n"
                 "within this share of the rate (0: the whole --risk-hours)")
      ->check(CLI::Range(0.0, 9.99))
      ->capture_default_str();
}

}  // namespace

Subcommand register_tune(CLI::App& app) {
  auto spec = std::make_shared<TuneSpec>();
  auto f = std::make_shared<TuneFlags>();
  CLI::App* cmd = app.add_subcommand(
      "tune",
      "Search a planner's parameters: each trial a bench on the same training seeds, proposed\n"
      "by a derivative-free optimiser (NLopt); then the best against the start on held-out\n"
      "seeds, paired, with intervals and verdicts. Writes trials.jsonl, best.json (a config\n"
      "for --config), summary.md and tune.html into --out; Ctrl-C keeps every finished trial.");
  cmd->add_option("--policy", spec->policy,
                  "The planner searched: a built-in policy, or a --planner-cmd, --policy-py or\n"
                  "--policy-lib by its name (default: the one planner from outside, when one)");
  add_search_flags(*cmd, *spec, *f);
  add_risk_flags(*cmd, *f);
  cmd->add_option("--trials", spec->trials, "The budget: trials at most")->capture_default_str();
  cmd->add_option("--hours", f->hours,
                  "The budget as simulated hours (training runs), when fewer trials than --trials")
      ->check(CLI::Range(0.0, 1e7));
  cmd->add_option("--algorithm", spec->algorithm,
                  "NLopt's: sbplx, neldermead, bobyqa, cobyla (local, from the start) or\n"
                  "direct (DIRECT-L), crs2 (controlled random search, seeded): global, over\n"
                  "the whole box")
      ->capture_default_str();
  cmd->add_option("-j,--jobs", spec->jobs, "Runs of a trial at once")
      ->default_val(batch::default_jobs());
  cmd->add_option("-o,--out", spec->out, "The output folder")->capture_default_str();
  cmd->add_flag("--resume", spec->resume, "Go on with the search in --out");
  cmd->add_flag("--force", spec->force, "Write into an --out that holds other files");
  cmd->add_flag("--quiet,-q", f->quiet,
                "No progress lines or summary (the files of --out are written all the same)");
  std::set<std::string> before;
  for (const CLI::Option* o : cmd->get_options()) {
    if (!o->get_lnames().empty()) before.insert(o->get_lnames().front());
  }
  add_planner_flags(*cmd, f->planners, planners::PlannerFlagSet::all);
  for (const CLI::Option* o : cmd->get_options()) {
    if (!o->get_lnames().empty() && before.count(o->get_lnames().front()) == 0) {
      f->planner_options.insert(o->get_lnames().front());
    }
  }
  add_slurm_flags(*cmd, f->slurm, "tune");
  cmd->get_option("--slurm")->description(
      "Run each bench of the search (a trial's on each map, the validation's) as a Slurm job\n"
      "array of this many tasks (docs/cluster.md): its batch script in the bench's folder\n"
      "(trials/NNNN/slurm/), submitted with sbatch, followed (squeue), failed tasks submitted\n"
      "again, the shards merged there before the search reads them (the same trials as\n"
      "here). Built-in policies and --planner-cmd programs. Ctrl-C stops following only;\n"
      "--resume follows again");
  return {cmd, [spec, f, cmd] {
            batch::check_jobs(spec->jobs);
            TuneSpec s = spec_of(*spec, *f);
            if (slurm_requested(*cmd)) s.run_bench_elsewhere = slurm_for(*cmd, s, *f);
            if (f->hours > 0.0) s.trials = std::min(s.trials, spec->trials);
            TuneOutcome o;
            {
              base::StatusLine line(!f->quiet);
              const InterruptScope interrupt;
              int shown = 0;
              o = batch::run_tune(s, &InterruptScope::flag(), [&](const TuneProgress& p) {
                if (!f->quiet) show_progress(line, p, shown);
              });
            }
            return batch::report_tune(s, o, f->quiet);
          }};
}

}  // namespace overtake::app
