#pragma once
// How subcommands join the `overtake` command line: each command file registers its
// options on the CLI11 app and returns what to run when that subcommand is chosen.

#include <CLI/CLI.hpp>
#include <functional>
#include <vector>

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
Subcommand register_serve(CLI::App& app);
Subcommand register_sim(CLI::App& app);
Subcommand register_view(CLI::App& app);
Subcommand register_calibrate(CLI::App& app);

/// Whether progress lines may be drawn (stderr is a terminal).
[[nodiscard]] bool stderr_is_terminal();

}  // namespace overtake::app
