#include "overtake/planner/walkthrough.hpp"

#include <algorithm>
#include <cmath>

#include "overtake/planner/spline_path.hpp"

namespace overtake::planner {

bool car_too_close(const core::Telemetry& t, const core::ReferenceLine& line, int lane,
                   double from_s_m, double ahead_time_s, double too_close_m,
                   const core::RoadParams& road) {
  const double centre = core::lane_center_d(lane, road);
  const double half = 0.5 * road.lane_width_m;
  for (const core::CarObservation& car : t.cars) {
    if (!(car.d_m < centre + half && car.d_m > centre - half)) continue;
    const double speed = core::norm(car.velocity_mps);
    const double projected_s = car.s_m + ahead_time_s * speed;
    const double gap = line.s_ahead(from_s_m, projected_s);
    if (gap > 0.0 && gap < too_close_m) return true;
  }
  return false;
}

WalkthroughPolicy::WalkthroughPolicy(const core::ReferenceLine& line, const PlannerParams& params)
    : line_(line),
      road_(params.road),
      step_s_(params.step_s),
      p_(params.walkthrough),
      lane_(params.walkthrough.start_lane) {}

core::PlanResult WalkthroughPolicy::plan(const core::Telemetry& t) {
  const std::size_t prev_size = t.previous_path.size();
  const double car_s = prev_size > 0 ? t.end_path.s_m : t.ego.s_m;
  const double ahead_time_s = static_cast<double>(prev_size) * step_s_;
  const bool too_close = car_too_close(t, line_, lane_, car_s, ahead_time_s, p_.too_close_m, road_);
  if (too_close) {
    // The walkthrough has no floor here; a floor of one step keeps the points apart.
    ref_speed_mps_ = std::max(ref_speed_mps_ - p_.speed_step_mps, p_.speed_step_mps);
  } else if (ref_speed_mps_ < p_.target_speed_mps) {
    ref_speed_mps_ += p_.speed_step_mps;
  }
  SplinePathSpec spec;
  spec.target_d_m = core::lane_center_d(lane_, road_);
  spec.ref_speed_mps = ref_speed_mps_;
  spec.anchor_distances_m = p_.anchor_distances_m;
  spec.path_points = p_.path_points;
  spec.horizon_x_m = p_.horizon_x_m;
  spec.step_s = step_s_;
  return core::normal_plan(spline_path(t, line_, spec));
}

}  // namespace overtake::planner

namespace overtake::planner {

bool WalkthroughPolicy::archive_state(core::StateArchive& ar) {
  ar.part("walkthrough");
  ar.io_range(lane_, 0, road_.lane_count - 1, "lane");
  ar.io_speed(ref_speed_mps_, "reference speed");
  return true;
}

}  // namespace overtake::planner
