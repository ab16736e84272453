// The `overtake bench` and `overtake bench merge` command lines.

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <optional>

#include "overtake/app/cli.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/batch/bench_page.hpp"
#include "overtake/batch/pool.hpp"
#include "overtake/batch/progress.hpp"
#include "overtake/batch/risk.hpp"
#include "overtake/batch/suite_run.hpp"
#include "overtake/cluster/arrays.hpp"
#include "overtake/cluster/slurm.hpp"
#include "overtake/core/units.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/pages.hpp"
#include "overtake/sandbox/planner_process.hpp"
#include "overtake/scenarios/suite.hpp"

namespace overtake::app {

using base::kExitInterrupted;
using base::kExitOk;
using base::split_list;
using base::UsageError;
using batch::bench_combinations;
using batch::bench_files_text;
using batch::BenchOutcome;
using batch::BenchProgress;
using batch::BenchSpec;
using batch::check_bench_spec;
using batch::check_report_pages;
using batch::kBenchRunsFile;
using batch::merge_bench;
using batch::parse_seed_list;
using batch::parse_shard;
using batch::run_bench;
using batch::run_suite;
using batch::Shard;
using batch::SuiteSpec;
using batch::write_bench_report_page;
using cluster::bench_array;
using cluster::check_programs_for_slurm;
using cluster::run_slurm_array;
using cluster::SlurmArray;
using cluster::SlurmOptions;
using planners::catalog_from_flags;
using planners::PlannerCatalog;
using planners::PlannerFlags;
using planners::PlannerFlagSet;
using scenarios::SuiteOutcome;
namespace {

// The flags of `overtake bench` and `overtake bench merge`.
struct BenchState {
  BenchSpec spec;
  std::string policies = "reference,walkthrough,seed000,seed001,seed002,seed003,seed004";
  std::string seeds = "1-20";
  std::string traffic = "faithful,calm";
  std::string map, config, out = "bench-out", shard, html;
  bool quiet = false;
  PlannerFlags planners;
  CLI::Option* policies_opt = nullptr;
  std::vector<std::string> merge_dirs;
  std::string merge_out, merge_html;
  std::string scenarios;
  std::vector<std::filesystem::path> risk;  // risk folders drawn on the page's chart
  std::vector<CLI::Option*> sweep_opts;     // flags a scenario suite does not take
  CLI::Option* out_opt = nullptr;
  SlurmOptions slurm;
};

// --risk: each folder an at-fault estimate the page can draw, and a page to draw it on; checked
// before any run, so that none is run in vain.
void check_risk_dirs(const BenchState& st) {
  if (st.risk.empty()) return;
  if (st.html.empty()) throw UsageError("--risk draws on the report page: give --html FILE too");
  for (const auto& dir : st.risk) {
    try {
      (void)batch::risk_chart_point(dir);
    } catch (const std::runtime_error& e) {
      throw UsageError("--risk " + dir.string() + ": " + e.what());
    }
  }
}

// The policies to run: --policies (its default only when no flag brought a planner), and
// every planner brought by a flag.
std::vector<std::string> chosen_policies(const BenchState& st, const PlannerCatalog& planners) {
  const auto brought = planners.added_names();
  std::vector<std::string> policies;
  if (st.policies_opt->count() > 0 || brought.empty()) policies = split_list(st.policies);
  for (const auto& name : brought) {
    if (std::find(policies.begin(), policies.end(), name) == policies.end())
      policies.push_back(name);
  }
  return policies;
}

// `overtake bench merge`.
int run_merge(const BenchState& st) {
  if (!st.merge_html.empty()) check_report_pages();
  const BenchOutcome o = merge_bench(
      std::vector<std::filesystem::path>(st.merge_dirs.begin(), st.merge_dirs.end()), st.merge_out);
  std::cout << "merged " << o.runs_done << " runs into " << st.merge_out << "\n\n"
            << o.summary_markdown;
  for (const auto& r : o.replays) std::cout << "replay: " << r.string() << "\n";
  if (!st.merge_html.empty()) write_bench_report_page(st.merge_out, st.merge_html, false);
  return kExitOk;
}

// Refuses the flags a Slurm bench, or a scenario suite, does not take.
void check_modes(const BenchState& st, bool on_slurm) {
  if (on_slurm && !st.scenarios.empty())
    throw UsageError("--slurm: a scenario suite (--scenarios) runs here, not on Slurm");
  if (on_slurm && !st.shard.empty())
    throw UsageError("--slurm makes the shards itself; --shard is for arrays of your own");
  if (on_slurm && st.spec.force)
    throw UsageError(
        "--force: a bench on Slurm merges into --out, which must not hold "
        "files of the names a bench writes; choose another --out");
  if (st.scenarios.empty()) return;
  for (const CLI::Option* o : st.sweep_opts) {
    if (o->count() > 0) {
      throw UsageError(o->get_name() +
                       ": a scenario suite (--scenarios) runs each scenario as its file "
                       "says; seeds, minutes and traffic do not apply");
    }
  }
}

// `overtake bench --scenarios DIR`: the suite, its table, and its exit status.
int run_scenarios(const BenchState& st) {
  SuiteSpec suite;
  suite.dir = st.scenarios;
  suite.planners = catalog_from_flags(st.planners);
  suite.policies = chosen_policies(st, *suite.planners);
  if (!st.config.empty()) suite.config = st.config;
  if (!st.map.empty()) suite.map = st.map;
  suite.jobs = st.spec.jobs;
  if (st.out_opt->count() > 0) suite.out = st.out;
  SuiteOutcome o;
  {
    base::StatusLine line(!st.quiet);
    const InterruptScope interrupt;
    o = run_suite(suite, &InterruptScope::flag(), [&](std::size_t done, std::size_t all) {
      line.draw("  scenarios: " + std::to_string(done) + "/" + std::to_string(all) + "   ");
    });
  }
  return batch::report_suite(suite, o, st.quiet);
}

// The sweep the flags name.
BenchSpec bench_spec_of(const BenchState& st) {
  BenchSpec spec = st.spec;
  spec.planners = catalog_from_flags(st.planners);
  spec.policies = chosen_policies(st, *spec.planners);
  spec.traffic = split_list(st.traffic);
  spec.seeds = parse_seed_list(st.seeds);
  if (!st.map.empty()) spec.map = st.map;
  if (!st.config.empty()) spec.config = st.config;
  spec.out = st.out;
  if (!st.shard.empty()) {
    const Shard shard = parse_shard(st.shard);
    spec.shard_index = shard.index;
    spec.shard_count = shard.count;
  }
  return spec;
}

// `overtake bench --slurm TASKS`: everything the tasks would refuse is refused here, before
// anything is submitted.
int run_on_slurm(const BenchState& st, const CLI::App& cmd, const BenchSpec& spec) {
  check_bench_spec(spec);
  check_programs_for_slurm(*spec.planners, st.planners.network);
  check_risk_dirs(st);
  if (!st.html.empty()) check_report_pages();
  const auto merged = [&st](const BenchOutcome& o, const std::filesystem::path& out,
                            std::size_t shards, double wall_s, int resubmitted) {
    if (!st.quiet) {
      std::cout << o.summary_markdown << "\n";
      std::printf("%zu runs in %zu Slurm tasks (%d submitted again) in %.1f s\n", o.runs_done,
                  shards, resubmitted, wall_s);
      std::cout << "written: " << out.string() << "/" << bench_files_text() << "\n";
      for (const auto& r : o.replays) std::cout << "replay: " << r.string() << "\n";
    }
    if (!st.html.empty()) write_bench_report_page(out, st.html, st.quiet, st.risk);
    return kExitOk;
  };
  SlurmArray array = bench_array(
      spec, st.slurm.tasks,
      task_arguments(cmd, {"out", "jobs", "resume", "quiet", "html", "shard", "force", "risk"}),
      merged);
  array.quiet = st.quiet;
  const InterruptScope interrupt;
  return run_slurm_array(array, st.slurm, &InterruptScope::flag());
}

// The bench run here under Ctrl-C, with its progress bar.
BenchOutcome run_bench_here(const BenchState& st, const BenchSpec& spec) {
  const double total_sim_s =
      spec.minutes * 60.0 * static_cast<double>(bench_combinations(spec).size()) / spec.shard_count;
  base::StatusLine line(!st.quiet);
  const InterruptScope interrupt;
  return run_bench(spec, &InterruptScope::flag(), [&](const BenchProgress& p) {
    line.draw(batch::progress_text(p, total_sim_s));
  });
}

// `overtake bench`: the sweep here, its summary and report page.
int run_sweep(const BenchState& st, const BenchSpec& spec) {
  if (spec.planners->has_programs() && !st.quiet) {
    const auto network = sandbox::parse_planner_network(st.planners.network);
    if (network == sandbox::PlannerNetwork::automatic) {
      const sandbox::NetworkCheck check = sandbox::check_planner_network(*network);
      if (!check.own_network) {
        std::fprintf(stderr,
                     "bench: planner programs run one at a time on the host's network: %s\n",
                     check.why.c_str());
      }
    }
  }
  if (!st.html.empty()) check_report_pages();
  check_risk_dirs(st);
  const BenchOutcome o = run_bench_here(st, spec);
  if (o.interrupted) {
    std::cerr << "bench: interrupted; " << o.runs_done << " finished runs kept in "
              << (spec.out / kBenchRunsFile).string() << "; rerun with --resume to finish\n";
    return kExitInterrupted;
  }
  if (!st.quiet) {
    std::cout << o.summary_markdown << "\n";
    const double hours_per_minute =
        o.wall_s > 0 ? (o.simulated_s / 3600.0) / (o.wall_s / 60.0) : 0.0;
    std::printf(
        "%zu runs (%zu new) in %.1f s on %d jobs: %.1f simulated hours per wall-clock "
        "minute\n",
        o.runs_done, o.runs_new, o.wall_s, spec.jobs, hours_per_minute);
    std::cout << "written: " << spec.out.string() << "/" << bench_files_text() << "\n";
    for (const auto& r : o.replays) std::cout << "replay: " << r.string() << "\n";
  }
  if (!st.html.empty()) write_bench_report_page(spec.out, st.html, st.quiet, st.risk);
  return kExitOk;
}

// The flags of the sweep, a scenario suite and the runs' output.
void add_sweep_flags(CLI::App& cmd, BenchState& st) {
  st.policies_opt = cmd.add_option("--policies", st.policies,
                                   "Comma-separated policies (built-in ones, and the names of\n"
                                   "planners brought by the flags below). Default: every\n"
                                   "built-in policy, or only the brought ones when any are")
                        ->capture_default_str();
  add_planner_flags(cmd, st.planners, PlannerFlagSet::all);
  st.sweep_opts.push_back(
      cmd.add_option("--seeds", st.seeds, "Seeds: a range and/or list, e.g. 1-20 or 1,5,9-12")
          ->capture_default_str());
  st.sweep_opts.push_back(cmd.add_option("--minutes", st.spec.minutes, "Simulated minutes per run")
                              ->capture_default_str());
  st.sweep_opts.push_back(
      cmd.add_option("--traffic", st.traffic, "Comma-separated traffic profiles (faithful, calm)")
          ->capture_default_str());
  cmd.add_option(
         "--scenarios", st.scenarios,
         "Instead of the sweep: run every scenario file (*.json) of this folder with every\n"
         "policy and judge it by what it expects (default: no at-fault collision); prints a\n"
         "pass/fail table (with --out, not this folder: suite.md, suite.json and the failed\n"
         "runs' replays) and exits with status 1 when any fails (docs/scenarios.md)")
      ->check(CLI::ExistingDirectory);
  cmd.add_option("--map", st.map, "Map file; default: the built-in track")
      ->check(CLI::ExistingFile);
  cmd.add_option("--config", st.config, "JSON parameter overrides")->check(CLI::ExistingFile);
  cmd.add_option("--steps-per-call", st.spec.steps_per_call,
                 "Fixed steps per reply (1-1000); default: drawn 1-3 by seed")
      ->check(CLI::Range(1, 1000));
  cmd.add_option("--jobs,-j", st.spec.jobs, "Runs in parallel (default: all cores)")
      ->capture_default_str();
}

// The flags of where the results go and how.
void add_output_flags(CLI::App& cmd, BenchState& st) {
  st.out_opt = cmd.add_option("--out,-o", st.out, "Output folder")->capture_default_str();
  cmd.add_option("--shard", st.shard, "Run only slice I of N (e.g. 3/8) of the combinations");
  cmd.add_flag("--resume", st.spec.resume,
               "Continue an interrupted bench in --out, skipping finished runs (its rows must\n"
               "be this bench's, each once, and of this build of overtake)");
  cmd.add_flag("--force", st.spec.force,
               "Write into --out even when it holds files of the names a bench writes\n"
               "(summary.md, summary.csv, summary.json, pairs.csv, replays/, logs/) that no\n"
               "bench wrote (the folder has no bench.json): they are replaced. A bench's own\n"
               "results are never replaced (--resume continues them)");
  cmd.add_option(
      "--record-worst", st.spec.record_worst,
      "After the bench, run the N runs with most incidents again (ties: lower seed first;\n"
      "deterministic, so the same runs) recording replays into --out/replays/\n"
      "<policy>-<traffic>-seed<N>.otr, for `overtake view`");
  cmd.add_option("--html", st.html,
                 "Also write the bench report page (summary table and charts per policy, each run\n"
                 "linked to its replay when recorded) to this file, and each recorded replay's\n"
                 "self-contained page beside it (replays/*.html)");
  cmd.add_option("--risk", st.risk,
                 "An `overtake risk` folder of an at-fault estimate (repeatable): drawn on the\n"
                 "report page's speed-against-safety chart beside the bench's rows, a hollow\n"
                 "mark at its rate and interval and its base runs' mean speed, the rate axis\n"
                 "then on a log scale (with --html)")
      ->check(CLI::ExistingDirectory);
  cmd.add_flag("--quiet,-q", st.quiet, "No progress bar or summary");
}

// `overtake bench merge`'s flags.
CLI::App* add_merge_command(CLI::App& cmd, BenchState& st) {
  auto* merge =
      cmd.add_subcommand("merge", "Join the output folders of the shards of one bench into --out.");
  merge->add_option("dirs", st.merge_dirs, "Shard output folders")
      ->required()
      ->check(CLI::ExistingDirectory);
  merge
      ->add_option("--out,-o", st.merge_out,
                   "Folder for the joined output (the shards' replays are copied\n"
                   "into its replays/)")
      ->required();
  merge->add_option(
      "--html", st.merge_html,
      "Also write the bench report page of the joined output to this file, each run\n"
      "linked to its replay when a shard recorded it (pages written into --out/replays/)");
  return merge;
}

}  // namespace

Subcommand register_bench(CLI::App& app) {
  auto st = std::make_shared<BenchState>();
  st->spec.jobs = batch::default_jobs();
  auto* cmd = app.add_subcommand(
      "bench",
      "Run every combination of policies x traffic profiles x seeds in parallel and summarise\n"
      "them with 95% intervals over the seeds, collisions (one per car touched) and whose\n"
      "fault, near misses, and paired comparisons of the policies whose verdicts are corrected\n"
      "for the number of figures judged; no interval or verdict below 8 seeds (runs.jsonl,\n"
      "summary.md, summary.csv, summary.json, pairs.csv in --out; docs/evaluation.md).\n"
      "`overtake bench merge` joins shards; `overtake compare` compares two benches.");
  add_sweep_flags(*cmd, *st);
  add_output_flags(*cmd, *st);
  add_slurm_flags(*cmd, st->slurm, "bench");
  auto* merge = add_merge_command(*cmd, *st);
  return {cmd, [st, merge, cmd] {
            if (merge->parsed()) return run_merge(*st);
            const bool on_slurm = slurm_requested(*cmd);
            check_modes(*st, on_slurm);
            if (!st->scenarios.empty()) return run_scenarios(*st);
            const BenchSpec spec = bench_spec_of(*st);
            if (on_slurm) return run_on_slurm(*st, *cmd, spec);
            return run_sweep(*st, spec);
          }};
}

}  // namespace overtake::app
