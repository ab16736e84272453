#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <string>

#include "overtake/app/cli.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/text.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/scenario_file.hpp"
#include "overtake/scenarios/cut.hpp"

namespace overtake::app {

using base::fixed_text;
using base::UsageError;
using run::parse_json_text;
using run::parse_scenario;
using scenarios::cut_replay;
using scenarios::CutOptions;
using scenarios::CutResult;
using scenarios::kDefaultWarmUpS;
using scenarios::parse_warm_up;

namespace {

// The flags of `cut` as given.
struct CutFlags {
  CutOptions o;
  std::string traffic = "reactive";
  std::string expect;
  std::string config, map;
  std::string warm_up = fixed_text(kDefaultWarmUpS, 0);
  bool quiet = false;
};

// Cuts the scenario the flags ask for and says what was written.
int run_cut(const CutFlags& st) {
  CutOptions o = st.o;
  if (st.traffic != "reactive" && st.traffic != "replayed") {
    throw UsageError("--traffic: '" + st.traffic + "' is neither reactive nor replayed");
  }
  o.replayed = st.traffic == "replayed";
  parse_warm_up(st.warm_up, o.warm_up_s, o.warm_up_all);
  if (!st.config.empty()) o.config = st.config;
  if (!st.map.empty()) o.map = st.map;
  if (!st.expect.empty()) {
    const nlohmann::json j = parse_json_text(st.expect, "--expect");
    o.expect = parse_scenario(nlohmann::json{{"expect", j}}, "--expect", {}).expect;
  }
  const CutResult res = cut_replay(o);
  if (!st.quiet) {
    std::cout << "wrote " << o.out.string() << " (" << res.file_bytes / 1024 << " KiB): t "
              << fixed_text(res.start_s, 2) << " to " << fixed_text(res.end_s, 2) << " s, "
              << (o.replayed ? "replayed" : "reactive") << " traffic\n";
    if (!res.exact_start) {
      std::cout << "  starts at the checkpoint at t " << fixed_text(res.start_s, 2) << " s, "
                << fixed_text(res.asked_start_s - res.start_s, 2) << " s before the asked start\n";
    }
    std::cout << "  planner: " << res.planner_state << "\n";
    if (!res.incident.empty()) std::cout << "  near the moment: " << res.incident << "\n";
    std::cout << "drive it: " << res.drive_command << "\n";
  }
  return 0;
}

}  // namespace

Subcommand register_cut(CLI::App& app) {
  auto st = std::make_shared<CutFlags>();
  auto* cmd = app.add_subcommand(
      "cut",
      "Cut a scenario from a recorded run: it starts --before seconds before the moment --at\n"
      "and lasts until --after seconds after it, from the world's exact state (replays carry\n"
      "checkpoints). Drive it with `overtake drive --scenario FILE`, or run a folder of them\n"
      "with `overtake bench --scenarios DIR` (docs/scenarios.md).");
  cmd->add_option("replay", st->o.replay, "A replay written by --record")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--at", st->o.at_s, "The moment that matters (run time, seconds)")->required();
  cmd->add_option("-o,--out", st->o.out, "The scenario file to write")->required();
  cmd->add_option("--before", st->o.before_s, "Seconds before the moment to start")
      ->capture_default_str();
  cmd->add_option("--after", st->o.after_s, "Seconds after the moment to end")
      ->capture_default_str();
  cmd->add_option("--lead-in", st->o.lead_in_s,
                  "Start this many seconds earlier still, for a planner that keeps its own\n"
                  "state (a target speed starting at 0) to settle; not judged")
      ->capture_default_str();
  cmd->add_option("--warm-up", st->warm_up,
                  "For a run of a planner from outside (a program, a plugin, Python): the\n"
                  "seconds before the start whose telemetry the scenario carries, played to the\n"
                  "planner before it drives so that it comes in step; `all`: from the run's first\n"
                  "cycle; 0: none")
      ->capture_default_str();
  cmd->add_option("--traffic", st->traffic,
                  "reactive: the cars start from their recorded state and keep driving by\n"
                  "their rules (they react to another planner); replayed: every car follows its\n"
                  "recorded trajectory whatever the ego does")
      ->capture_default_str();
  cmd->add_option("--expect", st->expect,
                  "What the scenario expects, as JSON (default {\"at_fault_collisions\": 0}):\n"
                  "at_fault_collisions, collisions, incidents (at most so many), reach_lane\n"
                  "{\"lane\": L, \"by_s\": T}, min_distance_m");
  cmd->add_option("--name", st->o.name, "The scenario's name (default: the run and the moment)");
  cmd->add_option("--description", st->o.description, "What happens in it");
  cmd->add_option("--config", st->config, "The parameters the run used (default: the defaults)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--map", st->map, "The run's map, when it is no longer where the replay says")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--quiet,-q", st->quiet, "Print nothing");
  return {cmd, [st] { return run_cut(*st); }};
}

}  // namespace overtake::app
