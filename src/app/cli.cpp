#include <CLI/CLI.hpp>
#include <algorithm>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <optional>
#include <string_view>
#include <vector>

#include "overtake/app/cli.hpp"
#include "overtake/app/interrupt.hpp"
#include "overtake/base/build_info.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/base/text.hpp"
#include "overtake/core/hash.hpp"
#include "overtake/core/track.hpp"
#include "overtake/core/units.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/finish.hpp"
#include "overtake/run/pages.hpp"
#include "overtake/run/progress.hpp"
#include "overtake/run/report.hpp"

namespace overtake::app {

using base::flush_stdout_or_throw;
using base::json_text;
using base::kExitFailure;
using base::kExitOk;
using base::kExitUsage;
using base::OutputClosed;
using base::overtake_version;
using base::same_file;
using base::UsageError;
using base::write_file_atomic;
using planners::catalog_from_flags;
using planners::chosen_policy;
using planners::PlannerFlags;
using planners::PlannerFlagSet;
using run::Config;
using run::config_to_json;
using run::drive;
using run::DriveOptions;
using run::DriveOutputs;
using run::DriveResult;
using run::finish_drive;
using run::load_config;
using run::ProgressLine;

std::string policy_help() {
  std::string out = "Policy (built-in planner). Available:";
  for (const auto& p : planner::list_policies()) out += "\n  " + p.name + ": " + p.summary;
  return out;
}

namespace {

int cmd_drive(DriveOptions opts, const std::optional<std::filesystem::path>& json_out, bool quiet) {
  const double total_s =
      opts.minutes_from_scenario ? 0.0 : opts.minutes * 60.0;  // 0: not known yet
  ProgressLine progress(!quiet, total_s);
  // Ctrl-C or SIGTERM stops the run at the next step, keeping everything: the scorecard, the
  // JSON and the replay, marked ended early (exit 130). A live run goes at real time, and
  // afterwards a second Ctrl-C stops serving the page.
  const InterruptScope interrupt;
  const auto wall0 = std::chrono::steady_clock::now();
  const DriveResult result = drive(
      opts, [&](double t, double dist) { progress.update(t, dist); }, &InterruptScope::flag());
  DriveOutputs out;
  out.json = json_out;
  out.quiet = quiet;
  out.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  progress.clear();
  return finish_drive(result, opts, out, &InterruptScope::flag());
}

/// A track spec's error in the command line's words: its fields by their flags.
std::string in_flag_words(std::string message) {
  const auto replace_all = [&](const std::string& from, const std::string& to) {
    for (std::size_t at = message.find(from); at != std::string::npos;
         at = message.find(from, at + to.size())) {
      message.replace(at, from.size(), to);
    }
  };
  replace_all("TrackSpec.", "");
  for (const char* field : {"straight_spacing_m", "min_spacing_m", "max_spacing_m", "length_m"}) {
    std::string flag = std::string("--") + field;
    std::replace(flag.begin(), flag.end(), '_', '-');
    replace_all(field, flag);
  }
  return message;
}

int cmd_track(const core::TrackSpec& spec, const std::optional<std::filesystem::path>& out_path,
              bool quiet) {
  const std::string name = out_path ? out_path->string() : "generated track";
  core::GeneratedTrack track;
  try {
    track = core::generate_checked_track(spec, name);
  } catch (const std::invalid_argument& e) {
    throw UsageError(in_flag_words(e.what()));
  }
  const std::string& text = track.text;
  const core::Map& map = track.map;
  const core::TrackReport& check = track.check;
  if (out_path) {
    write_file_atomic(*out_path, text);
  } else {
    std::cout << text;
    flush_stdout_or_throw();
  }
  if (!quiet) {
    std::fprintf(stderr,
                 "track: seed %llu, %zu waypoints, loop %.1f m, spacing %.1f-%.1f m, tightest "
                 "lane radius %.0f m%s%s\n",
                 static_cast<unsigned long long>(spec.seed), map.waypoints.size(),
                 map.loop_length_m, check.min_spacing_m, check.max_spacing_m, check.min_radius_m,
                 out_path ? ", written to " : "", out_path ? out_path->string().c_str() : "");
  }
  return 0;
}

}  // namespace

void print_live_address(const std::string& url) {
  std::fprintf(stderr, "live view at %s (the run goes at real time; Ctrl-C stops it)\n",
               url.c_str());
}

const CLI::Validator& seed_validator() {
  static const CLI::Validator v(
      [](std::string& text) -> std::string {
        std::uint64_t value = 0;
        const char* end = text.data() + text.size();
        const auto [ptr, ec] = std::from_chars(text.data(), end, value);
        if (text.empty() || ec != std::errc() || ptr != end) {
          return "a seed is a whole number from 0 to 18446744073709551615 (got '" + text + "')";
        }
        return {};
      },
      "SEED");
  return v;
}

void add_run_flags(CLI::App& cmd, RunFlags& f) {
  cmd.add_option("--map", f.map, "Map file (x y s dx dy per line); default: the built-in track")
      ->check(CLI::ExistingFile);
  cmd.add_option("--config", f.config,
                 "JSON file overriding any of the default parameters (see `overtake config`)")
      ->check(CLI::ExistingFile);
  cmd.add_option(
         "--scenario", f.scenario,
         "Scenario instead of random traffic: scripted (ego start, cars, timed events) or cut\n"
         "from a recorded run by `overtake cut` (docs/scenarios.md)")
      ->check(CLI::ExistingFile);
  cmd.add_flag(
      "!--no-warm-up", f.opts.warm_up,
      "A scenario cut from a run of a planner from outside carries a warm-up: what the planner\n"
      "was told before the start, played to it first so that it comes in step with the run;\n"
      "with this flag it starts afresh at the scenario's start");
  f.minutes = cmd.add_option("--minutes", f.opts.minutes,
                             "Simulated minutes to drive (default 30, or the scenario's duration)");
  cmd.add_option("--seed", f.opts.seed, "Seed of the traffic and latency draws (0 to 2^64 - 1)")
      ->check(seed_validator())
      ->capture_default_str();
  cmd.add_option("--traffic", f.opts.traffic,
                 "Traffic profile: faithful (the original's rules) or calm (IDM + MOBIL)")
      ->capture_default_str();
  cmd.add_option("--steps-per-call", f.opts.steps_per_call,
                 "World steps per planner reply (1-1000, lock-step); default: drawn from 1-3 per\n"
                 "reply by the seed")
      ->check(CLI::Range(1, 1000));
  cmd.add_option("--json", f.json, "Also write the report as JSON to this file");
  cmd.add_option("--record", f.record,
                 "Record a replay of the run to this file (every step's cars, the planned paths,\n"
                 "the referee's figures and incidents); watch it with `overtake view FILE`");
  cmd.add_option("--checkpoint-every", f.opts.checkpoint_every_s,
                 "With --record: store a world checkpoint every this many simulated seconds\n"
                 "(0: none), from which `overtake cut` starts scenarios")
      ->capture_default_str();
  auto* live =
      cmd.add_flag("--live", f.live_on,
                   "Serve the run's live view (open the printed address in a browser); the run\n"
                   "then goes at real time, and the page stays served after it until Ctrl-C");
  cmd.add_option("--port", f.live.port, "With --live: TCP port of the page (0: any free port)")
      ->capture_default_str()
      ->needs(live);
  cmd.add_option(
         "--host", f.live.host,
         "With --live: address to serve on (loopback by default; the page is for this machine)")
      ->capture_default_str()
      ->needs(live);
  cmd.add_flag("--quiet,-q", f.quiet, "No progress line or extra messages");
}

std::optional<std::filesystem::path> apply_run_flags(RunFlags& f) {
  if (!f.map.empty()) f.opts.map = f.map;
  if (!f.scenario.empty()) {
    f.opts.scenario = f.scenario;
    f.opts.minutes_from_scenario = f.minutes != nullptr && f.minutes->count() == 0;
  }
  if (!f.config.empty()) f.opts.config = f.config;
  if (!f.record.empty()) f.opts.record = f.record;
  if (f.live_on) {
    f.opts.live = f.live;
    f.opts.live->on_listening = print_live_address;
  }
  std::optional<std::filesystem::path> json_out;
  if (!f.json.empty()) json_out = f.json;
  if (json_out && f.opts.record && same_file(*json_out, *f.opts.record)) {
    throw UsageError("--json and --record name the same file (" + f.json +
                     "): one would overwrite the other");
  }
  return json_out;
}

Subcommand register_drive(CLI::App& app) {
  auto f = std::make_shared<RunFlags>();
  auto* cmd = app.add_subcommand(
      "drive", "Drive a car around the highway among traffic and print its scorecard.");
  add_run_flags(*cmd, *f);
  auto* policy = cmd->add_option("--policy", f->opts.policy, policy_help())->capture_default_str();
  auto planners = std::make_shared<PlannerFlags>();
  add_planner_flags(*cmd, *planners, PlannerFlagSet::in_process);
  return {cmd, [f, planners, policy] {
            const auto json_out = apply_run_flags(*f);
            f->opts.planners = catalog_from_flags(*planners);
            f->opts.policy = chosen_policy(*f->opts.planners, f->opts.policy, policy->count() > 0);
            return cmd_drive(f->opts, json_out, f->quiet);
          }};
}

Subcommand register_track(CLI::App& app) {
  struct State {
    core::TrackSpec spec;
    std::string out;
    bool quiet = false;
  };
  auto st = std::make_shared<State>();
  auto* cmd = app.add_subcommand("track",
                                 "Generate a closed highway loop map in the original file format.");
  cmd->add_option("--seed", st->spec.seed, "Seed of the track's shape (0 to 2^64 - 1)")
      ->check(seed_validator())
      ->capture_default_str();
  cmd->add_option("--length-m", st->spec.length_m, "Loop length in metres, about")
      ->capture_default_str();
  cmd->add_option("--straight-spacing-m", st->spec.straight_spacing_m,
                  "Waypoint spacing on straights (bends get closer ones)")
      ->capture_default_str();
  cmd->add_option("--min-spacing-m", st->spec.min_spacing_m, "Smallest waypoint spacing")
      ->capture_default_str();
  cmd->add_option("--max-spacing-m", st->spec.max_spacing_m, "Largest waypoint spacing")
      ->capture_default_str();
  cmd->add_option("-o,--output", st->out, "Write the map here (default: standard output)");
  cmd->add_flag("--quiet,-q", st->quiet, "No summary line");
  return {cmd, [st] {
            std::optional<std::filesystem::path> out;
            if (!st->out.empty()) out = st->out;
            return cmd_track(st->spec, out, st->quiet);
          }};
}

Subcommand register_config(CLI::App& app) {
  struct State {
    std::string file;
    bool defaults = false;
  };
  auto st = std::make_shared<State>();
  auto* cmd = app.add_subcommand(
      "config", "Print the parameters in effect as JSON (the defaults, or with --config applied).");
  cmd->add_option("--config", st->file, "JSON file overriding any default parameters")
      ->check(CLI::ExistingFile);
  cmd->add_flag(
         "--defaults", st->defaults,
         "Print this build's own defaults (the params structs), without reading the built-in\n"
         "config/overtake.json: the file's contents, when regenerating it")
      ->excludes("--config");
  return {cmd, [st] {
            std::optional<std::filesystem::path> path;
            if (!st->file.empty()) path = st->file;
            const Config c = st->defaults ? Config{} : load_config(path);
            std::cout << json_text(config_to_json(c), 2) << "\n";
            return kExitOk;  // run_cli checks that it was written
          }};
}

namespace {

// The commands as the overview lists them (what people do first comes first), each with the
// line that says what it is for.
struct CommandLine {
  const char* name;
  const char* summary;
};
constexpr CommandLine kCommands[] = {
    {"drive", "drive a built-in, plugin or Python planner among traffic; print its scorecard"},
    {"sim", "drive a planner program written for the original simulator (its protocol)"},
    {"serve", "serve a planner over the original protocol, for the original simulator"},
    {"bench", "run policies x traffic x seeds in parallel; summarise with intervals"},
    {"compare", "compare two bench (or risk) folders: paired differences and verdicts"},
    {"hunt", "drive a planner until it fails; cut each failure into a scenario"},
    {"tune", "search a planner's parameters; validate the best on held-out seeds"},
    {"risk", "estimate a rare event's rate per 100 miles (a collision, a near miss)"},
    {"cut", "cut a scenario from a recorded run, at a moment"},
    {"view", "watch a replay in the browser"},
    {"track", "generate a closed highway loop map in the original file format"},
    {"calibrate", "measure the traffic as a planner sees it, against the original's"},
    {"config", "print the parameters in effect as JSON"},
};

// The command of that name, or null (CLI11 2.1 throws for an unknown name).
const CLI::App* find_command(const CLI::App& app, std::string_view name) {
  const auto found = app.get_subcommands([&](const CLI::App* c) { return c->get_name() == name; });
  return found.empty() ? nullptr : found.front();
}

}  // namespace

std::vector<Subcommand> register_commands(CLI::App& app) {
  return {register_drive(app),     register_track(app), register_config(app), register_bench(app),
          register_compare(app),   register_serve(app), register_sim(app),    register_view(app),
          register_calibrate(app), register_cut(app),   register_hunt(app),   register_tune(app),
          register_risk(app)};
}

std::string command_overview(const CLI::App& app) {
  std::string out =
      "usage: overtake <command> [options]\n\n" + app.get_description() + "\n\ncommands:\n";
  for (const CommandLine& c : kCommands) {
    if (find_command(app, c.name) == nullptr) continue;
    std::string line = "  " + std::string(c.name);
    line.resize(14, ' ');
    out += line + c.summary + "\n";
  }
  return out +
         "\n`overtake <command> --help` gives a command's options; `overtake --version` the " +
         "build.\n";
}

std::optional<std::string> nearest_command(const CLI::App& app, std::string_view typed) {
  std::vector<std::string> names;
  for (const CLI::App* command : app.get_subcommands([](const CLI::App*) { return true; }))
    names.push_back(command->get_name());
  return base::nearest_word(names, typed);
}

int run_cli(int argc, const char* const* argv) {
  CLI::App app{
      "overtake: a headless highway simulator with the rules of the Udacity Term 3 simulator,\n"
      "and planners to drive it. Run `overtake <command> --help` for a command's options."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "overtake " + overtake_version());
  const std::vector<Subcommand> commands = register_commands(app);
  // `overtake` alone: what it can do, as `git` does.
  if (argc <= 1) {
    std::cout << command_overview(app);
    return kExitOk;
  }
  // A first word that is no option and no command: most often a command mistyped.
  const std::string_view first = argv[1];
  if (!first.empty() && first[0] != '-' && find_command(app, first) == nullptr) {
    const std::optional<std::string> near = nearest_command(app, first);
    std::cerr << "overtake: '" << first << "' is not a command"
              << (near ? "; did you mean '" + *near + "'?" : std::string("."))
              << " Run `overtake` alone to list the commands.\n";
    return kExitUsage;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? kExitOk : kExitUsage;
  }
  for (const Subcommand& c : commands) {
    if (!c.command->parsed()) continue;
    try {
      const int code = c.run();
      // Whatever a command printed must have reached its reader (`> /dev/full`, a closed
      // pipe): a failed write is a failure, even after a run that went well.
      try {
        flush_stdout_or_throw();
      } catch (const OutputClosed&) {
        return code == kExitOk ? kExitFailure : code;
      } catch (const std::exception& e) {
        std::cerr << "overtake: " << e.what() << "\n";
        return code == kExitOk ? kExitFailure : code;
      }
      return code;
    } catch (const OutputClosed&) {  // `| head`: the reader stopped on purpose
      return kExitFailure;
    } catch (const UsageError& e) {
      std::cerr << "overtake: " << e.what() << "\n";
      return kExitUsage;
    } catch (const std::invalid_argument& e) {
      std::cerr << "overtake: " << e.what() << "\n";
      return kExitUsage;
    } catch (const std::exception& e) {
      std::cerr << "overtake: " << e.what() << "\n";
      return kExitFailure;
    }
  }
  return kExitUsage;
}

}  // namespace overtake::app
