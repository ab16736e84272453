#pragma once
// Plain value types for planar geometry and Frenet coordinates.

#include <cmath>
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
/// The vector turned 90 degrees clockwise (to the right of the direction of travel).
[[nodiscard]] constexpr Vec2 right_of(Vec2 a) {
  return {a.y, -a.x};
}

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

/// Distance along a ray from `origin` in the unit direction `direction` to where it enters
/// the rectangle; 0 when the origin is inside it; nullopt when the ray misses it.
[[nodiscard]] std::optional<double> ray_box_distance(Vec2 origin, Vec2 direction,
                                                     const OrientedBox& box);

/// Curvature (1/m) of the circle through three points, signed positive for a left turn;
/// 0 when two of them coincide or they are collinear.
[[nodiscard]] double menger_curvature(Vec2 a, Vec2 b, Vec2 c);

}  // namespace overtake::core
