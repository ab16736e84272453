#pragma once
// What the files of `overtake risk` share (batch/risk*.cpp): the loaded inputs of a run and
// the simulator as a splitting system.

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>

#include "overtake/batch/risk.hpp"
#include "overtake/eval/splitting.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/sim/traffic.hpp"

namespace overtake::batch::risk_detail {

/// Everything a base run needs, loaded once.
struct RunInputs {
  std::shared_ptr<const run::Track> track;
  run::Config config;
  const planners::PlannerEntry* entry = nullptr;
  sim::TrafficProfile profile{};
  double minutes = 10.0;
  RiskEvent event;
  const RiskParams* params = nullptr;
};

/// Thrown by a path's step once the stop flag is set: the base run is dropped.
struct Interrupted {};

/// A base run of the world with seed `seed` and the entry's in-process policy. A path whose
/// policy throws ends there (its step says `ended`), and the failure is appended to `failures`
/// (the base path as path 0, a copy by its number among the copies made, from 1).
[[nodiscard]] std::unique_ptr<eval::SplitSystem> make_world_branches(
    const RunInputs& in, std::uint64_t seed, const std::atomic<bool>* stop,
    std::vector<RiskFailure>* failures);

/// A plain run of a planner from outside (a program, a plugin, Python) as the drive runs it,
/// its events counted from the report; nullopt when it was stopped. A run its planner ended
/// counts up to the failure, which is set in `failure` (the planner's failure, not the event).
[[nodiscard]] std::optional<eval::SplitTally> plain_run(const RunInputs& in, const RiskSpec& spec,
                                                        std::size_t index, std::uint64_t seed,
                                                        const std::atomic<bool>* stop,
                                                        std::optional<RiskFailure>& failure);

[[nodiscard]] double miles_of(double metres);

/// risk_runs_planned with the risk params already loaded.
[[nodiscard]] std::size_t planned_runs(const RiskSpec& spec, const RiskParams& params);

/// The folder of the cut events, under --out.
inline constexpr const char* kEventsDir = "events";

/// Cuts the first RiskSpec::scenarios events of the base runs into scenarios (OUT/events) by
/// a hunt over their runs' seeds, and sets RiskOutcome::cut or cut_note. Nothing is thrown:
/// a hunt that fails is said in cut_note, the estimate is kept whole.
void cut_events(const RiskSpec& spec, RiskOutcome& outcome, const std::atomic<bool>* stop);

}  // namespace overtake::batch::risk_detail
