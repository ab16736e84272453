#pragma once
// Drives a world with a planner in lock-step and sums up the run.

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "overtake/core/telemetry.hpp"
#include "overtake/sim/referee.hpp"
#include "overtake/sim/world.hpp"

namespace overtake::sim {

/// A planner as the loop sees it: telemetry in, path points out. It may throw
/// PlannerFailure to end the run (e.g. a remote planner that stalled); the report so far is
/// kept.
using PlannerFn = std::function<std::vector<core::Vec2>(const core::Telemetry&)>;

/// Raised by a PlannerFn that cannot go on.
struct PlannerFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// How long and how to run.
struct RunOptions {
  double duration_s = 1800.0;
  /// Steps the world advances after each reply; unset: drawn from the params' range by seed.
  std::optional<int> steps_per_call;
  std::uint64_t seed = 1;  ///< for the latency draw
  /// Called now and then with the simulated time (for progress displays).
  std::function<void(double t_s, double distance_m)> progress;
  /// When set (and true), the run stops at the next cycle with ended_early = "stopped".
  const std::atomic<bool>* stop = nullptr;
};

/// Planner compute time per cycle (microseconds). Not part of the determinism promise.
struct PlannerTiming {
  double p50_us = 0.0;
  double p99_us = 0.0;
  double max_us = 0.0;
  long cycles = 0;
};

/// Everything a run reports (SI; conversions at the report's edge).
struct RunReport {
  double distance_m = 0.0;
  double duration_s = 0.0;
  double mean_speed_mps = 0.0;
  double best_incident_free_m = 0.0;
  std::vector<Incident> incidents;
  std::array<int, kIncidentTypeCount> incident_counts{};
  Peaks peak;
  int lane_changes = 0;
  std::vector<double> time_in_lane_s;  ///< index = lane
  PlannerTiming timing;
  long planner_cycles = 0;
  /// Empty when the run went its full duration; else why it ended early.
  std::string ended_early;
};

/// Runs the loop: telemetry -> planner -> path -> K steps, until the duration is reached or
/// the planner fails. Returns the report (also on failure).
[[nodiscard]] RunReport run_drive(World& world, const PlannerFn& planner, const RunOptions& opts);

class LaneTracker;

/// The report of a world as it stands (for loops other than run_drive, e.g. real time).
/// `cycle_us`: planner time of each cycle; `ended_early`: empty, or why the run stopped.
[[nodiscard]] RunReport summarize(const World& world, const LaneTracker& lanes,
                                  std::vector<double> cycle_us, std::string ended_early);

/// Tracks lane changes and time per lane from the ego's d (with hysteresis: the lane counts
/// as changed once the car is within `settle_m` of another lane's centre).
class LaneTracker {
 public:
  explicit LaneTracker(const core::RoadParams& road, double settle_m = 1.0);
  void observe(double d_m, double dt_s);
  [[nodiscard]] int lane_changes() const { return changes_; }
  [[nodiscard]] const std::vector<double>& time_in_lane_s() const { return time_in_lane_s_; }

 private:
  core::RoadParams road_;
  double settle_m_;
  int settled_ = -1;  // -1 until the car first settles in a lane
  int changes_ = 0;
  std::vector<double> time_in_lane_s_;
};

}  // namespace overtake::sim
