#include "overtake/planner/reference/assertiveness.hpp"

#include <algorithm>

namespace overtake::planner {

namespace {

// The field of `p` that `key` names (one of assertiveness_keys()).
double& field_of(ReferenceParams& p, const std::string& key) {
  if (key == "trajectory.proximity_weight") return p.trajectory.proximity_weight;
  if (key == "trajectory.rear_weight") return p.trajectory.rear_weight;
  if (key == "trajectory.lon_margin_m") return p.trajectory.lon_margin_m;
  if (key == "trajectory.lat_margin_m") return p.trajectory.lat_margin_m;
  if (key == "behaviour.min_gap_m") return p.behaviour.min_gap_m;
  if (key == "behaviour.change_front_factor") return p.behaviour.change_front_factor;
  if (key == "behaviour.lead_brake_mps2") return p.behaviour.lead_brake_mps2;
  return p.behaviour.follower_brake_mps2;  // "behaviour.follower_brake_mps2"
}

}  // namespace

const std::vector<AssertivenessKey>& assertiveness_keys() {
  // The edge: no soft cost for nearness, a fifth of the shipped margins, a quarter of the gap,
  // and the cars around assumed to brake at 9 m/s^2 (tests/data/risk/weak2.json: about two
  // at-fault contacts per 100 mi).
  static const std::vector<AssertivenessKey> keys = {
      {"trajectory.proximity_weight", 0.0, true}, {"trajectory.rear_weight", 0.0, true},
      {"trajectory.lon_margin_m", 0.2, false},    {"trajectory.lat_margin_m", 0.1, false},
      {"behaviour.min_gap_m", 1.0, false},        {"behaviour.change_front_factor", 0.2, false},
      {"behaviour.lead_brake_mps2", 9.0, false},  {"behaviour.follower_brake_mps2", 9.0, false},
  };
  return keys;
}

ReferenceParams with_assertiveness(const ReferenceParams& from, double a) {
  a = std::clamp(a, 0.0, 1.0);
  ReferenceParams p = from;
  p.assertiveness = a;
  for (const AssertivenessKey& k : assertiveness_keys()) {
    double& v = field_of(p, k.key);
    v = k.soft_cost ? v * (1.0 - a) * (1.0 - a) : v + (k.edge - v) * a;
  }
  return p;
}

}  // namespace overtake::planner
