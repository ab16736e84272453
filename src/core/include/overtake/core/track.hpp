#pragma once
// Generated highway loops: a deterministic generator of closed, counter-clockwise loop maps in
// the original file format, and a checker that measures any map against the same spec.
//
// Shape model (generate_track): a rounded rectangle drawn as a curvature profile. Four corners
// of +90 degrees each (sometimes split in two), inward dents (left, right, left: the right
// bends) and gentle lane-shifting jogs on the sides, every bend entered and left through
// clothoids (curvature linear in s). The straights of each side take up the rest of the length
// so that the loop closes exactly; the split between the two axes makes the outline as square
// as possible, centred on the origin. A shape too big for the box is tightened step by step
// (corners towards the smallest radius, dents deeper). Everything is drawn from `core::Rng`
// seeded from the spec's seed; a shape that still does not fit, or fails check_track, is
// drawn again from a derived seed.

#include <cstdint>
#include <string>
#include <vector>

#include "overtake/core/map.hpp"
#include "overtake/core/road.hpp"

namespace overtake::core {

/// What to generate, and what check_track measures a map against (metres throughout).
struct TrackSpec {
  /// Seed of the shape: the same spec always gives the same map text.
  std::uint64_t seed = 1;
  /// Loop length; a generated loop is within 2% of it (in practice within centimetres).
  double length_m = 7000.0;
  /// No radius under this on the divider, any lane centre or the outer edge of the road.
  double min_radius_m = 150.0;
  /// Smallest straight-line distance between consecutive waypoints.
  double min_spacing_m = 20.0;
  /// Largest straight-line distance between consecutive waypoints.
  double max_spacing_m = 90.0;
  /// Spacing of the waypoints on straights (generated maps; bends get closer ones), kept
  /// within the limits above.
  double straight_spacing_m = 45.0;
  /// Smallest gap, road edge to road edge, between two stretches far apart along the road.
  double min_clearance_m = 40.0;
  /// Width beyond the lanes on either side that counts as road for clearance.
  double shoulder_m = 1.0;
  /// Largest |x| or |y| of a waypoint (generated roads keep their outer edge inside it too).
  /// 0: 1000 m for loops up to 7500 m (positions then keep 0.1 mm on the 7-digit wire),
  /// growing in proportion to the length above that.
  double max_abs_coordinate_m = 0.0;
  /// Straight road wanted from the first waypoint on (the ego starts at s = 125 m); capped
  /// at a tenth of the loop.
  double start_straight_m = 300.0;
  /// A stretch of road centre tighter than this radius counts as a bend.
  double bend_radius_m = 2000.0;
  /// Lane layout.
  RoadParams road;
};

/// The result of checking a map against a spec. Radii are unsigned; s values are the map's.
struct TrackReport {
  /// What the map fails, one line each naming the spec field or property; empty: it passes.
  std::vector<std::string> problems;
  /// Loop length (the map's last s plus the distance back to the first waypoint).
  double length_m = 0.0;
  /// Smallest radius on the divider, the lane centres and the outer edge.
  double min_radius_m = 0.0;
  /// Where that smallest radius is.
  double min_radius_s_m = 0.0;
  /// Smallest straight-line distance between consecutive waypoints (the last to the first too).
  double min_spacing_m = 0.0;
  /// Largest straight-line distance between consecutive waypoints.
  double max_spacing_m = 0.0;
  /// Mean distance between consecutive waypoints.
  double mean_spacing_m = 0.0;
  /// Largest |x| or |y| of a waypoint.
  double max_abs_coordinate_m = 0.0;
  /// Smallest edge-to-edge gap between two stretches far apart along the road (infinity
  /// when the road never comes back near itself).
  double min_clearance_m = 0.0;
  /// Length of straight road centre from the first waypoint on.
  double start_straight_m = 0.0;
  /// Largest angle between a waypoint's normal and the reference line's (degrees).
  double max_normal_error_deg = 0.0;
  /// Largest difference between a waypoint's s and the straight-line distance summed from
  /// the first waypoint.
  double max_s_error_m = 0.0;
  /// The road centre bends left (radius under bend_radius_m) somewhere.
  bool bends_left = false;
  /// The road centre bends right somewhere.
  bool bends_right = false;
  /// The divider line crosses itself.
  bool self_intersecting = false;
  /// The waypoints run counter-clockwise (divider on the inside).
  bool counter_clockwise = false;
  /// True when there are no problems.
  [[nodiscard]] bool ok() const { return problems.empty(); }
};

/// Throws std::invalid_argument, naming the field, when no track can be generated for `spec`:
/// a value that is not finite or out of range, a length under 1000 m or too short for bends
/// of min_radius_m, spacing limits out of order or too wide for such bends, a box too small.
void validate_track_spec(const TrackSpec& spec);

/// The largest |x| or |y| allowed for `spec` (its max_abs_coordinate_m, or the default).
[[nodiscard]] double max_abs_coordinate_for(const TrackSpec& spec);

/// Generates the loop's waypoints, already rounded as format_map prints them (so parsing
/// format_map's text gives them back exactly). The map passes check_track. Deterministic:
/// same spec, same waypoints. Throws std::invalid_argument for an impossible spec and
/// std::runtime_error when no attempt passes the check.
[[nodiscard]] std::vector<Waypoint> generate_track(const TrackSpec& spec);

/// A generated track as written (the map file's text), read back as a map is loaded, and its
/// check.
struct GeneratedTrack {
  std::string text;
  Map map;
  TrackReport check;
};

/// generate_track, written out by format_map and parsed back as `name`, then checked once more
/// against `spec` as a user's map is: std::runtime_error listing the problems when the map
/// read back fails (generate_track's own exceptions otherwise).
[[nodiscard]] GeneratedTrack generate_checked_track(const TrackSpec& spec, const std::string& name);

/// Checks a map as users load it against `spec`: length, radii on every lane, spacing, bends
/// both ways, self-intersection, clearance, coordinates, direction, normals, s values and the
/// straight start. Never throws for a bad map (a map whose reference line cannot be built is
/// reported as a problem); throws std::invalid_argument for a malformed spec.
[[nodiscard]] TrackReport check_track(const Map& map, const TrackSpec& spec);

}  // namespace overtake::core
