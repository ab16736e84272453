#include "overtake/planner/reference/assertiveness.hpp"

#include <algorithm>

namespace overtake::planner {

const std::vector<AssertivenessKey>& assertiveness_keys() {
  using S = AssertivenessStage;
  using P = ReferenceParams;
  // The margins' edge: no soft cost for nearness, a fifth of the shipped margins, a quarter of
  // the gap, and the cars around assumed to brake at 9 m/s^2 (tests/data/risk/weak2.json: about
  // two at-fault contacts per 100 mi). The pace's edge: acceleration and jerk up to 8.5 and
  // 9 (the rubric's limits are 10 and 10), the ego's own braking 8 m/s^2 after 0.1 s, no
  // hysteresis, 0.5 s between changes, a fifth of the gap ahead to pass through a lane, and
  // passing a car 12 m/s slower (docs/figures.md, "The reference against the public programs").
  static const std::vector<AssertivenessKey> keys = {
      {"trajectory.proximity_weight", 0.0, true, S::margins,
       [](P& p) -> double& { return p.trajectory.proximity_weight; }},
      {"trajectory.rear_weight", 0.0, true, S::margins,
       [](P& p) -> double& { return p.trajectory.rear_weight; }},
      {"trajectory.lon_margin_m", 0.2, false, S::margins,
       [](P& p) -> double& { return p.trajectory.lon_margin_m; }},
      {"trajectory.lat_margin_m", 0.1, false, S::margins,
       [](P& p) -> double& { return p.trajectory.lat_margin_m; }},
      {"behaviour.min_gap_m", 1.0, false, S::margins,
       [](P& p) -> double& { return p.behaviour.min_gap_m; }},
      {"behaviour.change_front_factor", 0.2, false, S::margins,
       [](P& p) -> double& { return p.behaviour.change_front_factor; }},
      {"behaviour.lead_brake_mps2", 9.0, false, S::margins,
       [](P& p) -> double& { return p.behaviour.lead_brake_mps2; }},
      {"behaviour.follower_brake_mps2", 9.0, false, S::margins,
       [](P& p) -> double& { return p.behaviour.follower_brake_mps2; }},
      {"trajectory.max_accel_mps2", 8.5, false, S::pace,
       [](P& p) -> double& { return p.trajectory.max_accel_mps2; }},
      {"trajectory.max_jerk_mps3", 9.0, false, S::pace,
       [](P& p) -> double& { return p.trajectory.max_jerk_mps3; }},
      {"behaviour.ego_brake_mps2", 8.0, false, S::pace,
       [](P& p) -> double& { return p.behaviour.ego_brake_mps2; }},
      {"behaviour.response_time_s", 0.1, false, S::pace,
       [](P& p) -> double& { return p.behaviour.response_time_s; }},
      {"behaviour.hysteresis", 0.0, false, S::pace,
       [](P& p) -> double& { return p.behaviour.hysteresis; }},
      {"behaviour.change_dwell_s", 0.5, false, S::pace,
       [](P& p) -> double& { return p.behaviour.change_dwell_s; }},
      {"behaviour.transit_front_factor", 0.2, false, S::pace,
       [](P& p) -> double& { return p.behaviour.transit_front_factor; }},
      {"behaviour.passing_speed_mps", 12.0, false, S::pace,
       [](P& p) -> double& { return p.behaviour.passing_speed_mps; }},
  };
  return keys;
}

double assertiveness_progress(AssertivenessStage stage, double a) {
  a = std::clamp(a, 0.0, 1.0);
  const double past = std::max(0.0, a - kAssertivenessPaceFrom) / (1.0 - kAssertivenessPaceFrom);
  if (stage == AssertivenessStage::pace) return past;
  if (a <= kAssertivenessPaceFrom) return a;
  return kAssertivenessPaceFrom + past * (kAssertivenessMarginsAtOne - kAssertivenessPaceFrom);
}

ReferenceParams with_assertiveness(const ReferenceParams& from, double a) {
  a = std::clamp(a, 0.0, 1.0);
  ReferenceParams p = from;
  p.assertiveness = a;
  for (const AssertivenessKey& k : assertiveness_keys()) {
    double& v = k.field(p);
    const double s = assertiveness_progress(k.stage, a);
    v = k.soft_cost ? v * (1.0 - s) * (1.0 - s) : v + (k.edge - v) * s;
  }
  return p;
}

}  // namespace overtake::planner
