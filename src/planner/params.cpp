#include "overtake/planner/params.hpp"

#include <cmath>
#include <sstream>

namespace overtake::planner {
namespace {

std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

void validate_reference(const PlannerParams& all, std::vector<std::string>& out) {
  const ReferenceParams& p = all.reference;
  const std::string base = "planner.reference.";
  auto positive = [&](const std::string& key, double v) {
    if (!(v > 0.0) || !std::isfinite(v)) out.push_back(base + key + " must be a positive number (got " + fmt(v) + ")");
  };
  auto non_negative = [&](const std::string& key, double v) {
    if (!(v >= 0.0) || !std::isfinite(v)) out.push_back(base + key + " must be zero or more (got " + fmt(v) + ")");
  };
  auto at_most = [&](const std::string& key, double v, double limit, const std::string& what) {
    if (v > limit) out.push_back(base + key + " must be at most " + what + " (got " + fmt(v) + ")");
  };
  auto times = [&](const std::string& key, const std::vector<double>& v) {
    if (v.empty()) out.push_back(base + key + " must list at least one value");
    for (const double x : v) {
      if (!(x > 0.0) || !std::isfinite(x)) {
        out.push_back(base + key + " must hold positive numbers (got " + fmt(x) + ")");
        break;
      }
    }
  };
  positive("car_length_m", p.car_length_m);
  positive("car_width_m", p.car_width_m);
  non_negative("line_smoothing_m3", p.line_smoothing_m3);
  const auto& pr = p.prediction;
  positive("prediction.lane_change_speed_mps", pr.lane_change_speed_mps);
  positive("prediction.lane_change_offset_m", pr.lane_change_offset_m);
  positive("prediction.lane_change_duration_s", pr.lane_change_duration_s);
  non_negative("prediction.braking_threshold_mps2", pr.braking_threshold_mps2);
  non_negative("prediction.braking_horizon_s", pr.braking_horizon_s);
  positive("prediction.max_track_jump_m", pr.max_track_jump_m);
  positive("prediction.max_plausible_speed_mps", pr.max_plausible_speed_mps);
  positive("prediction.max_plausible_accel_mps2", pr.max_plausible_accel_mps2);
  non_negative("prediction.off_road_margin_m", pr.off_road_margin_m);
  non_negative("prediction.follower_speed_up_mps2", pr.follower_speed_up_mps2);
  non_negative("prediction.follower_speed_margin_mps", pr.follower_speed_margin_mps);
  positive("prediction.free_speed_share", pr.free_speed_share);
  positive("prediction.min_cap_mps", pr.min_cap_mps);
  positive("prediction.max_cap_mps", pr.max_cap_mps);
  non_negative("prediction.reaction_gain_m", pr.reaction_gain_m);
  positive("prediction.wave_brake_mps2", pr.wave_brake_mps2);
  non_negative("prediction.wave_recover_mps2", pr.wave_recover_mps2);
  const auto& b = p.behaviour;
  positive("behaviour.cruise_speed_mps", b.cruise_speed_mps);
  positive("behaviour.lookahead_m", b.lookahead_m);
  positive("behaviour.evaluation_horizon_s", b.evaluation_horizon_s);
  non_negative("behaviour.response_time_s", b.response_time_s);
  positive("behaviour.ego_brake_mps2", b.ego_brake_mps2);
  positive("behaviour.ego_brake_jerk_mps3", b.ego_brake_jerk_mps3);
  positive("behaviour.lead_brake_mps2", b.lead_brake_mps2);
  positive("behaviour.min_gap_m", b.min_gap_m);
  positive("behaviour.follower_reaction_gap_m", b.follower_reaction_gap_m);
  positive("behaviour.follower_brake_mps2", b.follower_brake_mps2);
  non_negative("behaviour.follower_response_s", b.follower_response_s);
  non_negative("behaviour.follower_margin_m", b.follower_margin_m);
  non_negative("behaviour.change_front_factor", b.change_front_factor);
  non_negative("behaviour.transit_front_factor", b.transit_front_factor);
  non_negative("behaviour.min_change_speed_mps", b.min_change_speed_mps);
  non_negative("behaviour.change_dwell_s", b.change_dwell_s);
  non_negative("behaviour.speed_weight", b.speed_weight);
  non_negative("behaviour.change_cost", b.change_cost);
  non_negative("behaviour.hysteresis", b.hysteresis);
  non_negative("behaviour.rear_threat_weight", b.rear_threat_weight);
  non_negative("behaviour.rear_threat_speed_mps", b.rear_threat_speed_mps);
  positive("behaviour.rear_threat_span_mps", b.rear_threat_span_mps);
  positive("behaviour.rear_threat_range_m", b.rear_threat_range_m);
  positive("behaviour.passing_speed_mps", b.passing_speed_mps);
  const auto& t = p.trajectory;
  positive("trajectory.step_s", t.step_s);
  if (t.keep_points < 0 || t.keep_points > 50) {
    out.push_back(base + "trajectory.keep_points must be between 0 and 50 (got " + std::to_string(t.keep_points) + ")");
  }
  if (t.path_points < t.keep_points + 10 || t.path_points > 1000) {
    out.push_back(base + "trajectory.path_points must be between keep_points + 10 and 1000 (got " +
                  std::to_string(t.path_points) + ")");
  }
  positive("trajectory.check_step_s", t.check_step_s);
  positive("trajectory.horizon_s", t.horizon_s);
  if (t.check_step_s > 0.0 && t.horizon_s / t.check_step_s > 1000.0) {
    out.push_back(base + "trajectory.horizon_s must be at most 1000 check steps (got " + fmt(t.horizon_s) + ")");
  }
  positive("trajectory.max_speed_mps", t.max_speed_mps);
  at_most("behaviour.cruise_speed_mps", b.cruise_speed_mps, t.max_speed_mps, "trajectory.max_speed_mps");
  positive("trajectory.max_accel_mps2", t.max_accel_mps2);
  positive("trajectory.max_jerk_mps3", t.max_jerk_mps3);
  positive("trajectory.lateral_jerk_mps3", t.lateral_jerk_mps3);
  positive("trajectory.min_lateral_time_s", t.min_lateral_time_s);
  times("trajectory.lateral_time_factors", t.lateral_time_factors);
  non_negative("trajectory.road_edge_margin_m", t.road_edge_margin_m);
  times("trajectory.cruise_times_s", t.cruise_times_s);
  times("trajectory.follow_times_s", t.follow_times_s);
  if (t.speed_offsets_mps.empty()) out.push_back(base + "trajectory.speed_offsets_mps must list at least one value");
  for (const double x : t.speed_offsets_mps) {
    if (!std::isfinite(x)) out.push_back(base + "trajectory.speed_offsets_mps must hold numbers");
  }
  non_negative("trajectory.line_band_m", t.line_band_m);
  positive("trajectory.max_band_time_s", t.max_band_time_s);
  non_negative("trajectory.linger_weight", t.linger_weight);
  positive("trajectory.band_incident_s", t.band_incident_s);
  non_negative("trajectory.lon_margin_m", t.lon_margin_m);
  non_negative("trajectory.lat_margin_m", t.lat_margin_m);
  positive("trajectory.fallback_brake_mps2", t.fallback_brake_mps2);
  positive("trajectory.fallback_jerk_mps3", t.fallback_jerk_mps3);
  positive("trajectory.fallback_total_jerk_mps3", t.fallback_total_jerk_mps3);
  for (const double x : t.brake_levels_mps2) {
    if (!(x > 0.0) || !std::isfinite(x)) {
      out.push_back(base + "trajectory.brake_levels_mps2 must hold positive numbers");
      break;
    }
  }
  positive("trajectory.brake_level_jerk_mps3", t.brake_level_jerk_mps3);
  non_negative("trajectory.ahead_collision_slack_s", t.ahead_collision_slack_s);
  for (const auto& [key, v] : {std::pair<const char*, double>{"trajectory.progress_weight", t.progress_weight},
                               {"trajectory.lon_jerk_weight", t.lon_jerk_weight},
                               {"trajectory.lat_jerk_weight", t.lat_jerk_weight},
                               {"trajectory.lat_time_weight", t.lat_time_weight},
                               {"trajectory.lane_weight", t.lane_weight},
                               {"trajectory.proximity_weight", t.proximity_weight},
                               {"trajectory.change_early_window_s", t.change_early_window_s},
                               {"trajectory.rear_weight", t.rear_weight}}) {
    non_negative(key, v);
  }
  if (t.max_kinematic_checks < 1) {
    out.push_back(base + "trajectory.max_kinematic_checks must be at least 1 (got " +
                  std::to_string(t.max_kinematic_checks) + ")");
  }
}

}  // namespace

std::vector<std::string> validate(const PlannerParams& p) {
  std::vector<std::string> out;
  auto positive = [&](const char* key, double v) {
    if (!(v > 0.0) || !std::isfinite(v)) out.push_back(std::string(key) + " must be a positive number (got " + fmt(v) + ")");
  };
  const auto& w = p.walkthrough;
  positive("planner.walkthrough.target_speed_mps", w.target_speed_mps);
  positive("planner.walkthrough.speed_step_mps", w.speed_step_mps);
  positive("planner.walkthrough.too_close_m", w.too_close_m);
  positive("planner.walkthrough.horizon_x_m", w.horizon_x_m);
  positive("planner.walkthrough.step_s", w.step_s);
  if (w.path_points < 2 || w.path_points > 10000) {
    out.push_back("planner.walkthrough.path_points must be between 2 and 10000 (got " +
                  std::to_string(w.path_points) + ")");
  }
  if (w.anchor_distances_m.empty()) {
    out.push_back("planner.walkthrough.anchor_distances_m must list at least one distance");
  }
  double last = 0.0;
  for (const double a : w.anchor_distances_m) {
    if (!(a > last) || !std::isfinite(a)) {
      out.push_back("planner.walkthrough.anchor_distances_m must be positive and increasing (got " +
                    fmt(a) + " after " + fmt(last) + ")");
      break;
    }
    last = a;
  }
  const auto& s0 = p.seed000;
  positive("planner.seed000.min_gap_ahead_per_mph_m", s0.min_gap_ahead_per_mph_m);
  positive("planner.seed000.min_gap_behind_mph_m", s0.min_gap_behind_mph_m);
  positive("planner.seed000.open_lane_gap_m", s0.open_lane_gap_m);
  positive("planner.seed000.no_car_gap_m", s0.no_car_gap_m);
  if (p.seed001.patience_cycles < 0) {
    out.push_back("planner.seed001.patience_cycles must be zero or more (got " +
                  std::to_string(p.seed001.patience_cycles) + ")");
  }
  positive("planner.seed001.gap_front_m", p.seed001.gap_front_m);
  positive("planner.seed001.gap_rear_m", p.seed001.gap_rear_m);
  positive("planner.seed002.proximity_ahead_m", p.seed002.proximity_ahead_m);
  positive("planner.seed002.proximity_behind_m", p.seed002.proximity_behind_m);
  if (p.seed002.path_points < 2 || p.seed002.path_points > 10000) {
    out.push_back("planner.seed002.path_points must be between 2 and 10000 (got " +
                  std::to_string(p.seed002.path_points) + ")");
  }
  positive("planner.seed003.max_dist_front_m", p.seed003.max_dist_front_m);
  positive("planner.seed003.max_dist_back_m", p.seed003.max_dist_back_m);
  positive("planner.seed003.strong_speed_step_mps", p.seed003.strong_speed_step_mps);
  positive("planner.seed003.middle_return_speed_mps", p.seed003.middle_return_speed_mps);
  positive("planner.seed004.free_ahead_m", p.seed004.free_ahead_m);
  positive("planner.seed004.free_behind_m", p.seed004.free_behind_m);
  positive("planner.seed004.faster_behind_m", p.seed004.faster_behind_m);
  positive("planner.seed004.speed_match_divisor", p.seed004.speed_match_divisor);
  positive("planner.seed004.change_first_anchor_m", p.seed004.change_first_anchor_m);
  validate_reference(p, out);
  if (w.start_lane < 0 || w.start_lane >= p.road.lane_count) {
    out.push_back("planner.walkthrough.start_lane must be a lane of the road, 0 to " +
                  std::to_string(p.road.lane_count - 1) + " (got " + std::to_string(w.start_lane) + ")");
  }
  return out;
}

}  // namespace overtake::planner
