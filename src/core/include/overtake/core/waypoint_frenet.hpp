#pragma once
// Frenet coordinates as the original simulator measures them: on the straight segments
// (chords) between consecutive waypoints, not on a smooth curve. The original reports every
// s and d this way (the ego's, the other cars', the end of the queued path), its traffic
// decides lane changes on them, and its referee checks the ego's lane on them. On a bend a
// point on a lane's true centre reads up to L^2 / 8R off that centre (L the waypoint
// spacing, R the radius): about 1.2 m at L = 38 m, R = 150 m.
//
// The rule (CarAIControl.getFrenetFrame in the original): find the waypoint closest to a
// reference position; the "next" waypoint is that one, or the one after it when the point
// is already past it (measured along the road's direction at that waypoint); project the
// point onto the line from the waypoint before "next" to "next". s is that waypoint's s plus
// the length of the projection (not clamped to the segment); d is the distance from the
// line, negative on the divider's side.

#include <cstddef>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/map.hpp"

namespace overtake::core {

/// The original's waypoint-chord Frenet frame of one map. Immutable; cheap queries.
class WaypointFrenet {
 public:
  explicit WaypointFrenet(const Map& map);

  [[nodiscard]] std::size_t size() const { return position_.size(); }
  [[nodiscard]] double loop_length_m() const { return loop_length_m_; }
  [[nodiscard]] Vec2 position(std::size_t i) const { return position_[i]; }
  /// Unit normal at waypoint i, away from the divider (the map's dx, dy).
  [[nodiscard]] Vec2 normal(std::size_t i) const { return normal_[i]; }
  /// Unit direction of travel at waypoint i (the normal turned towards the road's heading).
  [[nodiscard]] Vec2 forward(std::size_t i) const { return forward_[i]; }
  [[nodiscard]] double s(std::size_t i) const { return s_[i]; }
  /// The point `offset_m` from waypoint i along its normal (a lane's point: 2 + 4k).
  [[nodiscard]] Vec2 offset_point(std::size_t i, double offset_m) const {
    return position_[i] + offset_m * normal_[i];
  }
  /// Index i + k around the loop (k may be negative).
  [[nodiscard]] std::size_t wrap_index(long i) const;

  /// The waypoint nearest to `p` (straight-line distance), over the whole map.
  [[nodiscard]] std::size_t closest(Vec2 p) const;
  /// The same, searched from `hint` (e.g. last step's answer) while a neighbour is nearer; the
  /// whole map is searched when that ends far from `p` (on a map folding close to itself a
  /// local search could stop at the wrong stretch).
  [[nodiscard]] std::size_t closest(Vec2 p, std::size_t hint) const;
  /// The original's next waypoint of `p`, given the waypoint closest to the reference
  /// position: that one, or the one after it when `p` is past it.
  [[nodiscard]] std::size_t next(Vec2 p, std::size_t closest_index) const;
  /// Frenet of `p` on the chord ending at next(p, closest_index). For a car's own position
  /// pass its own closest waypoint; the original measures the end of the ego's path from
  /// the ego's closest waypoint instead (so far ahead on a bend, d drifts off).
  [[nodiscard]] FrenetPoint to_frenet(Vec2 p, std::size_t closest_index) const;
  /// Frenet of `p` from its own closest waypoint.
  [[nodiscard]] FrenetPoint to_frenet(Vec2 p) const { return to_frenet(p, closest(p)); }
  /// The point at (s, d) on the chords, the course's helper getXY: s wraps at the loop
  /// length, d is measured along the chord's normal on the side the map's normals point to.
  [[nodiscard]] Vec2 to_cartesian(FrenetPoint f) const;
  /// Heading (radians, counter-clockwise from +x) of the chord that to_cartesian uses at s.
  [[nodiscard]] double chord_heading_rad(double s_m) const;

 private:
  [[nodiscard]] std::size_t segment_start(double s_m) const;
  std::vector<Vec2> position_;
  std::vector<Vec2> normal_;
  std::vector<Vec2> forward_;
  std::vector<double> s_;
  std::vector<double> side_;  // +1 when the map's normal at i is to the right of the chord i->i+1
  double loop_length_m_ = 0.0;
  double max_spacing_m_ = 0.0;
};

}  // namespace overtake::core
