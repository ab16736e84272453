#include "overtake/core/geometry.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace overtake::core {
namespace {

struct Axes {
  Vec2 u;  // along the heading
  Vec2 v;  // across
};

Axes axes_of(Vec2 u) {
  return {u, {-u.y, u.x}};
}

Axes axes_of(const OrientedBox& b) {
  return axes_of(heading_unit(b.heading_rad));
}

// Half the extent of box `b` projected on unit axis `n`.
double half_extent(const OrientedBox& b, const Axes& ax, Vec2 n) {
  return 0.5 * b.length_m * std::abs(dot(ax.u, n)) + 0.5 * b.width_m * std::abs(dot(ax.v, n));
}

}  // namespace

bool boxes_overlap(const OrientedBox& a, const OrientedBox& b) {
  const Axes aa = axes_of(a);
  const Axes ab = axes_of(b);
  const Vec2 delta = b.center - a.center;
  const std::array<Vec2, 4> axes{aa.u, aa.v, ab.u, ab.v};
  for (const Vec2 n : axes) {
    const double gap = std::abs(dot(delta, n)) - half_extent(a, aa, n) - half_extent(b, ab, n);
    if (gap > 0.0) return false;
  }
  return true;
}

std::optional<Penetration> box_penetration(const OrientedBox& a, const OrientedBox& b) {
  return box_penetration(a, heading_unit(a.heading_rad), b, heading_unit(b.heading_rad));
}

std::optional<Penetration> box_penetration(const OrientedBox& a, Vec2 a_axis, const OrientedBox& b,
                                           Vec2 b_axis) {
  const Axes aa = axes_of(a_axis);
  const Axes ab = axes_of(b_axis);
  const Vec2 delta = b.center - a.center;
  const std::array<Vec2, 4> axes{aa.u, aa.v, ab.u, ab.v};
  Penetration best{{}, std::numeric_limits<double>::infinity()};
  for (const Vec2 n : axes) {
    const double along = dot(delta, n);
    const double depth = half_extent(a, aa, n) + half_extent(b, ab, n) - std::abs(along);
    if (depth < 0.0) return std::nullopt;
    if (depth < best.depth_m) best = {along >= 0.0 ? n : -1.0 * n, depth};
  }
  return best;
}

std::optional<double> ray_box_distance(Vec2 origin, Vec2 direction, const OrientedBox& box) {
  return ray_box_distance(origin, direction, box, heading_unit(box.heading_rad));
}

std::optional<double> ray_box_distance(Vec2 origin, Vec2 direction, const OrientedBox& box,
                                       Vec2 box_axis) {
  // In the box's own axes: a slab test on each axis.
  const Axes ax = axes_of(box_axis);
  const Vec2 rel = origin - box.center;
  const std::array<double, 2> o{dot(rel, ax.u), dot(rel, ax.v)};
  const std::array<double, 2> d{dot(direction, ax.u), dot(direction, ax.v)};
  const std::array<double, 2> half{0.5 * box.length_m, 0.5 * box.width_m};
  double enter = 0.0;
  double leave = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < 2; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (std::abs(o[k]) > half[k]) return std::nullopt;  // parallel and outside the slab
      continue;
    }
    double t0 = (-half[k] - o[k]) / d[k];
    double t1 = (half[k] - o[k]) / d[k];
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0);
    leave = std::min(leave, t1);
    if (enter > leave) return std::nullopt;
  }
  return enter;
}

double menger_curvature(Vec2 a, Vec2 b, Vec2 c) {
  const double ab = distance(a, b);
  const double bc = distance(b, c);
  const double ca = distance(c, a);
  const double denom = ab * bc * ca;
  if (denom <= 0.0) return 0.0;
  return 2.0 * cross(b - a, c - a) / denom;
}

}  // namespace overtake::core
