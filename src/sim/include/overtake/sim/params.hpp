#pragma once
// Parameters of the simulated world. Defaults equal the shipped config file
// (config/overtake.json), which a test checks; every number here is a fact of the original
// simulator unless marked (ours).

#include <string>
#include <vector>

#include "overtake/core/road.hpp"
#include "overtake/core/units.hpp"

namespace overtake::sim {

/// The ego car.
struct EgoParams {
  double start_s_m = 124.8336;   ///< where it starts, at rest (the original's s)
  double start_d_m = 6.164833;   ///< middle lane, as in the original
  double length_m = 4.7;         ///< (ours) footprint for collisions
  double width_m = 1.9;          ///< (ours)
  /// A new path's first point is dropped when the car stands on it: within this distance.
  double stand_on_tolerance_m = 1e-3;
  friend bool operator==(const EgoParams&, const EgoParams&) = default;
};

/// Following and lane changes of the faithful (original) traffic profile.
struct FaithfulTrafficParams {
  /// Reaction distance = gain * (own cruise speed in mph - leader's speed in m/s), in metres
  /// (the original's mixed units, 10/20 m per unit), clamped to [min, max].
  double reaction_gain_m = 0.5;
  double min_reaction_m = 10.0;
  double max_reaction_m = 20.0;
  double ego_reaction_m = 10.0;    ///< when the vehicle ahead is the ego (not a car)
  double brake_mps2 = 8.0;         ///< (ours) full braking inside the reaction distance
  double accel_mps2 = 3.0;         ///< (ours) acceleration back to cruise speed
  double lane_change_min_speed_mps = core::mph_to_mps(15.0);
  double lane_change_interval_s = 2.0;   ///< since the car's last lane change
  double waypoint_trigger_m = 15.0;      ///< looks only within this of its next waypoint
  double clear_gap_m = 20.0;             ///< no vehicle within this ahead or behind in s
  int clear_steps = 50;                  ///< target lane clear for more than this many steps
  double ego_lane_radius_m = 3.0;        ///< the ego counts in a lane when d within this of its centre
  friend bool operator==(const FaithfulTrafficParams&, const FaithfulTrafficParams&) = default;
};

/// (ours) The calm profile: IDM following (Treiber et al. 2000) and MOBIL lane changes
/// (Kesting et al. 2007), standard highway parameters.
struct CalmTrafficParams {
  double time_headway_s = 1.5;
  double min_gap_m = 2.0;
  double max_accel_mps2 = 1.5;
  double comfort_decel_mps2 = 2.0;
  double accel_exponent = 4.0;
  double max_brake_mps2 = 9.0;           ///< physical braking limit
  double politeness = 0.3;
  double change_threshold_mps2 = 0.2;
  double safe_decel_mps2 = 4.0;          ///< a change may not force the new follower to brake harder
  double lane_change_interval_s = 4.0;
  friend bool operator==(const CalmTrafficParams&, const CalmTrafficParams&) = default;
};

/// The twelve other cars.
struct TrafficParams {
  int car_count = 12;
  double car_length_m = 4.7;
  double car_width_m = 1.9;
  double despawn_distance_m = 200.0;     ///< farther than this from the ego (along s): placed again
  double behind_probability = 0.5;
  int behind_min_waypoints = 2;
  int behind_max_waypoints = 3;
  int ahead_min_waypoints = 4;
  int ahead_max_waypoints = 5;
  double behind_min_speed_mps = core::mph_to_mps(50.0);
  double behind_max_speed_mps = core::mph_to_mps(60.0);
  double ahead_min_speed_mps = core::mph_to_mps(40.0);
  double ahead_max_speed_mps = core::mph_to_mps(50.0);
  double min_spawn_distance_m = 6.0;     ///< a spot closer than this to another car is drawn again
  /// (ours) in its lane, a spot must also leave room to brake to the other car's speed.
  double spawn_brake_mps2 = 6.0;
  int max_spawn_attempts = 50;
  int batch_min_frames = 20;
  int batch_max_frames = 60;
  int batch_min_cars = 1;
  int batch_max_cars = 3;
  double wander_amplitude_m = 0.3;       ///< (ours) lateral wander about the lane centre
  double wander_min_period_s = 8.0;
  double wander_max_period_s = 20.0;
  double lane_change_duration_s = 3.0;   ///< "a few seconds"
  FaithfulTrafficParams faithful;
  CalmTrafficParams calm;
  friend bool operator==(const TrafficParams&, const TrafficParams&) = default;
};

/// The rubric of incidents, and the strict comfort figures.
struct RefereeParams {
  double speed_limit_mps = core::mph_to_mps(50.0);
  double max_accel_mps2 = 10.0;
  double max_jerk_mps3 = 10.0;
  int accel_block_steps = 10;            ///< speed averaged over blocks of 10 steps (0.2 s)
  int jerk_group_blocks = 5;             ///< block totals averaged over groups of 5 (1 s)
  double min_d_m = 0.8;                  ///< outside the road below this ...
  double max_d_m = 11.2;                 ///< ... or above this
  double line_band_half_width_m = 0.8;   ///< around each lane line between lanes
  int straddle_max_steps = 150;          ///< in a band for more than this: outside of lane
  int latch_steps = 50;                  ///< a persisting incident counts again after this
  int strict_window_steps = 5;           ///< (ours) 0.1 s windows for the strict figures
  double car_length_m = 4.7;             ///< (ours) footprints for collisions
  double car_width_m = 1.9;
  friend bool operator==(const RefereeParams&, const RefereeParams&) = default;
};

/// The whole world.
struct WorldParams {
  double step_s = 0.02;
  core::RoadParams road;
  EgoParams ego;
  TrafficParams traffic;
  RefereeParams referee;
  /// Round what the planner sees and what it sends as the original's wire format does.
  bool wire_rounding = true;
  int min_steps_per_call = 1;            ///< (ours) lock-step latency K drawn from [min, max]
  int max_steps_per_call = 3;
  friend bool operator==(const WorldParams&, const WorldParams&) = default;
};

/// Problems with the parameters, each naming its key (empty: all valid).
[[nodiscard]] std::vector<std::string> validate(const WorldParams& p);

}  // namespace overtake::sim

