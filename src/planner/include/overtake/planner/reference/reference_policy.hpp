#pragma once
// The reference planner: the layers (map: the smooth reference line; prediction; behaviour;
// trajectory) driven once per cycle. It remembers its own last plan as Frenet states per
// point, so that from the number of points the simulator consumed it knows the exact state
// at the car and at every kept point; each new plan starts from the exact state (position,
// velocity, acceleration) where the kept prefix ends, so the joint is C2-continuous whatever
// the latency.

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "overtake/core/reference_line.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/planner/params.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/planner/reference/behaviour.hpp"
#include "overtake/planner/reference/frenet.hpp"
#include "overtake/planner/reference/prediction.hpp"
#include "overtake/planner/reference/trajectory.hpp"

namespace overtake::planner::reference {

/// The core status of a trajectory plan's status (feasible is normal).
[[nodiscard]] core::PlanStatus to_core(PlanStatus status);
/// Why a plan is not feasible, in a few words (empty when it is).
[[nodiscard]] std::string status_reason(const TrajectoryPlan& plan);

/// A decision given to the reference policy from outside (a learned agent's meta-action, say):
/// the lane to drive in and the speed wanted, in place of its behaviour layer's. Prediction
/// and the trajectory layer work as always, so that the path stays within the limits and
/// clear of the predicted cars: a lane change the trajectory layer cannot take safely is not
/// taken (the target lane then follows the lane it keeps), and a car ahead is followed.
struct DrivingCommand {
  int target_lane = 1;     ///< clamped to the road's lanes
  double speed_mps = 0.0;  ///< clamped to [0, the behaviour's cruise speed]
};

/// The reference policy's map geometry: its own smoothed line near the waypoints and the lane
/// frame on it. Immutable and a function of the map's line, the smoothing and the road only,
/// so that many policies on one map (the worlds of a learning environment) build it once.
struct ReferenceGeometry {
  const core::ReferenceLine* base = nullptr;  ///< the map's line it was built from
  double line_smoothing_m3 = 0.0;
  core::RoadParams road;
  std::shared_ptr<const core::ReferenceLine> smooth_line;
  LaneFrame frame;  ///< on smooth_line, d as the original measures it
};

/// The geometry a ReferencePolicy on `line` with `params` builds for itself.
[[nodiscard]] std::shared_ptr<const ReferenceGeometry> make_reference_geometry(
    const core::ReferenceLine& line, const PlannerParams& params);

/// The reference policy ("reference").
class ReferencePolicy final : public Policy {
 public:
  ReferencePolicy(const core::ReferenceLine& line, const PlannerParams& params);
  /// The same on a geometry built before (make_reference_geometry of this very line and of
  /// params with the same smoothing and road; anything else throws std::invalid_argument).
  ReferencePolicy(const core::ReferenceLine& line, const PlannerParams& params,
                  std::shared_ptr<const ReferenceGeometry> geometry);
  [[nodiscard]] core::PlanResult plan(const core::Telemetry& telemetry) override;
  /// The same with buffers lent by the caller instead of the policy's own: many policies
  /// planned in turn on one thread (a learning environment's worlds) share one set, which
  /// stays in the core's cache. The plan is the same either way (the buffers hold no state).
  [[nodiscard]] core::PlanResult plan(const core::Telemetry& telemetry, TrajectoryScratch& scratch);
  /// What carries from one cycle to the next: the points sent and their states, the states
  /// driven, the cars' tracks and the behaviour's state.
  bool archive_state(core::StateArchive& ar) override;

  /// From the next plan() on, drive by `command` instead of the behaviour layer's decision
  /// (nullopt: by the behaviour layer again). Not part of the archived state.
  void set_command(const std::optional<DrivingCommand>& command) { command_ = command; }

  /// The last cycle's behaviour decision (for tests and tools).
  [[nodiscard]] const BehaviourDecision& last_decision() const { return decision_; }
  /// How the last cycle's trajectory was found.
  [[nodiscard]] PlanStatus last_status() const { return status_; }
  /// The last cycle's trajectory plan.
  [[nodiscard]] const TrajectoryPlan& last_plan() const { return plan_; }
  /// The last cycle's predictions.
  [[nodiscard]] const std::vector<CarPrediction>& last_predictions() const { return predictions_; }
  /// False when the last cycle could not place the car on its own previous plan.
  [[nodiscard]] bool last_synced() const { return synced_; }
  /// Frenet states of the points sent last (s unwrapped).
  [[nodiscard]] const std::vector<FrenetState>& planned_states() const { return states_; }

 private:
  [[nodiscard]] FrenetState observed_state(const core::Telemetry& t) const;
  std::size_t sync_to(const core::Telemetry& t, FrenetState& car);
  void take_command(const DrivingCommand& c);
  core::PlanResult commit(std::vector<FrenetState> states, std::vector<core::Vec2> points,
                          const FrenetState& car, std::size_t n_points);
  [[nodiscard]] std::vector<FrenetState> history_before(const std::vector<FrenetState>& states,
                                                        const FrenetState& start) const;
  /// Sent point `i` as the simulator read it.
  [[nodiscard]] core::Vec2 sent_as_read(std::size_t i) const;

  const core::ReferenceLine& line_;  // the map's line (the loop's s)
  // The planner's own line near the waypoints and the frame on it (shared and immutable:
  // copies of the policy keep the frame valid).
  std::shared_ptr<const ReferenceGeometry> geometry_;
  const LaneFrame& frame_;  // geometry_->frame: d as the original measures it
  core::RoadParams road_;
  double step_s_;           // the world's step: spacing of path points in time
  core::CarFootprint car_;  // every car's, the ego's included
  ReferenceParams p_;
  std::vector<FrenetState> states_;  // state at each point sent last cycle
  std::vector<FrenetState> driven_;  // the last states the car went through, oldest first
  // Those points as sent; as the simulator read them (rounded like the wire) once
  // sent_rounded_. Of all of them the next cycle reads only the one or two where the car is, so
  // they are rounded when read (or archived), not all when sent.
  std::vector<core::Vec2> sent_;
  bool sent_rounded_ = true;
  FrenetState origin_;  // the car's state when they were sent
  bool have_plan_ = false;
  double band_time_s_ = 0.0;  // time in a lane-line band without a break, at the car
  bool synced_ = false;
  std::vector<CarTrack> tracks_;
  std::vector<CarPrediction> predictions_;
  BehaviourState behaviour_;
  BehaviourDecision decision_;
  PlanStatus status_ = PlanStatus::feasible;
  TrajectoryPlan plan_;
  TrajectoryScratch scratch_;              // buffers one plan leaves for the next; no state
  std::optional<DrivingCommand> command_;  // a decision from outside (set_command)
};

}  // namespace overtake::planner::reference
