// `overtake compare BEFORE AFTER`: two bench output folders compared, run for run on the same
// seeds, with every figure's change, its 95% interval and whether it is beyond noise (tests
// corrected for the family of figures compared); `--fail-if-worse` turns a significant
// worsening into exit status 1 for a planner's CI, and too few seeds to judge into 2.

#include <memory>
#include <string>
#include <vector>

#include "overtake/app/cli.hpp"
#include "overtake/batch/bench.hpp"

namespace overtake::app {

Subcommand register_compare(CLI::App& app) {
  struct State {
    std::string before, after, figures, json;
    std::vector<std::string> pairs;
    bool fail_if_worse = false;
    bool quiet = false;
  };
  auto st = std::make_shared<State>();
  auto* cmd = app.add_subcommand(
      "compare",
      "Compare two bench output folders (before and after a change to a planner): the runs\n"
      "of a policy on the same traffic profile and seed are pairs; for each figure, the change\n"
      "with its 95% interval over the seeds, the probability of improvement, and a verdict:\n"
      "better or worse when its test (paired t-test for mean speed, exact sign-flip test over\n"
      "seeds for rates) is significant at 5% family-wise, Holm-corrected over every figure,\n"
      "policy and profile compared; no verdict below 8 seeds (docs/evaluation.md).\n"
      "Exit status: 0; with --fail-if-worse 1 when a figure got significantly worse, 2 when a\n"
      "comparison has too few seeds for a verdict (the reason is printed). Also 1 when a folder\n"
      "cannot be read, holds a row the bench cannot vouch for (a line that is not a run, a run\n"
      "written twice, a row of another sweep, map, length or build: named with its file and\n"
      "line) or its runs cannot be paired; 2 for bad flags.\n"
      "Two `overtake risk` folders compare as the ratio of their rates with its 95% interval\n"
      "(MOVER) and a verdict (higher, lower, no difference); --fail-if-worse: 1 when higher.");
  cmd->add_option("before", st->before, "The first bench's --out folder (the base)")->required();
  cmd->add_option("after", st->after, "The second bench's --out folder (the candidate)")
      ->required();
  cmd->add_option("--pair", st->pairs,
                  "OLD=NEW: compare policy OLD of the first bench with NEW of the second\n"
                  "(repeatable; default: every policy both benches ran, by name)");
  cmd->add_option("--figures", st->figures,
                  "Comma-separated figures to compare (default: all): mean_speed_mph,\n"
                  "incidents_per_100mi, collisions_per_100mi, at_fault_collisions_per_100mi,\n"
                  "near_misses_per_100mi");
  cmd->add_flag("--fail-if-worse", st->fail_if_worse,
                "Exit with status 1 when any compared figure got significantly worse, 2 when\n"
                "some comparison has too few seeds to judge");
  cmd->add_option("--json", st->json, "Also write the comparison as JSON to this file");
  cmd->add_flag("--quiet,-q", st->quiet, "Print nothing (the exit status and --json say it)");
  return {cmd, [st] {
            return batch::compare_folders({st->before, st->after, st->pairs, st->figures, st->json,
                                           st->fail_if_worse, st->quiet});
          }};
}

}  // namespace overtake::app
