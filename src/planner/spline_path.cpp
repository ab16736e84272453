#include "overtake/planner/spline_path.hpp"

#include <algorithm>
#include <cmath>

#include "overtake/core/spline.hpp"

namespace overtake::planner {

std::vector<core::Vec2> spline_path(const core::Telemetry& t, const core::ReferenceLine& line,
                                    const SplinePathSpec& spec) {
  const auto& prev = t.previous_path;
  const std::size_t prev_size = prev.size();
  std::vector<core::Vec2> out(prev.begin(), prev.end());
  const auto wanted = static_cast<std::size_t>(std::max(spec.path_points, 0));
  if (prev_size >= wanted || !(spec.ref_speed_mps > 0.0) || !(spec.step_s > 0.0)) return out;

  // Two points that continue the current heading, then the anchors.
  core::Vec2 ref;
  double ref_yaw = 0.0;
  std::vector<core::Vec2> pts;
  if (prev_size < 2) {
    ref = t.ego.position;
    ref_yaw = t.ego.yaw_rad;
    pts.push_back(ref - core::Vec2{std::cos(ref_yaw), std::sin(ref_yaw)});
    pts.push_back(ref);
  } else {
    ref = prev[prev_size - 1];
    const core::Vec2 before = prev[prev_size - 2];
    ref_yaw = std::atan2(ref.y - before.y, ref.x - before.x);
    pts.push_back(before);
    pts.push_back(ref);
  }
  const double start_s = prev_size > 0 ? t.end_path.s_m : t.ego.s_m;
  for (const double ahead : spec.anchor_distances_m) {
    pts.push_back(line.to_cartesian({start_s + ahead, spec.target_d_m}));
  }

  // Into the car's frame at `ref`, heading along +x.
  const double c = std::cos(ref_yaw);
  const double s = std::sin(ref_yaw);
  std::vector<double> xs, ys;
  xs.reserve(pts.size());
  ys.reserve(pts.size());
  for (const core::Vec2 p : pts) {
    const core::Vec2 d = p - ref;
    xs.push_back(d.x * c + d.y * s);
    ys.push_back(-d.x * s + d.y * c);
  }
  const auto spline = core::PiecewiseCubic::natural(xs, ys);
  if (!spline) return out;

  const double target_x = spec.horizon_x_m;
  const double target_dist = std::hypot(target_x, (*spline)(target_x));
  const double n = target_dist / (spec.step_s * spec.ref_speed_mps);
  const double dx = target_x / n;
  double x = 0.0;
  for (std::size_t i = prev_size; i < wanted; ++i) {
    x += dx;
    const double y = (*spline)(x);
    out.push_back({ref.x + x * c - y * s, ref.y + x * s + y * c});
  }
  return out;
}

}  // namespace overtake::planner
