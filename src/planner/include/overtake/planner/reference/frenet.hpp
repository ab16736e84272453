#pragma once
// The map layer of the reference planner: kinematic states in Frenet coordinates of the
// smooth reference line (core::ReferenceLine), and the line's local geometry at a lateral
// offset, which turns Frenet rates into metres per second on the road.

#include "overtake/core/geometry.hpp"
#include "overtake/core/reference_line.hpp"

namespace overtake::planner::reference {

/// A kinematic state in Frenet coordinates (Werling et al. 2010): s along the reference line
/// and d across it, each with its first two time derivatives. s is not wrapped: it may run
/// past the loop's length within one plan.
struct FrenetState {
  double s_m = 0.0;
  double s_dot = 0.0;   ///< ds/dt (units of s per second)
  double s_ddot = 0.0;  ///< d2s/dt2
  double d_m = 0.0;
  double d_dot_mps = 0.0;
  double d_ddot_mps2 = 0.0;
  friend constexpr bool operator==(const FrenetState&, const FrenetState&) = default;
};

/// The reference line's geometry at one (s, d).
struct RoadPoint {
  core::Vec2 position;        ///< map position of (s, d)
  core::Vec2 tangent;         ///< unit, direction of travel
  core::Vec2 normal;          ///< unit, increasing d
  double along_scale = 1.0;   ///< metres travelled along the road at d per unit of s
  double curvature_1pm = 0.0; ///< signed curvature of the line at offset d (left turn > 0)
};

/// The line's geometry at (s, d) with one evaluation of the line.
[[nodiscard]] RoadPoint road_point(const core::ReferenceLine& line, double s_m, double d_m);

/// Map velocity of a Frenet state (its position given by `at`).
[[nodiscard]] inline core::Vec2 cartesian_velocity(const RoadPoint& at, const FrenetState& x) {
  return (x.s_dot * at.along_scale) * at.tangent + x.d_dot_mps * at.normal;
}

/// Speed (m/s) of a Frenet state.
[[nodiscard]] inline double cartesian_speed(const RoadPoint& at, const FrenetState& x) {
  return core::norm(cartesian_velocity(at, x));
}

/// The Frenet state of a car at `position` with map velocity `velocity` (acceleration 0);
/// `s_hint_m` as for ReferenceLine::to_frenet.
[[nodiscard]] FrenetState frenet_from_cartesian(const core::ReferenceLine& line, core::Vec2 position,
                                                core::Vec2 velocity, double s_hint_m);

}  // namespace overtake::planner::reference
