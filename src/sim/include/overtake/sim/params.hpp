#pragma once
// Parameters of the simulated world. Defaults equal the shipped config file
// (config/overtake.json), which a test checks; every number here is a fact of the original
// simulator unless marked (ours).

#include <string>
#include <vector>

#include "overtake/core/road.hpp"
#include "overtake/core/step.hpp"
#include "overtake/core/units.hpp"
#include "overtake/sim/safety.hpp"

namespace overtake::sim {

/// The ego car.
struct EgoParams {
  /// Where it starts, at rest: s and d as the original reports them at the start (measured on
  /// the waypoint chords). The position is the chord point there rounded to whole centimetres,
  /// the yaw the chord's heading rounded to a whole degree: on the original map exactly the
  /// original's start (x 909.48, y 1128.67, yaw 0).
  double start_s_m = 124.8336;
  double start_d_m = 6.164833;
  /// A new path's first point is dropped when the car stands on it: within this distance.
  /// 0, as the original (the car stands on a point it drove to, and points cross the wire
  /// rounded the same way, so "on it" is exact); a millimetre dropped points of a slow
  /// start or stop, the car skipped ahead in its plan and jerked.
  double stand_on_tolerance_m = 0.0;
  friend bool operator==(const EgoParams&, const EgoParams&) = default;
};

/// Where traffic cars are put around the ego (the original's CarAIControl.Spawn and
/// CarTraffic's batches). Speeds are the cars' speed caps.
struct PlacementParams {
  double despawn_distance_m = 200.0;  ///< farther than this from the ego: placed again
  double behind_probability = 0.5;
  int behind_min_waypoints = 2;  ///< behind the ego's closest waypoint ...
  int behind_max_waypoints = 3;
  int ahead_min_waypoints = 4;  ///< ... or ahead of it
  int ahead_max_waypoints = 5;
  double behind_min_speed_mps = core::mph_to_mps(50.0);
  double behind_max_speed_mps = core::mph_to_mps(60.0);
  double ahead_min_speed_mps = core::mph_to_mps(40.0);
  double ahead_max_speed_mps = core::mph_to_mps(50.0);
  double min_spawn_distance_m = 6.0;  ///< a spot closer than this to another car is drawn again
  int max_spawn_attempts = 500;
  int batch_min_frames = 20;  ///< a batch every 20-60 frames ...
  int batch_max_frames = 60;
  int batch_min_cars = 1;  ///< ... places 1-3 waiting cars
  int batch_max_cars = 3;
  friend bool operator==(const PlacementParams&, const PlacementParams&) = default;
};

/// The faithful (original) traffic profile: the original's CarAIControl driving a car body.
/// Numbers the original's source leaves to its scene (engine, drag, brakes, steering
/// response, wander) are (ours) and calibrated against telemetry recorded from it.
struct FaithfulTrafficParams {
  // Start: the cars wait off the road until the batches place them.
  double parked_d_m = -280.0;  ///< (ours) waiting cars stand this far on the divider's side ...
  double parked_s_before_end_m = 260.0;  ///< ... around s = loop length - this, 6 m apart
  // Speed law: throttle = (cap - speed) in mph * sensitivity, braking likewise, times a wander.
  double accel_sensitivity_per_mph = 0.04;
  double brake_sensitivity_per_mph = 1.0;
  double accel_wander_amount = 0.1;  ///< throttle scaled by 1 - this + this * noise
  double wander_rate_hz = 0.1;       ///< the noise is sampled at time * this
  double engine_mps2 = 7.5;          ///< (ours) acceleration at full throttle
  double drag_per_s = 0.13;          ///< (ours) deceleration per m/s of speed
  double brake_mps2 = 8.0;           ///< (ours) deceleration at full brake
  // Following: one ray straight ahead from the front of the car.
  double reaction_gain_m =
      0.5;  ///< reaction distance = this * (own cap in mph - body's speed in m/s)
  double no_body_reaction_m = 10.0;  ///< reaction distance when the ray meets no body
  double ray_horizon_m = 250.0;      ///< (ours) a ray still on the road this far meets nothing
  double scenery_margin_m = 3.0;  ///< (ours) a ray this far beyond the road's edges meets scenery
  // Lane changes (each counted step: reacting, fast enough, settled, near a waypoint).
  double lane_change_min_speed_mps = core::mph_to_mps(15.0);
  int lane_change_wait_steps = 100;    ///< steps since its last lane change
  double waypoint_trigger_m = 15.0;    ///< within this of its next waypoint
  double clear_gap_m = 20.0;           ///< a lane is clear with no car within this in s ...
  double car_lane_half_width_m = 2.0;  ///< ... among the cars with d within this of its centre ...
  double ego_lane_half_width_m = 3.0;  ///< ... and the ego within this
  int clear_steps = 50;                ///< moves after more than this many clear counted steps
  // Steering towards the next waypoint's lane point.
  double steer_sensitivity_per_deg = 0.05;
  double max_steer_deg = 25.0;           ///< (ours) full steering lock
  double wheelbase_m = 2.7;              ///< (ours)
  double max_lateral_accel_mps2 = 6.0;   ///< (ours) grip: turning is limited to this
  double target_reach_m = 5.0;           ///< the target waypoint advances within this + ...
  double target_reach_per_lane_m = 4.0;  ///< ... this * lane of the car
  double lateral_wander_m = 0.35;        ///< (ours) the target is offset by (2 noise - 1) * this
  // After a contact with another car or the ego.
  double avoid_time_s = 1.0;    ///< evasive action for this long:
  double avoid_slowdown = 0.5;  ///< desired speed times this when the other is in front
  friend bool operator==(const FaithfulTrafficParams&, const FaithfulTrafficParams&) = default;
};

/// (ours) The calm profile: IDM following (Treiber et al. 2000) and MOBIL lane changes
/// (Kesting et al. 2007), standard highway parameters; placed as the original places cars,
/// between waypoints, with room to brake; all twelve from the start.
struct CalmTrafficParams {
  double time_headway_s = 1.5;
  double min_gap_m = 2.0;
  double max_accel_mps2 = 1.5;
  double comfort_decel_mps2 = 2.0;
  double accel_exponent = 4.0;
  double max_brake_mps2 = 9.0;  ///< physical braking limit
  double politeness = 0.3;
  double change_threshold_mps2 = 0.2;
  double safe_decel_mps2 = 4.0;  ///< a change may not force the new follower to brake harder
  double lane_change_interval_s = 4.0;
  /// In its lane, a spot must also leave room to brake to the other car's speed.
  double spawn_brake_mps2 = 6.0;
  double wander_amplitude_m = 0.3;  ///< lateral wander about the lane centre
  double wander_min_period_s = 8.0;
  double wander_max_period_s = 20.0;
  double lane_change_duration_s = 3.0;  ///< minimum-jerk lateral profile (also scripted cars)
  friend bool operator==(const CalmTrafficParams&, const CalmTrafficParams&) = default;
};

/// The twelve other cars.
struct TrafficParams {
  int car_count = 12;
  PlacementParams placement;
  FaithfulTrafficParams faithful;
  CalmTrafficParams calm;
  friend bool operator==(const TrafficParams&, const TrafficParams&) = default;
};

/// The rubric of incidents, and the strict comfort figures.
struct RefereeParams {
  double speed_limit_mps = core::mph_to_mps(50.0);
  double max_accel_mps2 = 10.0;
  double max_jerk_mps3 = 10.0;
  int accel_block_steps = 10;  ///< speed averaged over blocks of 10 steps (0.2 s)
  int jerk_group_blocks = 5;   ///< block totals averaged over groups of 5 (1 s)
  /// Outside the road within this of its edges, or beyond them: d under this, or over the
  /// road's width (lane_count * lane_width_m) less this (0.8 and 11.2 on three 4 m lanes).
  double edge_margin_m = 0.8;
  double line_band_half_width_m = 0.8;  ///< around each lane line between lanes
  int straddle_max_steps = 150;         ///< in a band for more than this: outside of lane
  int latch_steps = 50;                 ///< a persisting incident counts again after this
  int strict_window_steps = 5;          ///< (ours) 0.1 s windows for the strict figures
  friend bool operator==(const RefereeParams&, const RefereeParams&) = default;
};

/// The whole world.
struct WorldParams {
  /// The fixed step; also the planners' (PlannerParams::step_s), copied by the config loader.
  double step_s = core::kDefaultStepS;
  core::RoadParams road;   ///< the config's `road`, copied in by the config loader
  core::CarFootprint car;  ///< the config's `car` (every body, the ego's too), likewise
  EgoParams ego;
  TrafficParams traffic;
  RefereeParams referee;
  SafetyParams safety;  ///< whose fault a collision was, near misses (safety.hpp)
  /// Round what the planner sees and what it sends as the original's wire format does.
  bool wire_rounding = true;
  int min_steps_per_call = 1;  ///< (ours) lock-step latency K drawn from [min, max]
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
void describe(V& v, core::CarFootprint& p) {
  v("length_m", p.length_m);
  v("width_m", p.width_m);
}

template <class V>
void describe(V& v, EgoParams& p) {
  v("start_s_m", p.start_s_m);
  v("start_d_m", p.start_d_m);
  v("stand_on_tolerance_m", p.stand_on_tolerance_m);
}

template <class V>
void describe(V& v, PlacementParams& p) {
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
  v("max_spawn_attempts", p.max_spawn_attempts);
  v("batch_min_frames", p.batch_min_frames);
  v("batch_max_frames", p.batch_max_frames);
  v("batch_min_cars", p.batch_min_cars);
  v("batch_max_cars", p.batch_max_cars);
}

template <class V>
void describe(V& v, FaithfulTrafficParams& p) {
  v("parked_d_m", p.parked_d_m);
  v("parked_s_before_end_m", p.parked_s_before_end_m);
  v("accel_sensitivity_per_mph", p.accel_sensitivity_per_mph);
  v("brake_sensitivity_per_mph", p.brake_sensitivity_per_mph);
  v("accel_wander_amount", p.accel_wander_amount);
  v("wander_rate_hz", p.wander_rate_hz);
  v("engine_mps2", p.engine_mps2);
  v("drag_per_s", p.drag_per_s);
  v("brake_mps2", p.brake_mps2);
  v("reaction_gain_m", p.reaction_gain_m);
  v("no_body_reaction_m", p.no_body_reaction_m);
  v("ray_horizon_m", p.ray_horizon_m);
  v("scenery_margin_m", p.scenery_margin_m);
  v("lane_change_min_speed_mps", p.lane_change_min_speed_mps);
  v("lane_change_wait_steps", p.lane_change_wait_steps);
  v("waypoint_trigger_m", p.waypoint_trigger_m);
  v("clear_gap_m", p.clear_gap_m);
  v("car_lane_half_width_m", p.car_lane_half_width_m);
  v("ego_lane_half_width_m", p.ego_lane_half_width_m);
  v("clear_steps", p.clear_steps);
  v("steer_sensitivity_per_deg", p.steer_sensitivity_per_deg);
  v("max_steer_deg", p.max_steer_deg);
  v("wheelbase_m", p.wheelbase_m);
  v("max_lateral_accel_mps2", p.max_lateral_accel_mps2);
  v("target_reach_m", p.target_reach_m);
  v("target_reach_per_lane_m", p.target_reach_per_lane_m);
  v("lateral_wander_m", p.lateral_wander_m);
  v("avoid_time_s", p.avoid_time_s);
  v("avoid_slowdown", p.avoid_slowdown);
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
  v("spawn_brake_mps2", p.spawn_brake_mps2);
  v("wander_amplitude_m", p.wander_amplitude_m);
  v("wander_min_period_s", p.wander_min_period_s);
  v("wander_max_period_s", p.wander_max_period_s);
  v("lane_change_duration_s", p.lane_change_duration_s);
}

template <class V>
void describe(V& v, TrafficParams& p) {
  v("car_count", p.car_count);
  v.section("placement", p.placement);
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
  v("edge_margin_m", p.edge_margin_m);
  v("line_band_half_width_m", p.line_band_half_width_m);
  v("straddle_max_steps", p.straddle_max_steps);
  v("latch_steps", p.latch_steps);
  v("strict_window_steps", p.strict_window_steps);
}

template <class V>
void describe(V& v, SafetyParams& p) {
  v("stopped_speed_mps", p.stopped_speed_mps);
  v("hard_braking_mps2", p.hard_braking_mps2);
  v("braking_window_s", p.braking_window_s);
  v("reaction_time_s", p.reaction_time_s);
  v("lane_change_window_s", p.lane_change_window_s);
  v("lane_overlap_m", p.lane_overlap_m);
  v("ttc_threshold_s", p.ttc_threshold_s);
  v("headway_threshold_s", p.headway_threshold_s);
  v("headway_min_speed_mps", p.headway_min_speed_mps);
  v("episode_gap_s", p.episode_gap_s);
  v("contact_gap_s", p.contact_gap_s);
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
  v.section("safety", p.safety);
}

}  // namespace overtake::sim
