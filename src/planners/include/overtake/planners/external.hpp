#pragma once
// A planner that is not an in-process policy: a planner program over the protocol (lock-step
// or real time) or a remote planner, reached through the loop that runs it on the world.

#include <functional>
#include <string>

#include "overtake/sim/run.hpp"

namespace overtake::sim {
class World;
}  // namespace overtake::sim

namespace overtake::planners {

/// Runs the loop of a run whose planner is not an in-process policy (e.g. a remote planner
/// over the protocol, lock-step or real time) on the world the drive built.
using RunLoop = std::function<sim::RunReport(sim::World& world, const sim::RunOptions& run)>;

/// A planner reached through a RunLoop, and how the report names it.
struct ExternalPlanner {
  RunLoop loop;
  std::string name;     ///< the report's `policy` (default: the address)
  std::string address;  ///< e.g. the remote planner's ws:// URL (shown on the scorecard)
  /// Lock-step (run_drive: a recording keeps its exact answers, a cut scenario's warm-up is
  /// played to it); false in real time.
  bool lock_step = true;
};

}  // namespace overtake::planners
