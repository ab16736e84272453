// Checking a map against a track spec (check_track): its waypoints (length, spacing,
// coordinates, direction, s values), then along its reference line (normals, radii on every
// lane, bends both ways, the straight start, clearance and self-intersection).

#include "overtake/core/track.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/units.hpp"
#include "track_internal.hpp"

namespace overtake::core {
namespace {

using track_detail::num;
using track_detail::required_start_straight_m;

// ---- Limits and sampling (metres unless named otherwise) ----

constexpr double kLengthTolerance = 0.02;  // fraction of length_m
constexpr double kMaxNormalErrorDeg = 5.0;
constexpr double kMaxSErrorM = 0.05;
constexpr double kCurvatureStepM = 1.0;  // curvature samples of the check
constexpr double kPairStepM = 2.0;       // samples for clearance and crossings
constexpr std::size_t kMaxPairSamples = 6000;
// Two samples of a road with every radius above the chord's length apart along it are at
// least 2/pi of that apart in a straight line; closer than this fraction of it means a
// different stretch of road.
constexpr double kDistinctChordFraction = 0.9 * 2.0 / kPi;

bool segments_cross(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  const double o1 = cross(b - a, c - a);
  const double o2 = cross(b - a, d - a);
  const double o3 = cross(d - c, a - c);
  const double o4 = cross(d - c, b - c);
  if (o1 * o2 > 0.0 || o3 * o4 > 0.0) return false;
  // Collinear: overlap of the boxes decides.
  return std::max(std::min(a.x, b.x), std::min(c.x, d.x)) <=
             std::min(std::max(a.x, b.x), std::max(c.x, d.x)) &&
         std::max(std::min(a.y, b.y), std::min(c.y, d.y)) <=
             std::min(std::max(a.y, b.y), std::max(c.y, d.y));
}

void check_waypoints(const Map& map, const TrackSpec& spec, TrackReport& rep) {
  const auto& w = map.waypoints;
  const std::size_t n = w.size();
  rep.min_spacing_m = std::numeric_limits<double>::infinity();
  std::size_t min_at = 0;
  std::size_t max_at = 0;
  double sum = 0.0;
  double area2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Waypoint& a = w[i];
    const Waypoint& b = w[(i + 1) % n];
    const double gap = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    sum += gap;
    if (gap < rep.min_spacing_m) {
      rep.min_spacing_m = gap;
      min_at = i;
    }
    if (gap > rep.max_spacing_m) {
      rep.max_spacing_m = gap;
      max_at = i;
    }
    area2 += a.x_m * b.y_m - b.x_m * a.y_m;
    rep.max_abs_coordinate_m =
        std::max({rep.max_abs_coordinate_m, std::abs(a.x_m), std::abs(a.y_m)});
  }
  rep.mean_spacing_m = sum / static_cast<double>(n);
  rep.counter_clockwise = area2 > 0.0;

  double along = 0.0;
  for (std::size_t i = 1; i < n; ++i) {
    along += std::hypot(w[i].x_m - w[i - 1].x_m, w[i].y_m - w[i - 1].y_m);
    rep.max_s_error_m = std::max(rep.max_s_error_m, std::abs(w[i].s_m - w[0].s_m - along));
  }

