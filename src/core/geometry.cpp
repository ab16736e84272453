#include "overtake/core/geometry.hpp"

#include <array>
#include <cmath>

namespace overtake::core {
namespace {

struct Axes {
  Vec2 u;  // along the heading
  Vec2 v;  // across
};

Axes axes_of(const OrientedBox& b) {
  const Vec2 u{std::cos(b.heading_rad), std::sin(b.heading_rad)};
  return {u, {-u.y, u.x}};
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

double menger_curvature(Vec2 a, Vec2 b, Vec2 c) {
  const double ab = distance(a, b);
  const double bc = distance(b, c);
  const double ca = distance(c, a);
  const double denom = ab * bc * ca;
  if (denom <= 0.0) return 0.0;
  return 2.0 * cross(b - a, c - a) / denom;
}

}  // namespace overtake::core
