#include "overtake/planner/reference/frenet.hpp"

namespace overtake::planner::reference {

RoadPoint road_point(const core::ReferenceLine& line, double s_m, double d_m) {
  const core::RoadFrame f = line.frame(s_m);
  // +1 when the normal points to the right of travel; the line's curvature-at-offset rule
  // depends on it.
  const double side = core::dot(f.normal, core::right_of(f.tangent)) >= 0.0 ? 1.0 : -1.0;
  const double stretch = 1.0 + side * f.curvature_1pm * d_m;
  RoadPoint p;
  p.position = f.position + d_m * f.normal;
  p.tangent = f.tangent;
  p.normal = f.normal;
  p.along_scale = f.ds_scale * stretch;
  p.curvature_1pm = f.curvature_1pm / stretch;
  return p;
}

FrenetState frenet_from_cartesian(const core::ReferenceLine& line, core::Vec2 position,
                                  core::Vec2 velocity, double s_hint_m) {
  const core::FrenetPoint f = line.to_frenet(position, s_hint_m);
  const RoadPoint at = road_point(line, f.s_m, f.d_m);
  FrenetState x;
  x.s_m = f.s_m;
  x.d_m = f.d_m;
  x.s_dot = at.along_scale > 1e-9 ? core::dot(velocity, at.tangent) / at.along_scale : 0.0;
  x.d_dot_mps = core::dot(velocity, at.normal);
  return x;
}

}  // namespace overtake::planner::reference
