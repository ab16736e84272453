#pragma once
// The scorecard of a run, one stage: the referee (the original's rubric and the strict
// figures), lane tracking, the planner's time and plan status per cycle, and how the run
// ended. It watches the world after every step and sums everything up in a RunReport.

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "overtake/core/plan.hpp"
#include "overtake/core/quantile_sketch.hpp"
#include "overtake/core/road.hpp"
#include "overtake/sim/frame.hpp"
#include "overtake/sim/referee.hpp"
#include "overtake/sim/safety.hpp"
#include "overtake/sim/warm_up.hpp"

namespace overtake::sim {

class World;

/// How a run ended.
enum class RunEnd : std::uint8_t {
  completed,       ///< it went its full duration
  stopped,         ///< the user stopped it (Ctrl-C, SIGTERM)
  planner_failed,  ///< the planner could not go on (it threw, stalled, disconnected, ...)
};

/// "completed", "stopped", "planner_failed".
[[nodiscard]] std::string_view to_string(RunEnd end);

/// How a run ended, and why when it ended early.
struct RunOutcome {
  RunEnd end = RunEnd::completed;
  double t_s = 0.0;    ///< simulated time when it ended
  std::string reason;  ///< for planner_failed: what went wrong (e.g. "the planner stalled ...")
  [[nodiscard]] bool ended_early() const { return end != RunEnd::completed; }
  friend bool operator==(const RunOutcome&, const RunOutcome&) = default;
};

/// The report's one-line account of an early end: "" when the run completed, "stopped", or
/// "planner failed at t = 12.340000 s: <reason>".
[[nodiscard]] std::string ended_early_text(const RunOutcome& outcome);

/// What the planner time of a cycle measures.
enum class CycleClock : std::uint8_t {
  thread_cpu,  ///< an in-process planner: its thread's CPU time
  round_trip,  ///< a remote planner: the wall time from telemetry sent to reply read
};

/// "thread_cpu" or "round_trip" (the report's `timing.clock`).
[[nodiscard]] std::string_view to_string(CycleClock clock);

/// Planner compute time per cycle (microseconds). Not part of the determinism promise.
/// p50 and p99 come from a fixed-memory sketch, within 1% of the exact order statistics
/// (core::QuantileSketch); the maxima are exact. In-process planners are timed on the
/// thread's CPU clock, so that other processes on a shared machine do not inflate the
/// figures; the wall-clock p99 and max are kept beside them. A remote planner's cycle is the
/// wall-clock round trip of a telemetry and its reply (its time plus the transport's).
struct PlannerTiming {
  double p50_us = 0.0;
  double p99_us = 0.0;
  double max_us = 0.0;
  long cycles = 0;
  CycleClock clock = CycleClock::round_trip;
  double wall_p99_us = 0.0;  ///< wall-clock figures (equal to the above for round_trip)
  double wall_max_us = 0.0;
};

/// Everything a run reports (SI; conversions at the report's edge).
struct RunReport {
  double distance_m = 0.0;
  double duration_s = 0.0;
  double mean_speed_mps = 0.0;
  double best_incident_free_m = 0.0;
  std::vector<Incident> incidents;
  std::array<int, kIncidentTypeCount> incident_counts{};
  /// The collisions as contacts: one per car the ego touched, however long (the rubric's
  /// `incident_counts` count one collision per second of contact).
  std::vector<Contact> contacts;
  /// Outside-of-lane counts under the same rule on the exact d (the rubric uses the
  /// original's d on the waypoint chords); a figure, not an incident.
  int exact_outside_lane = 0;
  Peaks peak;
  int lane_changes = 0;
  std::vector<double> time_in_lane_s;  ///< index = lane
  /// Near misses: least TTC and headway, time below their thresholds, episodes.
  SafetySummary safety;
  PlannerTiming timing;
  long planner_cycles = 0;
  /// Cycles by how the planner found its path (indexed by core::PlanStatus), and the reason
  /// the planner gave the first time it left normal planning. Only the cycles whose status
  /// is known count here.
  core::PlanStatusCounts plan_status_cycles{};
  std::string first_plan_reason;
  /// Cycles whose planner did not say how it planned (a program over the protocol answers
  /// points only). They count in planner_cycles, not in plan_status_cycles.
  long plan_status_unknown_cycles = 0;
  /// Lane changes the planner's decision layer chose and its path layer did not take (cycles
  /// with core::ChangeDeclined for_cost / for_safety; built-in planners say, others count 0).
  long changes_declined_for_cost = 0;
  long changes_declined_for_safety = 0;
  /// False when no cycle said how it was planned, though some were counted: the run's plan
  /// statuses are unknown (not all normal), and reports show none.
  [[nodiscard]] bool plan_status_known() const {
    return plan_status_unknown_cycles == 0 || planner_cycles > plan_status_unknown_cycles;
  }
  RunOutcome outcome;
  /// A cut scenario's warm-up, when one was played before the run (RunOptions::warm_up).
  std::optional<WarmUpResult> warm_up;
};

/// Tracks lane changes and time per lane from the ego's d (with hysteresis: the lane counts
/// as changed once the car is within `settle_m` of another lane's centre).
class LaneTracker {
 public:
  explicit LaneTracker(const core::RoadParams& road, double settle_m = 1.0);
  void observe(double d_m, double dt_s);
  [[nodiscard]] int lane_changes() const { return changes_; }
  [[nodiscard]] const std::vector<double>& time_in_lane_s() const { return time_in_lane_s_; }
  void archive(core::StateArchive& ar);
  /// Forgets the lane changes and time per lane counted, keeping the lane it is settled in.
  void forget_counts();

