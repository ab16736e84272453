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
  if (w.start_lane < 0 || w.start_lane >= p.road.lane_count) {
    out.push_back("planner.walkthrough.start_lane must be a lane of the road, 0 to " +
                  std::to_string(p.road.lane_count - 1) + " (got " + std::to_string(w.start_lane) + ")");
  }
  return out;
}

}  // namespace overtake::planner