  auto pair_name = [n](std::size_t i) {
    return "waypoints " + std::to_string(i + 1) + " and " + std::to_string((i + 1) % n + 1);
  };
  if (std::abs(rep.length_m - spec.length_m) > kLengthTolerance * spec.length_m) {
    rep.problems.push_back("length_m: the loop is " + num(rep.length_m) + " m long, more than " +
                           num(100.0 * kLengthTolerance, 0) + "% from " + num(spec.length_m) +
                           " m");
  }
  if (rep.min_spacing_m < spec.min_spacing_m) {
    rep.problems.push_back("min_spacing_m: " + pair_name(min_at) + " are " +
                           num(rep.min_spacing_m, 2) + " m apart, under " +
                           num(spec.min_spacing_m) + " m");
  }
  if (rep.max_spacing_m > spec.max_spacing_m) {
    rep.problems.push_back("max_spacing_m: " + pair_name(max_at) + " are " +
                           num(rep.max_spacing_m, 2) + " m apart, over " + num(spec.max_spacing_m) +
                           " m");
  }
  const double coordinate_limit = max_abs_coordinate_for(spec);
  if (rep.max_abs_coordinate_m >= coordinate_limit) {
    rep.problems.push_back(
        "max_abs_coordinate_m: a waypoint has |x| or |y| = " + num(rep.max_abs_coordinate_m) +
        " m, not under " + num(coordinate_limit) + " m");
  }
  if (!rep.counter_clockwise) {
    rep.problems.push_back("direction: the loop runs clockwise; it must run counter-clockwise");
  }
  if (rep.max_s_error_m > kMaxSErrorM) {
    rep.problems.push_back("s: a waypoint's s is " + num(rep.max_s_error_m, 3) +
                           " m off the straight-line distance from the first waypoint");
  }
}

// The waypoints' normals: to the right of travel, along the line's.
void check_normals(const Map& map, const ReferenceLine& line, TrackReport& rep) {
  bool normals_left = false;
  for (const Waypoint& w : map.waypoints) {
    const RoadFrame f = line.frame(w.s_m);
    const Vec2 n{w.dx, w.dy};
    const double c = dot(right_of(f.tangent), (1.0 / norm(n)) * n);
    if (c < 0.0) normals_left = true;
    rep.max_normal_error_deg = std::max(rep.max_normal_error_deg,
                                        rad_to_deg(std::acos(std::clamp(std::abs(c), 0.0, 1.0))));
  }
  if (normals_left) {
    rep.problems.push_back(
        "normals: (dx, dy) point left of the direction of travel; they must point right, away "
        "from the divider");
  }
  if (rep.max_normal_error_deg > kMaxNormalErrorDeg) {
    rep.problems.push_back("normals: a waypoint's (dx, dy) is " + num(rep.max_normal_error_deg) +
                           " degrees off the road's normal");
  }
}

// Radii on the divider, every lane centre and the outer edge; bends at the road's centre; the
// straight the loop starts with.
void check_curvature(const ReferenceLine& line, const TrackSpec& spec, TrackReport& rep) {
  const double length = line.length_m();
  const double s0 = line.start_s_m();
  std::vector<double> offsets{0.0};
  for (int k = 0; k < spec.road.lane_count; ++k) offsets.push_back(lane_center_d(k, spec.road));
  offsets.push_back(road_width_m(spec.road));
  const double centre_d = 0.5 * road_width_m(spec.road);
  const double bend_k = 1.0 / spec.bend_radius_m;
  const auto samples = static_cast<std::size_t>(std::ceil(length / kCurvatureStepM));
  double max_k = 0.0;
  double max_k_d = 0.0;
  rep.min_radius_s_m = s0;
  rep.start_straight_m = length;
  for (std::size_t i = 0; i < samples; ++i) {
    const double along = length * static_cast<double>(i) / static_cast<double>(samples);
    const double s = s0 + along;
    for (const double d : offsets) {
      const double k = std::abs(line.curvature_at(s, d));
      if (k > max_k) {
        max_k = k;
        max_k_d = d;
        rep.min_radius_s_m = s;
      }
    }
    const double kc = line.curvature_at(s, centre_d);
    if (kc > bend_k) rep.bends_left = true;
    if (kc < -bend_k) rep.bends_right = true;
    if (std::abs(kc) > bend_k && along < rep.start_straight_m) rep.start_straight_m = along;
  }
  rep.min_radius_m = max_k > 0.0 ? 1.0 / max_k : std::numeric_limits<double>::infinity();
  if (rep.min_radius_m < spec.min_radius_m) {
    rep.problems.push_back("min_radius_m: radius " + num(rep.min_radius_m) +
                           " m at s = " + num(rep.min_radius_s_m) + " m, d = " + num(max_k_d) +
                           " m, under " + num(spec.min_radius_m) + " m");
  }
  if (!rep.bends_left) {
    rep.problems.push_back("bends: no left bend (radius under " + num(spec.bend_radius_m, 0) +
                           " m)");
  }
  if (!rep.bends_right) {
    rep.problems.push_back("bends: no right bend (radius under " + num(spec.bend_radius_m, 0) +
                           " m)");
  }
  const double start_needed = required_start_straight_m(spec);
  if (rep.start_straight_m < start_needed) {
    rep.problems.push_back("start_straight_m: the road bends " + num(rep.start_straight_m) +
                           " m after the first waypoint, before " + num(start_needed) + " m");
  }
}

// Clearance between distant stretches (road band around its centre line) and crossings of
// the divider line.
void check_clearance(const ReferenceLine& line, const TrackSpec& spec, TrackReport& rep) {
  const double length = line.length_m();
  const double s0 = line.start_s_m();
  const double centre_d = 0.5 * road_width_m(spec.road);
  const std::size_t m = std::clamp<std::size_t>(
      static_cast<std::size_t>(std::ceil(length / kPairStepM)), 16, kMaxPairSamples);
  const double step = length / static_cast<double>(m);
  const double half_width = centre_d + spec.shoulder_m;
  std::vector<Vec2> divider(m);
  std::vector<Vec2> centre(m);
  double max_segment = 0.0;
  for (std::size_t i = 0; i < m; ++i) {
    const double s = s0 + step * static_cast<double>(i);
    divider[i] = line.frame(s).position;
    centre[i] = line.to_cartesian({s, centre_d});
  }
  for (std::size_t i = 0; i < m; ++i) {
    max_segment = std::max(max_segment, distance(divider[i], divider[(i + 1) % m]));
  }
  const double cross_reach_sq = 4.0 * max_segment * max_segment;
  double min_gap_sq = std::numeric_limits<double>::infinity();
  std::size_t gap_i = 0;
  std::size_t gap_j = 0;
  std::optional<std::pair<std::size_t, std::size_t>> crossing;
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = i + 1; j < m; ++j) {
      const std::size_t apart = std::min(j - i, m - (j - i));
      const double along = step * static_cast<double>(apart);
      const double dc = distance_sq(centre[i], centre[j]);
      const double distinct = kDistinctChordFraction * along;
      if (dc < distinct * distinct && dc < min_gap_sq) {
        min_gap_sq = dc;
        gap_i = i;
        gap_j = j;
      }
      if (!crossing && apart >= 2 && distance_sq(divider[i], divider[j]) <= cross_reach_sq &&
          segments_cross(divider[i], divider[(i + 1) % m], divider[j], divider[(j + 1) % m])) {
        crossing = std::pair{i, j};
      }
    }
  }
  rep.min_clearance_m = std::isfinite(min_gap_sq) ? std::sqrt(min_gap_sq) - 2.0 * half_width
                                                  : std::numeric_limits<double>::infinity();
  if (crossing) {
    rep.self_intersecting = true;
    rep.problems.push_back("self-intersecting: the divider line crosses itself near s = " +
                           num(s0 + step * static_cast<double>(crossing->first)) + " m and s = " +
                           num(s0 + step * static_cast<double>(crossing->second)) + " m");
  }
  if (rep.min_clearance_m < spec.min_clearance_m) {
    rep.problems.push_back(
        "min_clearance_m: the road at s = " + num(s0 + step * static_cast<double>(gap_i)) +
        " m and s = " + num(s0 + step * static_cast<double>(gap_j)) + " m is " +
        num(rep.min_clearance_m) + " m apart edge to edge, under " + num(spec.min_clearance_m) +
        " m");
  }
}

void check_line(const Map& map, const ReferenceLine& line, const TrackSpec& spec,
                TrackReport& rep) {
  check_normals(map, line, rep);
  check_curvature(line, spec, rep);
  check_clearance(line, spec, rep);
}

}  // namespace

TrackReport check_track(const Map& map, const TrackSpec& spec) {
  track_detail::validate_check_spec(spec);
  TrackReport rep;
  rep.length_m = map.loop_length_m;
  if (map.waypoints.size() < 3) {
    rep.problems.push_back("waypoints: a loop needs at least 3, the map has " +
                           std::to_string(map.waypoints.size()));
    return rep;
  }
  check_waypoints(map, spec, rep);
  std::optional<ReferenceLine> line;
  try {
    line.emplace(map);
  } catch (const MapError& e) {
    rep.problems.push_back(std::string("reference line: ") + e.what());
    return rep;
  }
  check_line(map, *line, spec, rep);
  return rep;
}

}  // namespace overtake::core
