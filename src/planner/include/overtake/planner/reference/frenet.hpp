#pragma once
// The map layer of the reference planner: kinematic states in Frenet coordinates of the
// smooth reference line (core::ReferenceLine), and the line's local geometry at a lateral
// offset, which turns Frenet rates into metres per second on the road.

#include <optional>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/spline.hpp"

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

/// The planner's lateral frame: the reference line's d, shifted by a smooth offset of s so
/// that it reads as the original measures d (on the straight segments between waypoints,
/// the chords). On a bend a chord runs inside the curve: a car on a lane's true centre reads
/// up to L^2 / 8R outside it (L the waypoint spacing, R the radius), and the original's
/// referee and traffic go by that reading. The offset is the chord reading's average over
/// the local waypoint spacing (so a car on the frame's lane centre stays within a fraction of
/// that bulge of the original's lane centre), rounded off further and drawn as a periodic
/// cubic spline, so that following it adds little lateral acceleration and jerk.
class LaneFrame {
 public:
  /// The line's own d (no offset). Implicit: any function taking a frame takes a line.
  LaneFrame(const core::ReferenceLine& line);  // NOLINT(google-explicit-constructor)
  /// The frame that matches the original's d on the line's waypoints (read in the middle of
  /// `road`).
  [[nodiscard]] static LaneFrame chord_aligned(const core::ReferenceLine& line,
                                               const core::RoadParams& road);

  [[nodiscard]] const core::ReferenceLine& line() const { return *line_; }
  /// Frame d minus the line's d at s.
  [[nodiscard]] double offset(double s_m) const;
  /// d(offset)/ds at s.
  [[nodiscard]] double slope(double s_m) const;
  /// The original's reading of a frame d at s (the chords' d itself, before averaging).
  [[nodiscard]] double original_d(double s_m, double d_m) const {
    return original_d(reading(s_m), d_m);
  }

  /// What original_d reads at one s, for reading many d there.
  struct Reading {
    bool shifted = false;  ///< false: the frame has no offset, d reads as it is
    double offset_m = 0.0;
    double chord_m = 0.0;  ///< the chords' d minus the line's
  };
  [[nodiscard]] Reading reading(double s_m) const;
  /// original_d at the s of `r` (the same number).
  [[nodiscard]] static double original_d(const Reading& r, double d_m) {
    return r.shifted ? d_m - r.offset_m + r.chord_m : d_m;
  }
  /// offset and slope at s from one lookup of the offset's spline.
  struct OffsetSlope {
    double offset_m = 0.0;
    double slope = 0.0;
  };
  [[nodiscard]] OffsetSlope offset_slope(double s_m) const;

 private:
  const core::ReferenceLine* line_;
  std::optional<core::PiecewiseCubic> offset_;  // of s; none: no offset
  std::vector<double> reading_;                 // the chords' d minus the line's, per metre of s
};

/// The reference line's geometry at one (s, d).
struct RoadPoint {
  core::Vec2 position;         ///< map position of (s, d)
  core::Vec2 tangent;          ///< unit, direction of travel
  core::Vec2 normal;           ///< unit, increasing d
  double along_scale = 1.0;    ///< metres travelled along the road at d per unit of s
  double curvature_1pm = 0.0;  ///< signed curvature of the line at offset d (left turn > 0)
  double offset_slope = 0.0;   ///< the frame's d(offset)/ds there
};

/// The frame's geometry at (s, d) with one evaluation of the line.
[[nodiscard]] RoadPoint road_point(const LaneFrame& frame, double s_m, double d_m);
/// The same from the line's frame `f` and the frame's offset and slope `o` at s (for several
/// d at one s, read once).
[[nodiscard]] RoadPoint road_point(const core::RoadFrame& f, const LaneFrame::OffsetSlope& o,
                                   double d_m);

/// Map velocity of a Frenet state (its position given by `at`).
[[nodiscard]] inline core::Vec2 cartesian_velocity(const RoadPoint& at, const FrenetState& x) {
  return (x.s_dot * at.along_scale) * at.tangent +
         (x.d_dot_mps - at.offset_slope * x.s_dot) * at.normal;
}

/// Speed (m/s) of a Frenet state.
[[nodiscard]] inline double cartesian_speed(const RoadPoint& at, const FrenetState& x) {
  return core::norm(cartesian_velocity(at, x));
}

/// The Frenet state of a car at `position` with map velocity `velocity` (acceleration 0);
/// `s_hint_m` as for ReferenceLine::to_frenet. `at`, when given, receives the frame's
/// geometry there (road_point at the state's s and d).
[[nodiscard]] FrenetState frenet_from_cartesian(const LaneFrame& frame, core::Vec2 position,
                                                core::Vec2 velocity, double s_hint_m,
                                                RoadPoint* at = nullptr);

}  // namespace overtake::planner::reference