namespace overtake::sim {

// Field lists: one per params struct, shared by the config reader and writer (app) so that
// a key's name is written once. `v(name, field)` for a value, `v.section(name, sub)` for a
// nested struct.

template <class V>
void describe(V& v, core::RoadParams& p) {
  v("lane_count", p.lane_count);
  v("lane_width_m", p.lane_width_m);
}

template <class V>
void describe(V& v, EgoParams& p) {
  v("start_s_m", p.start_s_m);
  v("start_d_m", p.start_d_m);
  v("length_m", p.length_m);
  v("width_m", p.width_m);
  v("stand_on_tolerance_m", p.stand_on_tolerance_m);
}

template <class V>
void describe(V& v, FaithfulTrafficParams& p) {
  v("reaction_gain_m", p.reaction_gain_m);
  v("min_reaction_m", p.min_reaction_m);
  v("max_reaction_m", p.max_reaction_m);
  v("ego_reaction_m", p.ego_reaction_m);
  v("brake_mps2", p.brake_mps2);
  v("accel_mps2", p.accel_mps2);
  v("lane_change_min_speed_mps", p.lane_change_min_speed_mps);
  v("lane_change_interval_s", p.lane_change_interval_s);
  v("waypoint_trigger_m", p.waypoint_trigger_m);
  v("clear_gap_m", p.clear_gap_m);
  v("clear_steps", p.clear_steps);
  v("ego_lane_radius_m", p.ego_lane_radius_m);
}

template <class V>
void describe(V& v, CalmTrafficParams& p) {
  v("time_headway_s", p.time_headway_s);
  v("min_gap_m", p.min_gap_m);
  v("max_accel_mps2", p.max_accel_mps2);
  v("comfort_decel_mps2", p.comfort_decel_mps2);
  v("accel_exponent", p.accel_exponent);
  v("max_brake_mps2", p.max_brake_mps2);
  v("politeness", p.politeness);
  v("change_threshold_mps2", p.change_threshold_mps2);
  v("safe_decel_mps2", p.safe_decel_mps2);
  v("lane_change_interval_s", p.lane_change_interval_s);
}

template <class V>
void describe(V& v, TrafficParams& p) {
  v("car_count", p.car_count);
  v("car_length_m", p.car_length_m);
  v("car_width_m", p.car_width_m);
  v("despawn_distance_m", p.despawn_distance_m);
  v("behind_probability", p.behind_probability);
  v("behind_min_waypoints", p.behind_min_waypoints);
  v("behind_max_waypoints", p.behind_max_waypoints);
  v("ahead_min_waypoints", p.ahead_min_waypoints);
  v("ahead_max_waypoints", p.ahead_max_waypoints);
  v("behind_min_speed_mps", p.behind_min_speed_mps);
  v("behind_max_speed_mps", p.behind_max_speed_mps);
  v("ahead_min_speed_mps", p.ahead_min_speed_mps);
  v("ahead_max_speed_mps", p.ahead_max_speed_mps);
  v("min_spawn_distance_m", p.min_spawn_distance_m);
  v("spawn_brake_mps2", p.spawn_brake_mps2);
  v("max_spawn_attempts", p.max_spawn_attempts);
  v("batch_min_frames", p.batch_min_frames);
  v("batch_max_frames", p.batch_max_frames);
  v("batch_min_cars", p.batch_min_cars);
  v("batch_max_cars", p.batch_max_cars);
  v("wander_amplitude_m", p.wander_amplitude_m);
  v("wander_min_period_s", p.wander_min_period_s);
  v("wander_max_period_s", p.wander_max_period_s);
  v("lane_change_duration_s", p.lane_change_duration_s);
  v.section("faithful", p.faithful);
  v.section("calm", p.calm);
}

template <class V>
void describe(V& v, RefereeParams& p) {
  v("speed_limit_mps", p.speed_limit_mps);
  v("max_accel_mps2", p.max_accel_mps2);
  v("max_jerk_mps3", p.max_jerk_mps3);
  v("accel_block_steps", p.accel_block_steps);
  v("jerk_group_blocks", p.jerk_group_blocks);
  v("min_d_m", p.min_d_m);
  v("max_d_m", p.max_d_m);
  v("line_band_half_width_m", p.line_band_half_width_m);
  v("straddle_max_steps", p.straddle_max_steps);
  v("latch_steps", p.latch_steps);
  v("strict_window_steps", p.strict_window_steps);
  v("car_length_m", p.car_length_m);
  v("car_width_m", p.car_width_m);
}

template <class V>
void describe(V& v, WorldParams& p) {
  v("step_s", p.step_s);
  v("wire_rounding", p.wire_rounding);
  v("min_steps_per_call", p.min_steps_per_call);
  v("max_steps_per_call", p.max_steps_per_call);
  v.section("ego", p.ego);
  v.section("traffic", p.traffic);
  v.section("referee", p.referee);
}

}  // namespace overtake::sim
