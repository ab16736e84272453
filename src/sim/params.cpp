#include "overtake/sim/params.hpp"

#include <cmath>
#include <sstream>

namespace overtake::sim {
namespace {

// Collects problems while walking the field lists: every number must be finite; the
// range checks below name the key.
class Checker {
 public:
  explicit Checker(std::vector<std::string>& out) : out_(out) {}

  void positive(const std::string& key, double v) {
    if (!(v > 0.0) || !std::isfinite(v)) add(key, v, "must be a positive number");
  }
  void non_negative(const std::string& key, double v) {
    if (!(v >= 0.0) || !std::isfinite(v)) add(key, v, "must be zero or more");
  }
  void in_range(const std::string& key, double v, double lo, double hi) {
    if (!(v >= lo && v <= hi)) {
      std::ostringstream os;
      os << "must be between " << lo << " and " << hi;
      add(key, v, os.str());
    }
  }
  void ordered(const std::string& lo_key, double lo, const std::string& hi_key, double hi) {
    if (lo > hi) out_.push_back(lo_key + " (" + fmt(lo) + ") must not exceed " + hi_key + " (" + fmt(hi) + ")");
  }

 private:
  static std::string fmt(double v) {
    std::ostringstream os;
    os << v;
    return os.str();
  }
  void add(const std::string& key, double v, const std::string& what) {
    out_.push_back(key + " " + what + " (got " + fmt(v) + ")");
  }
  std::vector<std::string>& out_;
};

}  // namespace

std::vector<std::string> validate(const WorldParams& p) {
  std::vector<std::string> out;
  Checker c(out);
  c.positive("world.step_s", p.step_s);
  c.in_range("world.min_steps_per_call", p.min_steps_per_call, 1, 1000);
  c.in_range("world.max_steps_per_call", p.max_steps_per_call, 1, 1000);
  c.ordered("world.min_steps_per_call", p.min_steps_per_call, "world.max_steps_per_call",
            p.max_steps_per_call);
  c.in_range("road.lane_count", p.road.lane_count, 1, 8);
  c.positive("road.lane_width_m", p.road.lane_width_m);

  const auto& e = p.ego;
  c.positive("world.ego.length_m", e.length_m);
  c.positive("world.ego.width_m", e.width_m);
  c.non_negative("world.ego.stand_on_tolerance_m", e.stand_on_tolerance_m);
  c.in_range("world.ego.start_d_m", e.start_d_m, 0.0, p.road.lane_count * p.road.lane_width_m);
  if (!std::isfinite(e.start_s_m)) out.push_back("world.ego.start_s_m must be finite");

  const auto& t = p.traffic;
  c.in_range("world.traffic.car_count", t.car_count, 0, 64);
  c.positive("world.traffic.car_length_m", t.car_length_m);
  c.positive("world.traffic.car_width_m", t.car_width_m);
  c.positive("world.traffic.despawn_distance_m", t.despawn_distance_m);
  c.in_range("world.traffic.behind_probability", t.behind_probability, 0.0, 1.0);
  c.in_range("world.traffic.behind_min_waypoints", t.behind_min_waypoints, 1, 100);
  c.in_range("world.traffic.behind_max_waypoints", t.behind_max_waypoints, 1, 100);
  c.ordered("world.traffic.behind_min_waypoints", t.behind_min_waypoints,
            "world.traffic.behind_max_waypoints", t.behind_max_waypoints);
  c.in_range("world.traffic.ahead_min_waypoints", t.ahead_min_waypoints, 1, 100);
  c.in_range("world.traffic.ahead_max_waypoints", t.ahead_max_waypoints, 1, 100);
  c.ordered("world.traffic.ahead_min_waypoints", t.ahead_min_waypoints,
            "world.traffic.ahead_max_waypoints", t.ahead_max_waypoints);
  c.non_negative("world.traffic.behind_min_speed_mps", t.behind_min_speed_mps);
  c.ordered("world.traffic.behind_min_speed_mps", t.behind_min_speed_mps,
            "world.traffic.behind_max_speed_mps", t.behind_max_speed_mps);
  c.non_negative("world.traffic.ahead_min_speed_mps", t.ahead_min_speed_mps);
  c.ordered("world.traffic.ahead_min_speed_mps", t.ahead_min_speed_mps,
            "world.traffic.ahead_max_speed_mps", t.ahead_max_speed_mps);
  c.non_negative("world.traffic.min_spawn_distance_m", t.min_spawn_distance_m);
  c.positive("world.traffic.spawn_brake_mps2", t.spawn_brake_mps2);
  c.in_range("world.traffic.max_spawn_attempts", t.max_spawn_attempts, 1, 100000);
  c.in_range("world.traffic.batch_min_frames", t.batch_min_frames, 1, 100000);
  c.in_range("world.traffic.batch_max_frames", t.batch_max_frames, 1, 100000);
  c.ordered("world.traffic.batch_min_frames", t.batch_min_frames, "world.traffic.batch_max_frames",
            t.batch_max_frames);
  c.in_range("world.traffic.batch_min_cars", t.batch_min_cars, 1, 64);
  c.in_range("world.traffic.batch_max_cars", t.batch_max_cars, 1, 64);
  c.ordered("world.traffic.batch_min_cars", t.batch_min_cars, "world.traffic.batch_max_cars",
            t.batch_max_cars);
  c.non_negative("world.traffic.wander_amplitude_m", t.wander_amplitude_m);
  c.positive("world.traffic.wander_min_period_s", t.wander_min_period_s);
  c.ordered("world.traffic.wander_min_period_s", t.wander_min_period_s,
            "world.traffic.wander_max_period_s", t.wander_max_period_s);
  c.positive("world.traffic.lane_change_duration_s", t.lane_change_duration_s);

  const auto& f = t.faithful;
  c.non_negative("world.traffic.faithful.reaction_gain_m", f.reaction_gain_m);
  c.positive("world.traffic.faithful.min_reaction_m", f.min_reaction_m);
  c.ordered("world.traffic.faithful.min_reaction_m", f.min_reaction_m,
            "world.traffic.faithful.max_reaction_m", f.max_reaction_m);
  c.positive("world.traffic.faithful.ego_reaction_m", f.ego_reaction_m);
  c.positive("world.traffic.faithful.brake_mps2", f.brake_mps2);
  c.positive("world.traffic.faithful.accel_mps2", f.accel_mps2);
  c.non_negative("world.traffic.faithful.lane_change_min_speed_mps", f.lane_change_min_speed_mps);
  c.non_negative("world.traffic.faithful.lane_change_interval_s", f.lane_change_interval_s);
  c.positive("world.traffic.faithful.waypoint_trigger_m", f.waypoint_trigger_m);
  c.non_negative("world.traffic.faithful.clear_gap_m", f.clear_gap_m);
  c.in_range("world.traffic.faithful.clear_steps", f.clear_steps, 0, 100000);
  c.non_negative("world.traffic.faithful.ego_lane_radius_m", f.ego_lane_radius_m);

  const auto& m = t.calm;
  c.positive("world.traffic.calm.time_headway_s", m.time_headway_s);
  c.non_negative("world.traffic.calm.min_gap_m", m.min_gap_m);
  c.positive("world.traffic.calm.max_accel_mps2", m.max_accel_mps2);
  c.positive("world.traffic.calm.comfort_decel_mps2", m.comfort_decel_mps2);
  c.positive("world.traffic.calm.accel_exponent", m.accel_exponent);
  c.positive("world.traffic.calm.max_brake_mps2", m.max_brake_mps2);
  c.in_range("world.traffic.calm.politeness", m.politeness, 0.0, 10.0);
  c.non_negative("world.traffic.calm.change_threshold_mps2", m.change_threshold_mps2);
  c.positive("world.traffic.calm.safe_decel_mps2", m.safe_decel_mps2);
  c.non_negative("world.traffic.calm.lane_change_interval_s", m.lane_change_interval_s);

  const auto& r = p.referee;
  c.positive("world.referee.speed_limit_mps", r.speed_limit_mps);
  c.positive("world.referee.max_accel_mps2", r.max_accel_mps2);
  c.positive("world.referee.max_jerk_mps3", r.max_jerk_mps3);
  c.in_range("world.referee.accel_block_steps", r.accel_block_steps, 1, 10000);
  c.in_range("world.referee.jerk_group_blocks", r.jerk_group_blocks, 1, 10000);
  c.ordered("world.referee.min_d_m", r.min_d_m, "world.referee.max_d_m", r.max_d_m);
  c.non_negative("world.referee.line_band_half_width_m", r.line_band_half_width_m);
  c.in_range("world.referee.straddle_max_steps", r.straddle_max_steps, 1, 1000000);
  c.in_range("world.referee.latch_steps", r.latch_steps, 1, 1000000);
  c.in_range("world.referee.strict_window_steps", r.strict_window_steps, 1, 1000);
  c.positive("world.referee.car_length_m", r.car_length_m);
  c.positive("world.referee.car_width_m", r.car_width_m);
  return out;
}

}  // namespace overtake::sim
