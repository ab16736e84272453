#pragma once
// The trajectory layer of the reference planner (Werling et al. 2010): jerk-minimising
// polynomial candidates in Frenet space, lateral (quintics to a lane centre) times
// longitudinal (quartics to several end speeds over several end times; quintics that follow
// a car ahead; a jerk-limited braking profile), started from the exact state where the kept
// path ends. Each candidate is costed, then, cheapest first, checked against the
// predictions for collision with margins and, converted to Cartesian on the reference line,
// for speed, total acceleration and jerk over 0.1 s windows; the first that passes wins.
// When none passes, the one that collides latest, or the braking fallback, is driven.

#include <vector>

#include "overtake/core/plan.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/road.hpp"
#include "overtake/planner/params.hpp"
#include "overtake/planner/reference/frenet.hpp"
#include "overtake/planner/reference/polynomial.hpp"
#include "overtake/planner/reference/prediction.hpp"

namespace overtake::planner::reference {

/// A longitudinal motion s(t): a polynomial, or the jerk-limited braking profile.
struct Longitudinal {
  Polynomial1d poly;
  BrakingProfile brake;
  bool braking = false;
  [[nodiscard]] Motion1d at(double t) const { return braking ? brake.at(t) : poly.at(t); }
};

/// One candidate: lateral and longitudinal motions from the same start (t = 0).
struct Trajectory {
  Polynomial1d lateral;
  Longitudinal longitudinal;
  int end_lane = 0;
  [[nodiscard]] FrenetState at(double t) const;
};

/// What the trajectory layer is asked for.
struct TrajectoryRequest {
  FrenetState start;           ///< state at the end of the kept path (s unwrapped)
  double start_delay_s = 0.0;  ///< time from the cars' observation to `start`
  int target_lane = 1;         ///< behaviour's lane
  double wanted_speed_mps = 0.0;
  /// Time the ego has already spent in a lane-line band, without a break, up to `start`.
  double band_time_s = 0.0;
  const std::vector<CarPrediction>* cars = nullptr;
  /// Where the ego was (or will have been, along the kept path) 1, 2 and 3 check steps
  /// before `start`, newest first: the acceleration and jerk checks across the joint with
  /// the path already driven use them. Fewer (or none): the candidate is extended backwards.
  std::vector<FrenetState> history;
};

/// True when `d_m` lies within `half_width_m` of a line between two lanes.
[[nodiscard]] bool in_line_band(double d_m, double half_width_m, const core::RoadParams& road);

/// How the chosen trajectory was found.
enum class PlanStatus {
  feasible,   ///< passed every check
  least_bad,  ///< none passed: the one that collides latest
  fallback,   ///< none passed: jerk-limited braking
};

/// Why a candidate costs what it costs: the terms of its cost, each already weighted
/// (ReferenceTrajectoryParams names the weights). Lower is better; a term may be negative
/// (progress, when the candidate goes farther than the wanted speed would).
struct TrajectoryCost {
  double lateral_jerk = 0.0;       ///< lat_jerk_weight x the lateral motion's jerk integral
  double lateral_time = 0.0;       ///< lat_time_weight x its duration (s); 0 when holding the lane
  double off_target_lane = 0.0;    ///< lane_weight x lanes between its end lane and behaviour's
  double linger = 0.0;             ///< linger_weight x its longest lane-line stay beyond the budget
  double progress = 0.0;           ///< progress_weight x metres short of the wanted speed's
  double longitudinal_jerk = 0.0;  ///< lon_jerk_weight x the longitudinal jerk integral
  double lane = 0.0;        ///< soft cost of the end lane's cars (RSS gap, rear room), full horizon
  double early_lane = 0.0;  ///< when changing lanes: the start lane's soft cost, early window
  /// The candidate's cost: the terms added as the planner adds them (lateral, then
  /// longitudinal, then the lanes'), so that it equals TrajectoryPlan::cost exactly.
  [[nodiscard]] double total() const {
    double lateral = lateral_jerk + lateral_time + off_target_lane;
    lateral += linger;
    const double longitudinal = progress + longitudinal_jerk;
    double c = lateral + longitudinal + lane;
    c += early_lane;
    return c;
  }
};

/// The chosen trajectory and how it was found.
struct TrajectoryPlan {
  Trajectory trajectory;
  PlanStatus status = PlanStatus::fallback;
  double cost = 0.0;          ///< the chosen candidate's cost (0 for the braking fallback)
  TrajectoryCost cost_terms;  ///< ... and its terms: why it won (all 0 for the fallback)
  int candidates = 0;         ///< combinations costed
  int collision_checks = 0;
  int kinematic_checks = 0;
  int collision_failures = 0;    ///< candidates that failed the collision check
  int blocking_car = -1;         ///< id of the car the cheapest candidate would have hit
  double blocking_time_s = 0.0;  ///< ... and when
  /// A change to the requested lane (another than the start lane) that this plan does not
  /// take: for its cost when some candidate into that lane passes every check (staying was
  /// cheaper), for safety when none does; `no` when the plan goes there or none was asked.
  core::ChangeDeclined change_declined = core::ChangeDeclined::no;
};

/// Sample buffers one plan leaves for the next: kept by the policy, a cycle's samples reuse
/// the last cycle's memory instead of asking malloc for about a hundred buffers. It holds no
/// figure a plan reads: every buffer taken from it is filled before it is read.
struct TrajectoryScratch {
  std::vector<std::vector<double>> spare;
};

/// Chooses this cycle's trajectory. Never fails: the braking fallback always exists.
/// `scratch`, when given, lends the plan its buffers and gets them back.
[[nodiscard]] TrajectoryPlan plan_trajectory(const LaneFrame& line,
                                             const TrajectoryRequest& request,
                                             const ReferenceParams& params,
                                             const core::RoadParams& road,
                                             const core::CarFootprint& car,
                                             TrajectoryScratch* scratch = nullptr);

/// Result of the Cartesian check of one trajectory.
struct KinematicReport {
  bool ok = true;
  double first_violation_s = 1e9;  ///< time of the first sample over a limit
  double peak_speed_mps = 0.0;
  double peak_accel_mps2 = 0.0;  ///< over 0.1 s windows, tangential and normal together
  double peak_jerk_mps3 = 0.0;
};

/// Checks speed, total acceleration and jerk of `t` converted to Cartesian on the line,
/// sampled every check_step_s over the horizon, against the limits.
[[nodiscard]] KinematicReport check_kinematics(const Trajectory& t, const LaneFrame& line,
                                               const ReferenceTrajectoryParams& p);

/// Result of the collision check of one trajectory.
struct CollisionReport {
  bool ok = true;
  double first_collision_s = 1e9;
  int car_id = -1;
  bool from_behind = false;  ///< the car comes from behind (it does not see the ego in time)
};

/// Checks `t` against the predicted cars (observed `start_delay_s` before t = 0) with the
/// margins, every car of footprint `car`; `m_per_unit_s` (metres of road per unit of s) converts
/// s to metres along the road. Cars already following the ego in its lane are left to follow; a
/// car the ego moves in front of must have room to stop closing (rear_room).
[[nodiscard]] CollisionReport check_collisions(const Trajectory& t,
                                               const std::vector<CarPrediction>& cars,
                                               double start_delay_s, double m_per_unit_s,
                                               const ReferenceParams& p,
                                               const core::RoadParams& road,
                                               const core::CarFootprint& car);

}  // namespace overtake::planner::reference
