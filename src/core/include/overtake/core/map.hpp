#pragma once
// Highway maps in the original file format: one waypoint per line, `x y s dx dy` (divider
// position in metres, distance along the road in metres, unit normal pointing away from the
// divider). The road is a closed loop. The core parses and formats the text; files are read
// and written by the app (overtake/app/map_file.hpp).

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace overtake::core {

/// One line of a map file.
struct Waypoint {
  double x_m = 0.0;
  double y_m = 0.0;
  double s_m = 0.0;
  double dx = 0.0;  ///< unit normal, away from the divider
  double dy = 0.0;
  friend bool operator==(const Waypoint&, const Waypoint&) = default;
};

/// A validated closed-loop map.
struct Map {
  std::vector<Waypoint> waypoints;
  /// Loop length: the last waypoint's s plus the distance from it back to the first.
  double loop_length_m = 0.0;
  /// Where it came from (a path, or a name such as `builtin:default`), for messages.
  std::string source;
  /// FNV-1a hash of the file's bytes, for provenance.
  std::uint64_t content_hash = 0;
};

/// A map file that cannot be used; the message names the file, the line and the fault.
class MapError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Limits a map must meet: what a highway loop can be, so that nothing downstream (the
/// reference line's samples, the 7-digit wire, the traffic's placement) meets a number it
/// cannot handle.
struct MapRules {
  std::size_t min_waypoints = 4;
  std::size_t max_waypoints = 20000;  ///< (the original map has 181)
  double normal_tolerance = 0.01;     ///< |(dx, dy)| within 1 +- this
  double min_point_spacing_m = 0.01;  ///< two waypoints closer than this are duplicates
  /// Largest |x|, |y| or |s|: 100 km (positions then keep a decimetre or better on the
  /// original's 7-digit wire).
  double max_abs_coordinate_m = 100000.0;
  double min_loop_length_m = 200.0;  ///< the ego starts 125 m along; traffic needs room
  double max_loop_length_m = 200000.0;
  /// Each step of s between consecutive waypoints is within this factor of their straight
  /// distance (s is a distance along the road).
  double max_s_step_ratio = 2.0;
  double s_step_slack_m = 1.0;  ///< ... give or take this much
};

/// Parses and validates map text: numbers, unit normals, increasing s, no duplicate points,
/// the limits of MapRules, and a loop that does not cross itself. `source` names the file in
/// error messages, with the line. Throws MapError on the first fault; never returns a
/// partial map.
[[nodiscard]] Map parse_map(std::string_view text, std::string_view source,
                            const MapRules& rules = {});

/// Map text in the original format, one waypoint per line.
[[nodiscard]] std::string format_map(const std::vector<Waypoint>& waypoints);

}  // namespace overtake::core
