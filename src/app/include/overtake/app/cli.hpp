#pragma once
// How subcommands join the `overtake` command line: each command file registers its
// options on the CLI11 app and returns what to run when that subcommand is chosen.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "overtake/batch/bench.hpp"
#include "overtake/cluster/slurm.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/drive.hpp"

namespace overtake::app {

/// A registered subcommand: chosen when `command` was parsed; `run` returns the exit code.
/// `run` may throw UsageError (exit 2) or any std::exception (exit 1); the message is printed.
struct Subcommand {
  CLI::App* command = nullptr;
  std::function<int()> run;
};

/// Every command, registered on `app`.
[[nodiscard]] std::vector<Subcommand> register_commands(CLI::App& app);

/// What `overtake` alone prints: a usage line, then each command with the first line of its
/// description.
[[nodiscard]] std::string command_overview(const CLI::App& app);

/// The command whose name is nearest to `typed` (fewest single-character edits), when it is
/// near enough to be a slip of the keyboard.
[[nodiscard]] std::optional<std::string> nearest_command(const CLI::App& app,
                                                         std::string_view typed);

/// The `overtake` command line. Returns the process exit code: 0 success, 1 failure, 2 bad
/// usage.
[[nodiscard]] int run_cli(int argc, const char* const* argv);

/// Registration functions, one per command file.
Subcommand register_drive(CLI::App& app);
Subcommand register_track(CLI::App& app);
Subcommand register_config(CLI::App& app);
Subcommand register_bench(CLI::App& app);
Subcommand register_compare(CLI::App& app);
Subcommand register_cut(CLI::App& app);
Subcommand register_hunt(CLI::App& app);
Subcommand register_serve(CLI::App& app);
Subcommand register_sim(CLI::App& app);
Subcommand register_view(CLI::App& app);
Subcommand register_calibrate(CLI::App& app);
Subcommand register_tune(CLI::App& app);
Subcommand register_risk(CLI::App& app);

/// A seed: a whole number from 0 to 2^64 - 1, written out; anything else (-1, 2^64, 1e3) is
/// refused with the range, never wrapped or saturated.
[[nodiscard]] const CLI::Validator& seed_validator();

/// The flags of every command that runs a drive (`drive`, `sim`): --map, --config,
/// --scenario, --minutes, --seed, --traffic, --steps-per-call, --json, --record, --live with
/// --port and --host, --quiet.
struct RunFlags {
  run::DriveOptions opts;
  std::string map, config, json, scenario, record;
  run::LiveOptions live;
  bool live_on = false;
  bool quiet = false;
  CLI::Option* minutes = nullptr;
};

/// Registers the run flags on `cmd`.
void add_run_flags(CLI::App& cmd, RunFlags& flags);

/// The drive options the flags give (with the live view's address printed on stderr), and
/// where the JSON report goes. UsageError when --json and --record name the same file.
[[nodiscard]] std::optional<std::filesystem::path> apply_run_flags(RunFlags& flags);

/// Says on stderr where a run's live view is served (LiveOptions::on_listening).
void print_live_address(const std::string& url);

/// Registers the planner flags on `cmd`.
void add_planner_flags(CLI::App& cmd, planners::PlannerFlags& flags,
                       planners::PlannerFlagSet which);

/// Registers --slurm TASKS and the --slurm-* flags on `cmd` (`what`: "bench", "hunt").
/// `merge`: how the shards are merged by hand (default: "WHAT merge").
void add_slurm_flags(CLI::App& cmd, cluster::SlurmOptions& options, const std::string& what,
                     const std::string& merge = "");
/// Whether --slurm was given; UsageError when a --slurm-* flag was given without it.
[[nodiscard]] bool slurm_requested(const CLI::App& cmd);
/// The options given to `cmd`, as each task gives them again (--name=value; flags as --name),
/// without the --slurm flags and those whose long name is in `leave_out`.
[[nodiscard]] std::vector<std::string> task_arguments(const CLI::App& cmd,
                                                      const std::set<std::string>& leave_out);

/// The --policy flag's help: every built-in policy with its summary.
[[nodiscard]] std::string policy_help();

}  // namespace overtake::app
