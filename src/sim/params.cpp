#include "overtake/sim/params.hpp"

#include "overtake/core/param_check.hpp"

namespace overtake::sim {

// One line per key of the world's params, in the order of the struct: longer than the
// project's 80 lines because it is a flat list (no branch, no state), which a split by section
// would only scatter.
std::vector<std::string> validate(const WorldParams& p) {
  std::vector<std::string> out;
  core::ParamChecker c(out);
  // Bounds of what makes physical sense: a step of a millisecond to half a second (the
  // original's 0.02 s; 1e-9 would never end, 1e308 would run no step), bodies and lanes up to
  // 20 m, speeds up to 100 m/s.
  c.in_range("world.step_s", p.step_s, 0.001, 0.5);
  c.in_range("world.min_steps_per_call", p.min_steps_per_call, 1, 1000);
  c.in_range("world.max_steps_per_call", p.max_steps_per_call, 1, 1000);
  c.ordered("world.min_steps_per_call", p.min_steps_per_call, "world.max_steps_per_call",
            p.max_steps_per_call);
  c.in_range("road.lane_count", p.road.lane_count, 1, 8);
  c.in_range("road.lane_width_m", p.road.lane_width_m, 1.0, 20.0);
  c.in_range("car.length_m", p.car.length_m, 0.5, 20.0);
  c.in_range("car.width_m", p.car.width_m, 0.5, 20.0);

  const auto& e = p.ego;
  c.non_negative("world.ego.stand_on_tolerance_m", e.stand_on_tolerance_m);
  c.in_range("world.ego.start_d_m", e.start_d_m, 0.0, core::road_width_m(p.road));
  c.in_range("world.ego.start_s_m", e.start_s_m, -100000.0, 100000.0);

  const auto& t = p.traffic;
  c.in_range("world.traffic.car_count", t.car_count, 0, 64);

  const auto& pl = t.placement;
  const std::string pk = "world.traffic.placement.";
  c.positive(pk + "despawn_distance_m", pl.despawn_distance_m);
  c.in_range(pk + "behind_probability", pl.behind_probability, 0.0, 1.0);
  c.in_range(pk + "behind_min_waypoints", pl.behind_min_waypoints, 1, 100);
  c.in_range(pk + "behind_max_waypoints", pl.behind_max_waypoints, 1, 100);
  c.ordered(pk + "behind_min_waypoints", pl.behind_min_waypoints, pk + "behind_max_waypoints",
            pl.behind_max_waypoints);
  c.in_range(pk + "ahead_min_waypoints", pl.ahead_min_waypoints, 1, 100);
  c.in_range(pk + "ahead_max_waypoints", pl.ahead_max_waypoints, 1, 100);
  c.ordered(pk + "ahead_min_waypoints", pl.ahead_min_waypoints, pk + "ahead_max_waypoints",
            pl.ahead_max_waypoints);
  c.in_range(pk + "behind_min_speed_mps", pl.behind_min_speed_mps, 0.0, 100.0);
  c.in_range(pk + "behind_max_speed_mps", pl.behind_max_speed_mps, 0.0, 100.0);
  c.ordered(pk + "behind_min_speed_mps", pl.behind_min_speed_mps, pk + "behind_max_speed_mps",
            pl.behind_max_speed_mps);
  c.in_range(pk + "ahead_min_speed_mps", pl.ahead_min_speed_mps, 0.0, 100.0);
  c.in_range(pk + "ahead_max_speed_mps", pl.ahead_max_speed_mps, 0.0, 100.0);
  c.ordered(pk + "ahead_min_speed_mps", pl.ahead_min_speed_mps, pk + "ahead_max_speed_mps",
            pl.ahead_max_speed_mps);
  c.non_negative(pk + "min_spawn_distance_m", pl.min_spawn_distance_m);
  c.in_range(pk + "max_spawn_attempts", pl.max_spawn_attempts, 1, 100000);
  c.in_range(pk + "batch_min_frames", pl.batch_min_frames, 1, 100000);
  c.in_range(pk + "batch_max_frames", pl.batch_max_frames, 1, 100000);
  c.ordered(pk + "batch_min_frames", pl.batch_min_frames, pk + "batch_max_frames",
            pl.batch_max_frames);
  c.in_range(pk + "batch_min_cars", pl.batch_min_cars, 1, 64);
  c.in_range(pk + "batch_max_cars", pl.batch_max_cars, 1, 64);
  c.ordered(pk + "batch_min_cars", pl.batch_min_cars, pk + "batch_max_cars", pl.batch_max_cars);

  const auto& f = t.faithful;
  const std::string fk = "world.traffic.faithful.";
  c.finite(fk + "parked_d_m", f.parked_d_m);
  c.non_negative(fk + "parked_s_before_end_m", f.parked_s_before_end_m);
  c.non_negative(fk + "accel_sensitivity_per_mph", f.accel_sensitivity_per_mph);
  c.non_negative(fk + "brake_sensitivity_per_mph", f.brake_sensitivity_per_mph);
  c.in_range(fk + "accel_wander_amount", f.accel_wander_amount, 0.0, 1.0);
  c.non_negative(fk + "wander_rate_hz", f.wander_rate_hz);
  c.positive(fk + "engine_mps2", f.engine_mps2);
  c.non_negative(fk + "drag_per_s", f.drag_per_s);
  c.positive(fk + "brake_mps2", f.brake_mps2);
  c.non_negative(fk + "reaction_gain_m", f.reaction_gain_m);
  c.non_negative(fk + "no_body_reaction_m", f.no_body_reaction_m);
  c.in_range(fk + "ray_horizon_m", f.ray_horizon_m, 1.0, 5000.0);
  c.non_negative(fk + "scenery_margin_m", f.scenery_margin_m);
  c.non_negative(fk + "lane_change_min_speed_mps", f.lane_change_min_speed_mps);
  c.in_range(fk + "lane_change_wait_steps", f.lane_change_wait_steps, 0, 1000000);
  c.positive(fk + "waypoint_trigger_m", f.waypoint_trigger_m);
  c.non_negative(fk + "clear_gap_m", f.clear_gap_m);
  c.non_negative(fk + "car_lane_half_width_m", f.car_lane_half_width_m);
  c.non_negative(fk + "ego_lane_half_width_m", f.ego_lane_half_width_m);
  c.in_range(fk + "clear_steps", f.clear_steps, 0, 100000);
  c.non_negative(fk + "steer_sensitivity_per_deg", f.steer_sensitivity_per_deg);
  c.in_range(fk + "max_steer_deg", f.max_steer_deg, 0.0, 80.0);
  c.positive(fk + "wheelbase_m", f.wheelbase_m);
  c.positive(fk + "max_lateral_accel_mps2", f.max_lateral_accel_mps2);
  c.non_negative(fk + "target_reach_m", f.target_reach_m);
  c.non_negative(fk + "target_reach_per_lane_m", f.target_reach_per_lane_m);
  c.non_negative(fk + "lateral_wander_m", f.lateral_wander_m);
  c.non_negative(fk + "avoid_time_s", f.avoid_time_s);
  c.in_range(fk + "avoid_slowdown", f.avoid_slowdown, 0.0, 1.0);

  const auto& m = t.calm;
  const std::string mk = "world.traffic.calm.";
  c.positive(mk + "time_headway_s", m.time_headway_s);
  c.non_negative(mk + "min_gap_m", m.min_gap_m);
  c.positive(mk + "max_accel_mps2", m.max_accel_mps2);
  c.positive(mk + "comfort_decel_mps2", m.comfort_decel_mps2);
  c.positive(mk + "accel_exponent", m.accel_exponent);
  c.positive(mk + "max_brake_mps2", m.max_brake_mps2);
  c.in_range(mk + "politeness", m.politeness, 0.0, 10.0);
  c.non_negative(mk + "change_threshold_mps2", m.change_threshold_mps2);
  c.positive(mk + "safe_decel_mps2", m.safe_decel_mps2);
  c.non_negative(mk + "lane_change_interval_s", m.lane_change_interval_s);
  c.positive(mk + "spawn_brake_mps2", m.spawn_brake_mps2);
  c.non_negative(mk + "wander_amplitude_m", m.wander_amplitude_m);
  c.positive(mk + "wander_min_period_s", m.wander_min_period_s);
  c.ordered(mk + "wander_min_period_s", m.wander_min_period_s, mk + "wander_max_period_s",
            m.wander_max_period_s);
  c.positive(mk + "lane_change_duration_s", m.lane_change_duration_s);

  const auto& r = p.referee;
  c.positive("world.referee.speed_limit_mps", r.speed_limit_mps);
  c.positive("world.referee.max_accel_mps2", r.max_accel_mps2);
  c.positive("world.referee.max_jerk_mps3", r.max_jerk_mps3);
  c.in_range("world.referee.accel_block_steps", r.accel_block_steps, 1, 10000);
  c.in_range("world.referee.jerk_group_blocks", r.jerk_group_blocks, 1, 10000);
  c.in_range("world.referee.edge_margin_m", r.edge_margin_m, 0.0, 0.5 * core::road_width_m(p.road));
  c.non_negative("world.referee.line_band_half_width_m", r.line_band_half_width_m);
  c.in_range("world.referee.straddle_max_steps", r.straddle_max_steps, 1, 1000000);
  c.in_range("world.referee.latch_steps", r.latch_steps, 1, 1000000);
  c.in_range("world.referee.strict_window_steps", r.strict_window_steps, 1, 1000);

  const auto& s = p.safety;
  c.in_range("world.safety.stopped_speed_mps", s.stopped_speed_mps, 0.0, 10.0);
  c.in_range("world.safety.hard_braking_mps2", s.hard_braking_mps2, 0.1, 100.0);
  c.in_range("world.safety.braking_window_s", s.braking_window_s, p.step_s, 60.0);
  c.in_range("world.safety.reaction_time_s", s.reaction_time_s, 0.0, 60.0);
  c.in_range("world.safety.lane_change_window_s", s.lane_change_window_s, 0.0, 60.0);
  c.in_range("world.safety.lane_overlap_m", s.lane_overlap_m, 0.0, p.road.lane_width_m);
  c.in_range("world.safety.ttc_threshold_s", s.ttc_threshold_s, 0.0, 60.0);
  c.in_range("world.safety.headway_threshold_s", s.headway_threshold_s, 0.0, 60.0);
  c.in_range("world.safety.headway_min_speed_mps", s.headway_min_speed_mps, 0.0, 100.0);
  c.in_range("world.safety.episode_gap_s", s.episode_gap_s, 0.0, 600.0);
  c.in_range("world.safety.contact_gap_s", s.contact_gap_s, 0.0, 600.0);
  return out;
}

}  // namespace overtake::sim
