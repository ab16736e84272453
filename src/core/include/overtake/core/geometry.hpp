#pragma once
// Plain value types for planar geometry and Frenet coordinates.

#include <bit>
#include <cmath>
#include <cstdint>
#include <optional>

namespace overtake::core {

/// A point or vector in map axes (metres, or metres per second for velocities).
struct Vec2 {
  double x = 0.0;
  double y = 0.0;

  friend constexpr Vec2 operator+(Vec2 a, Vec2 b) { return {a.x + b.x, a.y + b.y}; }
  friend constexpr Vec2 operator-(Vec2 a, Vec2 b) { return {a.x - b.x, a.y - b.y}; }
  friend constexpr Vec2 operator*(double k, Vec2 a) { return {k * a.x, k * a.y}; }
  friend constexpr Vec2 operator*(Vec2 a, double k) { return {k * a.x, k * a.y}; }
  friend constexpr bool operator==(Vec2, Vec2) = default;
};

[[nodiscard]] constexpr double dot(Vec2 a, Vec2 b) {
  return a.x * b.x + a.y * b.y;
}
[[nodiscard]] constexpr double cross(Vec2 a, Vec2 b) {
  return a.x * b.y - a.y * b.x;
}
[[nodiscard]] inline double norm(Vec2 a) {
  return std::hypot(a.x, a.y);
}
[[nodiscard]] inline double distance(Vec2 a, Vec2 b) {
  return norm(a - b);
}
[[nodiscard]] constexpr double distance_sq(Vec2 a, Vec2 b) {
  return dot(a - b, a - b);
}
/// Exactly distance(a, b) >= r, without the hypot when the squared distance is clear of r^2
/// (by a relative 1e-9, far beyond the rounding of either): most calls are nowhere near the
/// boundary.
[[nodiscard]] inline bool distance_at_least(Vec2 a, Vec2 b, double r) {
  const double d2 = distance_sq(a, b);
  if (r > 1e-150 && r < 1e150 && d2 < 1e300) {
    const double r2 = r * r;
    if (d2 > r2 * (1.0 + 1e-9)) return true;
    if (d2 < r2 * (1.0 - 1e-9)) return false;
  }
  return distance(a, b) >= r;
}
/// The vector turned 90 degrees clockwise (to the right of the direction of travel).
[[nodiscard]] constexpr Vec2 right_of(Vec2 a) {
  return {a.y, -a.x};
}

/// The unit vector along a heading: {cos, sin}. Callers that need it for one heading many
/// times compute it once and pass it to the overloads below that take a box's axis.
[[nodiscard]] inline Vec2 heading_unit(double heading_rad) {
  return {std::cos(heading_rad), std::sin(heading_rad)};
}

/// heading_unit of the heading last asked for, kept with that heading's bits: a body's
/// heading is read several times a step but changes at most once, so the sine and cosine
/// are computed once. Any other heading (even -0 for 0) is computed afresh.
class HeadingUnit {
 public:
  [[nodiscard]] Vec2 of(double heading_rad) {
    const auto bits = std::bit_cast<std::uint64_t>(heading_rad);
    if (bits != bits_) {
      bits_ = bits;
      unit_ = heading_unit(heading_rad);
    }
    return unit_;
  }
  /// The unit of the heading last asked for.
  [[nodiscard]] Vec2 of_current() const { return unit_; }

 private:
  std::uint64_t bits_ = 0;  // of +0.0, whose unit is exactly {1, 0}
  Vec2 unit_{1.0, 0.0};
};

/// A position along the road: s along the reference line, d to the right of it (away from
/// the divider).
struct FrenetPoint {
  double s_m = 0.0;
  double d_m = 0.0;
  friend constexpr bool operator==(FrenetPoint, FrenetPoint) = default;
};

/// A rectangle centred on `center`, its length along `heading_rad`.
struct OrientedBox {
  Vec2 center;
  double heading_rad = 0.0;
  double length_m = 0.0;
  double width_m = 0.0;
};

/// True when the two rectangles overlap (separating-axis test); touching edges count.
[[nodiscard]] bool boxes_overlap(const OrientedBox& a, const OrientedBox& b);

/// How two overlapping rectangles interpenetrate: the shortest push that separates them.
struct Penetration {
  Vec2 normal;           ///< unit, pointing from the first box towards the second
  double depth_m = 0.0;  ///< moving the second box this far along `normal` separates them
};

/// The penetration of two rectangles (separating-axis test, smallest overlap over the four
/// axes); nullopt when they do not overlap. Touching edges give depth 0.
[[nodiscard]] std::optional<Penetration> box_penetration(const OrientedBox& a,
                                                         const OrientedBox& b);
/// The same with each box's axis given: heading_unit of its heading, exactly.
[[nodiscard]] std::optional<Penetration> box_penetration(const OrientedBox& a, Vec2 a_axis,
                                                         const OrientedBox& b, Vec2 b_axis);

/// Distance along a ray from `origin` in the unit direction `direction` to where it enters
/// the rectangle; 0 when the origin is inside it; nullopt when the ray misses it.
[[nodiscard]] std::optional<double> ray_box_distance(Vec2 origin, Vec2 direction,
                                                     const OrientedBox& box);
/// The same with the box's axis given: heading_unit(box.heading_rad), exactly.
[[nodiscard]] std::optional<double> ray_box_distance(Vec2 origin, Vec2 direction,
                                                     const OrientedBox& box, Vec2 box_axis);

/// Curvature (1/m) of the circle through three points, signed positive for a left turn;
/// 0 when two of them coincide or they are collinear.
[[nodiscard]] double menger_curvature(Vec2 a, Vec2 b, Vec2 c);

}  // namespace overtake::core
