#pragma once
// How subcommands join the `overtake` command line: each command file registers its
// options on the CLI11 app and returns what to run when that subcommand is chosen.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "overtake/app/commands.hpp"

namespace overtake::app {

/// Exit codes of the command line.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;  ///< the work failed (bad file, planner failure, ...)
inline constexpr int kExitUsage = 2;    ///< bad flags or values

/// A registered subcommand: chosen when `command` was parsed; `run` returns the exit code.
/// `run` may throw UsageError (exit 2) or any std::exception (exit 1); the message is printed.
struct Subcommand {
  CLI::App* command = nullptr;
  std::function<int()> run;
};

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

/// A seed: a whole number from 0 to 2^64 - 1, written out; anything else (-1, 2^64, 1e3) is
/// refused with the range, never wrapped or saturated.
[[nodiscard]] const CLI::Validator& seed_validator();

/// Standard output's reader has gone (EPIPE: `overtake config | head`). Not an error to
/// report: the reader stopped reading on purpose; run_cli exits without a message.
class OutputClosed : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Flushes standard output and throws std::runtime_error when anything written to it was lost
/// (a full disk, an error of the device): a command whose output did not arrive must not exit
/// 0. Throws OutputClosed when the reader of a pipe has gone.
void flush_stdout_or_throw();

/// True when `a` and `b` name the same file (after resolving . and .., symbolic links of
/// existing parts, and hard links of existing files).
[[nodiscard]] bool same_file(const std::filesystem::path& a, const std::filesystem::path& b);

/// The flags of every command that runs a drive (`drive`, `sim`): --map, --config,
/// --scenario, --minutes, --seed, --traffic, --steps-per-call, --json, --record, --live with
/// --port and --host, --quiet.
struct RunFlags {
  DriveOptions opts;
  std::string map, config, json, scenario, record;
  LiveOptions live;
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

/// Whether progress lines may be drawn (stderr is a terminal).
[[nodiscard]] bool stderr_is_terminal();
/// A comma-separated list of names (policies, traffic profiles); spaces and empty items
/// are dropped.
[[nodiscard]] std::vector<std::string> split_list(const std::string& text);
/// Throws UsageError naming `flag` and the name when `names` holds one twice: a list flag
/// (--policies, --traffic, --maps) names each thing once, or its runs would be driven, and
/// their failures counted, twice.
void check_unique_names(const std::vector<std::string>& names, const std::string& flag);
/// The --policy flag's help: every built-in policy with its summary.
[[nodiscard]] std::string policy_help();

}  // namespace overtake::app
