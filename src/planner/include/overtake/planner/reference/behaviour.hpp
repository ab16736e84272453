#pragma once
// The behaviour layer of the reference planner: which lane to aim for and how fast, by a
// cost over every lane (the speed it allows over the next seconds, a car closing fast from
// behind, the lanes to cross; a far lane is reached through the middle one), safety gaps
// ahead (RSS longitudinal distance, Shalev-Shwartz et al. 2017, with the ego's braking
// limited in jerk) and behind (a follower that reacts late and brakes hard), and hysteresis
// so that it never weaves between lanes. Held up and boxed in by cars that pace it in the
// next lane while a clearly cheaper lane lies beyond, it drops back behind them (gap seeking).

#include <algorithm>
#include <cmath>
#include <vector>

#include "overtake/core/road.hpp"
#include "overtake/planner/params.hpp"
#include "overtake/planner/reference/prediction.hpp"

namespace overtake::planner::reference {

/// Distance (m) to stop from `speed_mps` braking at up to `brake_mps2`, reached at `jerk_mps3`
/// from zero acceleration. (Inline, as the RSS reaches below: the soft lane costs work them
/// out for every sample of every longitudinal candidate.)
[[nodiscard]] inline double jerk_limited_stop_distance(double speed_mps, double brake_mps2,
                                                       double jerk_mps3) {
  const double v = speed_mps;
  const double brake = brake_mps2;
  const double jerk = jerk_mps3;
  if (!(v > 0.0)) return 0.0;
  const double ramp_t = brake / jerk;
  const double ramp_dv = 0.5 * brake * ramp_t;
  if (v <= ramp_dv) {
    // Stops before the full braking is reached: v = jerk t^2 / 2.
    const double t = std::sqrt(2.0 * v / jerk);
    return v * t - jerk * t * t * t / 6.0;
  }
  const double ramp_d = v * ramp_t - jerk * ramp_t * ramp_t * ramp_t / 6.0;
  const double rest = v - ramp_dv;
  return ramp_d + rest * rest / (2.0 * brake);
}

/// RSS minimum bumper-to-bumper distance (m) from the ego, behind at `rear_mps`, to a car
/// ahead at `front_mps`: the ego keeps its speed for the response time, then brakes with
/// limited jerk; the car ahead brakes at lead_brake_mps2. Never less than min_gap_m.
[[nodiscard]] double rss_front_gap(double rear_mps, double front_mps,
                                   const ReferenceBehaviourParams& p);
/// The two halves of rss_front_gap, for many pairs of speeds: how far the car behind goes
/// before it stands (response time, then braking) ...
[[nodiscard]] inline double rss_rear_reach(double rear_mps, const ReferenceBehaviourParams& p) {
  const double rear = std::max(0.0, rear_mps);
  return rear * p.response_time_s +
         jerk_limited_stop_distance(rear, p.ego_brake_mps2, p.ego_brake_jerk_mps3);
}
/// ... and how far the car ahead goes braking at lead_brake_mps2.
[[nodiscard]] inline double rss_front_reach(double front_mps, const ReferenceBehaviourParams& p) {
  const double front = std::max(0.0, front_mps);
  return front * front / (2.0 * p.lead_brake_mps2);
}
/// rss_front_gap from the halves (exactly the same number).
[[nodiscard]] inline double rss_gap_of(double rear_reach_m, double front_reach_m,
                                       const ReferenceBehaviourParams& p) {
  const double d = rear_reach_m - front_reach_m;
  return d < p.min_gap_m ? p.min_gap_m : d;
}

/// Room (m) left, bumper to bumper beyond the margin, when a car behind at centre distance
/// `centre_gap_m` closes at `closing_mps` on the ego and reacts as late as followers do
/// (within the follower's reaction gap `reaction_gap_m`, centre to centre) and then brakes;
/// negative: it would come too close. (Inline: the soft lane costs and the collision check
/// call it in their inner loops.)
[[nodiscard]] inline double rear_room(double centre_gap_m, double closing_mps, double car_length_m,
                                      const ReferenceBehaviourParams& p, double reaction_gap_m) {
  const double floor_m = car_length_m + p.follower_margin_m;
  if (closing_mps <= 0.0) return centre_gap_m - floor_m;
  const double react_at = std::min(centre_gap_m, reaction_gap_m);
  return react_at - closing_mps * p.follower_response_s -
         closing_mps * closing_mps / (2.0 * p.follower_brake_mps2) - floor_m;
}
/// The same with the behaviour's follower_reaction_gap_m.
[[nodiscard]] inline double rear_room(double centre_gap_m, double closing_mps, double car_length_m,
                                      const ReferenceBehaviourParams& p) {
  return rear_room(centre_gap_m, closing_mps, car_length_m, p, p.follower_reaction_gap_m);
}

/// The ego as behaviour sees it.
struct EgoSnapshot {
  double s_m = 0.0;        ///< unwrapped, in the cars' frame
  double speed_mps = 0.0;  ///< along the road
  double d_m = 0.0;
  double m_per_unit_s = 1.0;  ///< metres along the road per unit of s near the ego
};

/// One lane as seen from the ego.
struct LaneView {
  int lane = 0;
  int leader = -1;            ///< index into the predictions, -1: none within lookahead
  double leader_gap_m = 1e9;  ///< bumper to bumper
  double leader_speed_mps = 0.0;
  int follower = -1;            ///< nearest car behind
  double follower_gap_m = 1e9;  ///< bumper to bumper
  double follower_speed_mps = 0.0;
  bool alongside = false;           ///< a car overlaps the ego's length (with a margin)
  double expected_speed_mps = 0.0;  ///< average over the evaluation horizon
  double rear_threat = 0.0;         ///< 0 .. 1: a car closing fast from behind
  /// The next lanes only: the RSS gap (m) the ego at its speed needs behind the leader there
  /// (0: no leader) ...
  double entry_rss_gap_m = 0.0;
  bool rear_ok = false;    ///< ... and whether the car behind there has room were it to enter now
  bool enterable = false;  ///< a next lane with room to move into now
  bool passable = false;   ///< ... or at least to pass through to the lane beyond
  double cost = 0.0;
};

/// Views of every lane.
[[nodiscard]] std::vector<LaneView> assess_lanes(const std::vector<CarPrediction>& cars,
                                                 const EgoSnapshot& ego, double car_length_m,
                                                 const ReferenceBehaviourParams& p,
                                                 const core::RoadParams& road);

/// What behaviour remembers between cycles.
struct BehaviourState {
  int target_lane = -1;          ///< lane being driven to or kept; -1 before the first cycle
  int goal_lane = -1;            ///< the lane it is heading for (two lanes across: beyond target)
  double since_settled_s = 1e9;  ///< time since the ego last settled in its target lane
};

/// What behaviour asks of the trajectory layer.
struct BehaviourDecision {
  int target_lane = 1;
  int goal_lane = 1;
  double speed_mps = 0.0;  ///< wanted speed (cruise; less passing a slow queue or gap seeking)
  std::vector<LaneView> lanes;
};

/// Chooses the target lane and speed. `elapsed_s`: time since the last decision.
[[nodiscard]] BehaviourDecision decide(const std::vector<CarPrediction>& cars,
                                       const EgoSnapshot& ego, BehaviourState& state,
                                       double elapsed_s, double car_length_m,
                                       const ReferenceBehaviourParams& p,
                                       const core::RoadParams& road);

}  // namespace overtake::planner::reference
