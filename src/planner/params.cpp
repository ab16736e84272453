#include "overtake/planner/params.hpp"

#include <cmath>
#include <utility>

#include "overtake/core/param_check.hpp"

namespace overtake::planner {
namespace {

// One line per key of the reference planner's params, in the order of the struct: longer than
// the project's 80 lines because it is a flat list (no branch, no state), which a split by
// section would only scatter.
void validate_reference(const PlannerParams& all, std::vector<std::string>& out) {
  const ReferenceParams& p = all.reference;
  core::ParamChecker c(out, "planner.reference.");
  c.non_negative("line_smoothing_m3", p.line_smoothing_m3);
  c.in_range("assertiveness", p.assertiveness, 0.0, 1.0);
  const auto& pr = p.prediction;
  c.positive("prediction.lane_change_speed_mps", pr.lane_change_speed_mps);
  c.positive("prediction.lane_change_offset_m", pr.lane_change_offset_m);
  c.positive("prediction.lane_change_duration_s", pr.lane_change_duration_s);
  c.non_negative("prediction.braking_threshold_mps2", pr.braking_threshold_mps2);
  c.non_negative("prediction.braking_horizon_s", pr.braking_horizon_s);
  c.positive("prediction.max_track_jump_m", pr.max_track_jump_m);
  c.positive("prediction.max_plausible_speed_mps", pr.max_plausible_speed_mps);
  c.positive("prediction.max_plausible_accel_mps2", pr.max_plausible_accel_mps2);
  c.non_negative("prediction.off_road_margin_m", pr.off_road_margin_m);
  c.non_negative("prediction.follower_speed_up_mps2", pr.follower_speed_up_mps2);
  c.non_negative("prediction.follower_speed_margin_mps", pr.follower_speed_margin_mps);
  c.positive("prediction.free_speed_share", pr.free_speed_share);
  c.positive("prediction.min_cap_mps", pr.min_cap_mps);
  c.positive("prediction.max_cap_mps", pr.max_cap_mps);
  c.non_negative("prediction.reaction_gain_m", pr.reaction_gain_m);
  c.positive("prediction.wave_brake_mps2", pr.wave_brake_mps2);
  c.non_negative("prediction.wave_recover_mps2", pr.wave_recover_mps2);
  const auto& b = p.behaviour;
  c.positive("behaviour.cruise_speed_mps", b.cruise_speed_mps);
  c.positive("behaviour.lookahead_m", b.lookahead_m);
  c.positive("behaviour.evaluation_horizon_s", b.evaluation_horizon_s);
  c.non_negative("behaviour.response_time_s", b.response_time_s);
  c.positive("behaviour.ego_brake_mps2", b.ego_brake_mps2);
  c.positive("behaviour.ego_brake_jerk_mps3", b.ego_brake_jerk_mps3);
  c.positive("behaviour.lead_brake_mps2", b.lead_brake_mps2);
  c.positive("behaviour.min_gap_m", b.min_gap_m);
  c.positive("behaviour.follower_reaction_gap_m", b.follower_reaction_gap_m);
  c.positive("behaviour.follower_brake_mps2", b.follower_brake_mps2);
  c.non_negative("behaviour.follower_response_s", b.follower_response_s);
  c.non_negative("behaviour.follower_margin_m", b.follower_margin_m);
  c.non_negative("behaviour.change_front_factor", b.change_front_factor);
  c.non_negative("behaviour.transit_front_factor", b.transit_front_factor);
  c.non_negative("behaviour.min_change_speed_mps", b.min_change_speed_mps);
  c.non_negative("behaviour.change_dwell_s", b.change_dwell_s);
  c.non_negative("behaviour.speed_weight", b.speed_weight);
  c.non_negative("behaviour.change_cost", b.change_cost);
  c.non_negative("behaviour.hysteresis", b.hysteresis);
  c.non_negative("behaviour.rear_threat_weight", b.rear_threat_weight);
  c.non_negative("behaviour.rear_threat_speed_mps", b.rear_threat_speed_mps);
  c.positive("behaviour.rear_threat_span_mps", b.rear_threat_span_mps);
  c.positive("behaviour.rear_threat_range_m", b.rear_threat_range_m);
  c.positive("behaviour.passing_speed_mps", b.passing_speed_mps);
  c.non_negative("behaviour.gap_seek_gain", b.gap_seek_gain);
  c.non_negative("behaviour.gap_seek_pace_mps", b.gap_seek_pace_mps);
  c.non_negative("behaviour.gap_seek_behind_m", b.gap_seek_behind_m);
  c.non_negative("behaviour.gap_seek_ahead_m", b.gap_seek_ahead_m);
  c.positive("behaviour.gap_seek_drop_mps", b.gap_seek_drop_mps);
  c.non_negative("behaviour.gap_seek_min_speed_mps", b.gap_seek_min_speed_mps);
  c.non_negative("behaviour.gap_seek_rear_gap_m", b.gap_seek_rear_gap_m);
  c.non_negative("behaviour.gap_seek_front_factor", b.gap_seek_front_factor);
  const auto& t = p.trajectory;
  c.in_range("trajectory.keep_points", t.keep_points, 0, 50);
  c.require(t.path_points >= t.keep_points + 10 && t.path_points <= 1000, "trajectory.path_points",
            "must be between keep_points + 10 and 1000", t.path_points);
  c.positive("trajectory.check_step_s", t.check_step_s);
  c.positive("trajectory.horizon_s", t.horizon_s);
  c.require(!(t.check_step_s > 0.0 && t.horizon_s / t.check_step_s > 1000.0),
            "trajectory.horizon_s", "must be at most 1000 check steps", t.horizon_s);
  c.positive("trajectory.max_speed_mps", t.max_speed_mps);
  c.at_most("behaviour.cruise_speed_mps", b.cruise_speed_mps, t.max_speed_mps,
            "trajectory.max_speed_mps");
  c.positive("trajectory.max_accel_mps2", t.max_accel_mps2);
  c.positive("trajectory.max_jerk_mps3", t.max_jerk_mps3);
  c.positive("trajectory.lateral_jerk_mps3", t.lateral_jerk_mps3);
  c.positive("trajectory.min_lateral_time_s", t.min_lateral_time_s);
  c.positive_list("trajectory.lateral_time_factors", t.lateral_time_factors);
  c.non_negative("trajectory.road_edge_margin_m", t.road_edge_margin_m);
  c.positive_list("trajectory.cruise_times_s", t.cruise_times_s);
  c.positive_list("trajectory.follow_times_s", t.follow_times_s);
  c.require(!t.speed_offsets_mps.empty(), "trajectory.speed_offsets_mps",
            "must list at least one value");
  for (const double x : t.speed_offsets_mps) {
    c.require(std::isfinite(x), "trajectory.speed_offsets_mps", "must hold numbers");
  }
  c.non_negative("trajectory.line_band_m", t.line_band_m);
  c.in_range("trajectory.crawl_heading_tolerance_rad", t.crawl_heading_tolerance_rad, 0.0, 1.5);
  c.in_range("trajectory.crawl_max_lag_m", t.crawl_max_lag_m, 0.0, 0.5);
  c.positive("trajectory.max_band_time_s", t.max_band_time_s);
  c.non_negative("trajectory.linger_weight", t.linger_weight);
  c.positive("trajectory.band_incident_s", t.band_incident_s);
  c.non_negative("trajectory.lon_margin_m", t.lon_margin_m);
  c.non_negative("trajectory.lat_margin_m", t.lat_margin_m);
  c.positive("trajectory.fallback_brake_mps2", t.fallback_brake_mps2);
  c.positive("trajectory.fallback_jerk_mps3", t.fallback_jerk_mps3);
  c.positive("trajectory.fallback_total_jerk_mps3", t.fallback_total_jerk_mps3);
  for (const double x : t.brake_levels_mps2) {
    if (!(x > 0.0) || !std::isfinite(x)) {
      c.require(false, "trajectory.brake_levels_mps2", "must hold positive numbers");
      break;
    }
  }
  c.positive("trajectory.brake_level_jerk_mps3", t.brake_level_jerk_mps3);
  c.non_negative("trajectory.ahead_collision_slack_s", t.ahead_collision_slack_s);
  c.in_range("trajectory.unseen_guard_s", t.unseen_guard_s, 0.0, 10.0);
  for (const auto& [key, v] :
       {std::pair<const char*, double>{"trajectory.progress_weight", t.progress_weight},
        {"trajectory.lon_jerk_weight", t.lon_jerk_weight},
        {"trajectory.lat_jerk_weight", t.lat_jerk_weight},
        {"trajectory.lat_time_weight", t.lat_time_weight},
        {"trajectory.lane_weight", t.lane_weight},
        {"trajectory.proximity_weight", t.proximity_weight},
        {"trajectory.change_early_window_s", t.change_early_window_s},
        {"trajectory.rear_weight", t.rear_weight}}) {
    c.non_negative(key, v);
  }
  c.at_least("trajectory.max_kinematic_checks", t.max_kinematic_checks, 1);
}

}  // namespace

std::vector<std::string> validate(const PlannerParams& p) {
  std::vector<std::string> out;
  core::ParamChecker c(out, "planner.");
  const auto& w = p.walkthrough;
  c.positive("walkthrough.target_speed_mps", w.target_speed_mps);
  c.positive("walkthrough.speed_step_mps", w.speed_step_mps);
  c.positive("walkthrough.too_close_m", w.too_close_m);
  c.positive("walkthrough.horizon_x_m", w.horizon_x_m);
  c.in_range("walkthrough.path_points", w.path_points, 2, 10000);
  c.require(!w.anchor_distances_m.empty(), "walkthrough.anchor_distances_m",
            "must list at least one distance");
  double last = 0.0;
  for (const double a : w.anchor_distances_m) {
    if (!(a > last) || !std::isfinite(a)) {
      c.require(false, "walkthrough.anchor_distances_m",
                "must be positive and increasing (got " + core::ParamChecker::format(a) +
                    " after " + core::ParamChecker::format(last) + ")");
      break;
    }
    last = a;
  }
  const auto& s0 = p.seed000;
  c.positive("seed000.min_gap_ahead_per_mph_m", s0.min_gap_ahead_per_mph_m);
  c.positive("seed000.min_gap_behind_mph_m", s0.min_gap_behind_mph_m);
  c.positive("seed000.open_lane_gap_m", s0.open_lane_gap_m);
  c.positive("seed000.no_car_gap_m", s0.no_car_gap_m);
  c.non_negative("seed001.patience_cycles", p.seed001.patience_cycles);
  c.positive("seed001.gap_front_m", p.seed001.gap_front_m);
  c.positive("seed001.gap_rear_m", p.seed001.gap_rear_m);
  c.positive("seed002.proximity_ahead_m", p.seed002.proximity_ahead_m);
  c.positive("seed002.proximity_behind_m", p.seed002.proximity_behind_m);
  c.in_range("seed002.path_points", p.seed002.path_points, 2, 10000);
  c.positive("seed003.max_dist_front_m", p.seed003.max_dist_front_m);
  c.positive("seed003.max_dist_back_m", p.seed003.max_dist_back_m);
  c.positive("seed003.strong_speed_step_mps", p.seed003.strong_speed_step_mps);
  c.positive("seed003.middle_return_speed_mps", p.seed003.middle_return_speed_mps);
  c.positive("seed004.free_ahead_m", p.seed004.free_ahead_m);
  c.positive("seed004.free_behind_m", p.seed004.free_behind_m);
  c.positive("seed004.faster_behind_m", p.seed004.faster_behind_m);
  c.positive("seed004.speed_match_divisor", p.seed004.speed_match_divisor);
  c.positive("seed004.change_first_anchor_m", p.seed004.change_first_anchor_m);
  // The step and the footprint are the world's too: a config names them by their own keys.
  core::ParamChecker shared(out);
  shared.positive("world.step_s", p.step_s);
  shared.positive("car.length_m", p.car.length_m);
  shared.positive("car.width_m", p.car.width_m);
  validate_reference(p, out);
  c.require(w.start_lane >= 0 && w.start_lane < p.road.lane_count, "walkthrough.start_lane",
            "must be a lane of the road, 0 to " + std::to_string(p.road.lane_count - 1),
            w.start_lane);
  return out;
}

}  // namespace overtake::planner
