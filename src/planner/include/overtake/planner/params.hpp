#pragma once
// Parameters of the planners. Defaults equal the shipped config file (config/overtake.json),
// which a test checks.

#include <string>
#include <vector>

#include "overtake/core/road.hpp"
#include "overtake/core/units.hpp"

namespace overtake::planner {

/// The walkthrough policy: keep lane, ramp speed, slow behind a close car, spline path.
struct WalkthroughParams {
  double target_speed_mps = core::mph_to_mps(49.5);
  double speed_step_mps = core::mph_to_mps(0.224);  ///< change of reference speed per cycle
  double too_close_m = 30.0;          ///< a car ahead in the lane nearer than this: slow down
  std::vector<double> anchor_distances_m = {30.0, 60.0, 90.0};
  int path_points = 50;
  double horizon_x_m = 30.0;          ///< points are spaced along this much of the spline
  double step_s = 0.02;               ///< the simulator's step, for point spacing
  int start_lane = 1;
  friend bool operator==(const WalkthroughParams&, const WalkthroughParams&) = default;
};

/// seed000: per-lane gap and speed bookkeeping, speed-dependent minimum gaps.
struct Seed000Params {
  double min_gap_ahead_per_mph_m = 10.0 / 49.5;   ///< min gap ahead = this x ego speed (mph)
  double min_gap_behind_mph_m = 20.0 * 49.5;      ///< min gap behind = this / ego speed (mph)
  double open_lane_gap_m = 60.0;                  ///< a lane with this much room ahead is worth it
  double no_car_gap_m = 1000.0;                   ///< the gap recorded for a lane with no car
  friend bool operator==(const Seed000Params&, const Seed000Params&) = default;
};

/// seed001: a deceleration counter that triggers a lane change, 35 m gap check.
struct Seed001Params {
  int patience_cycles = 40;        ///< lane change once decelerating for more than this
  double gap_front_m = 35.0;
  double gap_rear_m = 35.0;
  friend bool operator==(const Seed001Params&, const Seed001Params&) = default;
};

/// seed002: proximity per lane and an 80-point path.
struct Seed002Params {
  double proximity_ahead_m = 30.0;
  double proximity_behind_m = 5.0;
  int path_points = 80;
  friend bool operator==(const Seed002Params&, const Seed002Params&) = default;
};

/// seed003: prioritised rules, strong acceleration, return to the middle lane.
struct Seed003Params {
  double max_dist_front_m = 30.0;   ///< write-up silent on its value: the too-close distance
  double max_dist_back_m = 5.0;
  double strong_speed_step_mps = core::mph_to_mps(0.424);
  double middle_return_speed_mps = core::mph_to_mps(49.4);
  friend bool operator==(const Seed003Params&, const Seed003Params&) = default;
};

/// seed004: 20 m ahead / 10 m behind free-lane test, faster cars 10-20 m behind, speed
/// matching, 45 m first anchor when changing lanes.
struct Seed004Params {
  double free_ahead_m = 20.0;
  double free_behind_m = 10.0;
  double faster_behind_m = 20.0;
  double speed_match_divisor = 30.0;  ///< ref -= (ref - other) / this, the write-up's mixed units
  double change_first_anchor_m = 45.0;
  friend bool operator==(const Seed004Params&, const Seed004Params&) = default;
};

/// Parameters of every policy.
struct PlannerParams {
  core::RoadParams road;
  WalkthroughParams walkthrough;  ///< also the shared base of the seed policies
  Seed000Params seed000;
  Seed001Params seed001;
  Seed002Params seed002;
  Seed003Params seed003;
  Seed004Params seed004;
  friend bool operator==(const PlannerParams&, const PlannerParams&) = default;
};

/// Problems with the parameters, each naming its key (empty: all valid).
[[nodiscard]] std::vector<std::string> validate(const PlannerParams& p);

}  // namespace overtake::planner

namespace overtake::planner {

/// Field list of the walkthrough's parameters (see overtake/sim/params.hpp for the pattern).
template <class V>
void describe(V& v, WalkthroughParams& p) {
  v("target_speed_mps", p.target_speed_mps);
  v("speed_step_mps", p.speed_step_mps);
  v("too_close_m", p.too_close_m);
  v("anchor_distances_m", p.anchor_distances_m);
  v("path_points", p.path_points);
  v("horizon_x_m", p.horizon_x_m);
  v("step_s", p.step_s);
  v("start_lane", p.start_lane);
}

template <class V>
void describe(V& v, Seed000Params& p) {
  v("min_gap_ahead_per_mph_m", p.min_gap_ahead_per_mph_m);
  v("min_gap_behind_mph_m", p.min_gap_behind_mph_m);
  v("open_lane_gap_m", p.open_lane_gap_m);
  v("no_car_gap_m", p.no_car_gap_m);
}

template <class V>
void describe(V& v, Seed001Params& p) {
  v("patience_cycles", p.patience_cycles);
  v("gap_front_m", p.gap_front_m);
  v("gap_rear_m", p.gap_rear_m);
}

template <class V>
void describe(V& v, Seed002Params& p) {
  v("proximity_ahead_m", p.proximity_ahead_m);
  v("proximity_behind_m", p.proximity_behind_m);
  v("path_points", p.path_points);
}

template <class V>
void describe(V& v, Seed003Params& p) {
  v("max_dist_front_m", p.max_dist_front_m);
  v("max_dist_back_m", p.max_dist_back_m);
  v("strong_speed_step_mps", p.strong_speed_step_mps);
  v("middle_return_speed_mps", p.middle_return_speed_mps);
}

template <class V>
void describe(V& v, Seed004Params& p) {
  v("free_ahead_m", p.free_ahead_m);
  v("free_behind_m", p.free_behind_m);
  v("faster_behind_m", p.faster_behind_m);
  v("speed_match_divisor", p.speed_match_divisor);
  v("change_first_anchor_m", p.change_first_anchor_m);
}

template <class V>
void describe(V& v, PlannerParams& p) {
  v.section("walkthrough", p.walkthrough);
  v.section("seed000", p.seed000);
  v.section("seed001", p.seed001);
  v.section("seed002", p.seed002);
  v.section("seed003", p.seed003);
  v.section("seed004", p.seed004);
}

}  // namespace overtake::planner
