#pragma once
// Whether a cut scenario reproduces the failure it was cut from (`overtake hunt` checks each one
// at once): driven by the same planner, the same kind of failure at the same step. And whether
// a planner is deterministic: two drives of one scenario tell it the same things; a planner
// whose answers differ (threads, clocks, random numbers) is named, with the first that differed.

#include <atomic>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/sim/scorecard.hpp"

namespace overtake::scenarios {

/// A failure as a run booked it: an incident (a contact's first collision incident, or another
/// incident), or the planner's failure at `t_s`.
struct FailureMark {
  std::optional<sim::Incident> incident;
  double t_s = 0.0;
};

/// One scenario driven again.
struct ReproCheck {
  bool reproduced = false;
  bool stopped = false;  ///< the drive was stopped (Ctrl-C): nothing was checked
  std::string text;      ///< "yes", or "no: what happened instead"; with the warm-up's account
  sim::RunReport report;
  /// Each answer of the drive, as the world read it (sim::answer_digest), with its run time.
  std::vector<std::pair<double, std::uint64_t>> answers;
};

/// Drives the scenario at `scenario` with the planner `base` names (its policy, planners and
/// planner log) and says whether `failure` came again: the same incident type (a collision of
/// the same kind) at the same step, or the planner failing at the same step.
[[nodiscard]] ReproCheck check_reproduction(const run::Track& track, const run::Config& config,
                                            run::DriveOptions base,
                                            const std::filesystem::path& scenario,
                                            const FailureMark& failure,
                                            const std::atomic<bool>* stop);

/// "" when two drives of one scenario went the same; else how they differed, the first
/// warm-up cycle whose answers differed when there is one ("told the same twice, it answered
/// differently at warm-up cycle 12 (t 25.48 s)"), else the first incident that differed.
[[nodiscard]] std::string drives_differ(const ReproCheck& a, const ReproCheck& b);

}  // namespace overtake::scenarios
