#pragma once
// What a command line does with a finished drive (`drive`, `sim`): the scorecard, the JSON
// report, where the replay went, and the exit status.

#include <atomic>
#include <filesystem>
#include <optional>
#include <string>

#include "overtake/run/drive.hpp"

namespace overtake::run {

/// Where a finished drive's results go, and how it ran.
struct DriveOutputs {
  std::optional<std::filesystem::path> json;  ///< write the JSON report here
  bool quiet = false;
  double wall_s = 0.0;  ///< the run's wall time, for the scorecard's last line
  std::string mode;     ///< how it ran, appended to the wall time line (may be empty)
};

/// The one post-run path of `drive` and `sim`: prints the scorecard and the wall time, writes
/// the JSON report, says where the replay went, and returns the exit status (0 completed,
/// 1 ended early by the planner, 130 stopped by the user). With a live view, waits until
/// `stop` is set before returning (the page stays served). Throws what
/// base::flush_stdout_or_throw throws when the output did not arrive.
[[nodiscard]] int finish_drive(const DriveResult& result, const DriveOptions& opts,
                               const DriveOutputs& out, const std::atomic<bool>* stop);

}  // namespace overtake::run
