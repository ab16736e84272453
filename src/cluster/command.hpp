#pragma once
// Running one of Slurm's client commands (sbatch, squeue, scontrol) for cluster/slurm.cpp.

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace overtake::cluster::command_detail {

struct CommandResult {
  int status = -1;  ///< exit status; -1 when it could not start, timed out or was signalled
  std::string out;
  std::string err;  ///< its standard error, or why it did not run
};

/// Runs argv (looked up in PATH) with standard input from /dev/null, gathering its output,
/// for at most `timeout_s`; a command that takes longer is killed.
[[nodiscard]] CommandResult run_command(const std::vector<std::string>& argv, double timeout_s);

/// `s` without the blanks at either end.
[[nodiscard]] std::string trimmed(std::string_view s);

/// The last line of `text` that is not empty, at most `max` characters.
[[nodiscard]] std::string last_line(std::string_view text, std::size_t max = 300);

/// Why argv failed, in one line: "sbatch: <the last line it wrote>" or its exit status.
[[nodiscard]] std::string command_error(const std::vector<std::string>& argv,
                                        const CommandResult& r);

}  // namespace overtake::cluster::command_detail
