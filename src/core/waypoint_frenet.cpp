#include "overtake/core/waypoint_frenet.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

namespace overtake::core {
namespace {

/// A local search that ends farther than this beyond the largest waypoint spacing from the
/// point is not trusted: the point is off the road, or the map folds near itself.
constexpr double kLocalSearchSlackM = 20.0;

}  // namespace

WaypointFrenet::WaypointFrenet(const Map& map) : loop_length_m_(map.loop_length_m) {
  const std::size_t n = map.waypoints.size();
  assert(n >= 2);
  position_.reserve(n);
  normal_.reserve(n);
  s_.reserve(n);
  for (const Waypoint& w : map.waypoints) {
    position_.push_back({w.x_m, w.y_m});
    normal_.push_back({w.dx, w.dy});
    s_.push_back(w.s_m);
  }
  forward_.resize(n);
  side_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2 before = position_[(i + n - 1) % n];
    const Vec2 after = position_[(i + 1) % n];
    // The normal turned a quarter turn; the way that points along the road.
    const Vec2 turned{-normal_[i].y, normal_[i].x};
    forward_[i] = dot(turned, after - before) >= 0.0 ? turned : -1.0 * turned;
    const Vec2 chord = after - position_[i];
    side_[i] = dot(normal_[i], right_of(chord)) >= 0.0 ? 1.0 : -1.0;
    max_spacing_m_ = std::max(max_spacing_m_, norm(chord));
  }
}

std::size_t WaypointFrenet::wrap_index(long i) const {
  const auto n = static_cast<long>(position_.size());
  return static_cast<std::size_t>(((i % n) + n) % n);
}

std::size_t WaypointFrenet::closest(Vec2 p) const {
  std::size_t best = 0;
  double best_sq = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < position_.size(); ++i) {
    const double d2 = distance_sq(position_[i], p);
    if (d2 < best_sq) {
      best_sq = d2;
      best = i;
    }
  }
  return best;
}

std::size_t WaypointFrenet::closest(Vec2 p, std::size_t hint) const {
  const std::size_t n = position_.size();
  std::size_t i = hint % n;
  double here = distance_sq(position_[i], p);
  for (std::size_t step = 0; step < n; ++step) {
    const std::size_t prev = (i + n - 1) % n;
    const std::size_t next = (i + 1) % n;
    const double dp = distance_sq(position_[prev], p);
    const double dn = distance_sq(position_[next], p);
    if (dn < here && dn <= dp) {
      i = next;
      here = dn;
    } else if (dp < here) {
      i = prev;
      here = dp;
    } else {
      break;
    }
  }
  const double trusted = max_spacing_m_ + kLocalSearchSlackM;
  if (here > trusted * trusted) return closest(p);
  return i;
}

std::size_t WaypointFrenet::next(Vec2 p, std::size_t closest_index) const {
  const Vec2 heading = position_[closest_index] - p;
  if (dot(heading, forward_[closest_index]) < 0.0) return (closest_index + 1) % position_.size();
  return closest_index;
}

FrenetPoint WaypointFrenet::to_frenet(Vec2 p, std::size_t closest_index) const {
  const std::size_t n = position_.size();
  const std::size_t nx = next(p, closest_index);
  const std::size_t prev = nx == 0 ? n - 1 : nx - 1;
  const Vec2 v = position_[nx] - position_[prev];
  const Vec2 x0 = p - position_[prev];
  const double len_sq = dot(v, v);
  const double t = len_sq > 0.0 ? dot(x0, v) / len_sq : 0.0;
  const Vec2 proj = t * v;
  const Vec2 off = x0 - proj;
  double d = norm(off);
  if (dot(off, normal_[prev] + normal_[nx]) < 0.0) d = -d;
  return {s_[prev] + norm(proj), d};
}

std::size_t WaypointFrenet::segment_start(double s_m) const {
  const double s0 = s_.front();
  double s = std::fmod(s_m - s0, loop_length_m_);
  if (s < 0.0) s += loop_length_m_;
  s += s0;
  const auto it = std::upper_bound(s_.begin(), s_.end(), s);
  return it == s_.begin() ? 0 : static_cast<std::size_t>(it - s_.begin()) - 1;
}

Vec2 WaypointFrenet::to_cartesian(FrenetPoint f) const {
  const std::size_t i = segment_start(f.s_m);
  const std::size_t j = (i + 1) % position_.size();
  const Vec2 chord = position_[j] - position_[i];
  const double len = norm(chord);
  const Vec2 dir = len > 0.0 ? (1.0 / len) * chord : forward_[i];
  double along = std::fmod(f.s_m - s_[i], loop_length_m_);
  if (along < 0.0) along += loop_length_m_;
  return position_[i] + along * dir + (f.d_m * side_[i]) * right_of(dir);
}

double WaypointFrenet::chord_heading_rad(double s_m) const {
  const std::size_t i = segment_start(s_m);
  const Vec2 chord = position_[(i + 1) % position_.size()] - position_[i];
  return std::atan2(chord.y, chord.x);
}

}  // namespace overtake::core