 private:
  core::RoadParams road_;
  double settle_m_;
  int settled_ = -1;  // -1 until the car first settles in a lane
  int changes_ = 0;
  std::vector<double> time_in_lane_s_;
};

/// The scorecard stage. Made from the world before its first step; told every step
/// (observe_step) and every planner cycle (count_cycle), in order.
class Scorecard {
 public:
  explicit Scorecard(const World& world);

  /// After each world step: the safety monitor sees the ego and the cars (and classifies a
  /// contact), then the referee and the lane tracker see the ego.
  void observe_step(const World& world);
  /// After each planner cycle: its status (or that it is unknown), its time on the run's clock
  /// and on the wall clock.
  void count_cycle(const core::PlanResult& plan, double cycle_us, double wall_us);

  [[nodiscard]] const Referee& referee() const { return referee_; }
  [[nodiscard]] const SafetyMonitor& safety() const { return safety_; }
  /// The contacts so far, in the order they began (each classified at its first step).
  [[nodiscard]] const std::vector<Contact>& contacts() const { return contacts_; }
  /// The world's state and the running figures, as a frame for those who watch (`out` is
  /// reused, so that a long run does not allocate per step).
  void fill_frame(const World& world, Frame& out) const;
  /// The report of the run so far, ended as `outcome` says, timed on `clock`. Its duration
  /// counts from the world's time when the scorecard was made (a scenario cut from a run
  /// starts on that run's clock).
  [[nodiscard]] RunReport report(const World& world, RunOutcome outcome, CycleClock clock) const;

  /// Writes or restores everything it counts (a checkpoint), but the planner's timing: that
  /// is not part of the determinism promise, and after a restore it counts afresh.
  void archive(core::StateArchive& ar);
  /// Writes or restores the contacts (a part of its own, after the stepper's: checkpoints of
  /// builds before contacts end without it, and restore with none). Call after archive().
  void archive_contacts(core::StateArchive& ar);
  /// A cut scenario's scorecard, made afresh at its start: its referee, safety monitor and lane
  /// tracker go on from `run`'s (the run restored from the checkpoint), having forgotten what
  /// they counted, so that the rubric's blocks, groups and latches fall at the steps they fell
  /// in the run, and a contact is classified from the same history.
  void continue_rubric(const Scorecard& run);

 private:
  Referee referee_;
  SafetyMonitor safety_;
  LaneTracker lanes_;
  std::vector<Contact> contacts_;
  double step_s_;
  double start_s_ = 0.0;  // the world's time when the scorecard was made
  // Timing in fixed memory: a 7-day run has 15 million cycles.
  core::QuantileSketch cycle_us_;
  core::QuantileSketch wall_us_;
  core::PlanStatusCounts status_cycles_{};
  std::string first_reason_;
  long unknown_status_cycles_ = 0;  // cycles whose planner did not say how it planned
  long declined_for_cost_ = 0;
  long declined_for_safety_ = 0;
};

}  // namespace overtake::sim
