#pragma once
// The smooth, closed reference line of a map (periodic cubic splines x(s), y(s) through the
// waypoints) with Frenet <-> Cartesian conversion. s wraps at the loop length.

#include <optional>
#include <span>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/map.hpp"
#include "overtake/core/spline.hpp"

namespace overtake::core {

/// The reference line's local frame at one s.
struct RoadFrame {
  Vec2 position;  ///< on the divider (d = 0)
  Vec2 tangent;   ///< unit, direction of travel
  Vec2 normal;    ///< unit, away from the divider (increasing d)
  double heading_rad = 0.0;
  double curvature_1pm = 0.0;  ///< signed curvature of the d = 0 line, positive for a left turn
  double ds_scale = 1.0;       ///< metres travelled on the divider line per unit of s
};

/// The map's reference line. Immutable after construction; cheap queries.
class ReferenceLine {
 public:
  /// Builds the line through the map's waypoints; throws MapError when they do not make a
  /// usable loop. With a smoothing stiffness (m^3, see PiecewiseCubic::periodic_smoothing)
  /// the line passes near the waypoints instead, damping wiggles that their rounded
  /// coordinates would put in its curvature.
  explicit ReferenceLine(const Map& map, double smoothing_m3 = 0.0);

  [[nodiscard]] double length_m() const { return length_m_; }
  /// s of the first waypoint; s values wrap into [start_s_m, start_s_m + length_m).
  [[nodiscard]] double start_s_m() const { return start_s_m_; }

  /// s wrapped into [start_s_m, start_s_m + length_m).
  [[nodiscard]] double wrap_s(double s_m) const;
  /// Signed distance along the road from `from_s_m` to `to_s_m`, the shorter way round:
  /// positive when `to` is ahead. In (-length/2, length/2].
  [[nodiscard]] double s_ahead(double from_s_m, double to_s_m) const;

  /// s of the map's waypoints, through (or, smoothed, near) which the line passes (in the
  /// map's order).
  [[nodiscard]] std::span<const double> waypoint_s() const {
    const std::span<const double> k = x_.knots();
    return k.first(k.size() - 1);
  }

  /// The map the line was built from: its waypoints as given (not the line's points).
  [[nodiscard]] const Map& map() const { return map_; }

  [[nodiscard]] RoadFrame frame(double s_m) const;
  /// frame(s_m) with heading_rad left at 0, for callers that never read it: its atan2 is
  /// about a third of a frame's cost. Every other field is the same, bit for bit.
  [[nodiscard]] RoadFrame frame_without_heading(double s_m) const;
  [[nodiscard]] Vec2 to_cartesian(FrenetPoint p) const;
  /// Projects a point onto the line. `s_hint_m` (a nearby s, e.g. last step's) makes it
  /// faster; without it, or when the hint leads astray, the whole loop is searched.
  [[nodiscard]] FrenetPoint to_frenet(Vec2 p, std::optional<double> s_hint_m = {}) const;

  /// Curvature (1/m, positive for a left turn) of the line at lateral offset d.
  [[nodiscard]] double curvature_at(double s_m, double d_m) const;
  /// Map velocity of a point moving with ds/dt = s_dot and dd/dt = d_dot at (s, d).
  [[nodiscard]] Vec2 velocity(FrenetPoint p, double s_dot, double d_dot) const;
  /// ds/dt of a point at (s, d) moving along the lane at `speed_mps`.
  [[nodiscard]] double s_rate(FrenetPoint p, double speed_mps) const;

  /// The line at one s (wrapped, its piece found, the splines evaluated) for several of the
  /// queries below at that s: the same results as the calls above with that s, each of
  /// which would look it up again.
  struct Sample {
    double s_m = 0.0;  ///< wrapped
    SplineSample x;
    SplineSample y;
  };
  [[nodiscard]] Sample sample(double s_m) const;
  /// Metres travelled at lateral offset d per unit of s: s_rate(p, v) is v / this.
  [[nodiscard]] double metres_per_s(const Sample& at, double d_m) const;
  /// velocity(p, s_dot, d_dot) and to_cartesian(p) at sample(p.s_m).
  [[nodiscard]] Vec2 velocity(const Sample& at, double d_m, double s_dot, double d_dot) const;
  [[nodiscard]] Vec2 to_cartesian(const Sample& at, double d_m) const;

 private:
  [[nodiscard]] double refine(Vec2 p, double s0) const;
  Map map_;
  PiecewiseCubic x_;
  PiecewiseCubic y_;
  double start_s_m_ = 0.0;
  double length_m_ = 0.0;
  double side_ = 1.0;             // +1: normal to the right of travel, -1: to the left
  std::vector<double> sample_s_;  // dense samples for global projection
  std::vector<Vec2> sample_xy_;
};

}  // namespace overtake::core
