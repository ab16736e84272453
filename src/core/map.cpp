#include "overtake/core/map.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <optional>
#include <sstream>
#include <utility>

#include "overtake/core/hash.hpp"

namespace overtake::core {
namespace {

constexpr const char* kColumnNames[5] = {"x", "y", "s", "dx", "dy"};

std::string fmt(double v) {
  std::ostringstream os;
  os.precision(10);
  os << v;
  return os.str();
}

[[noreturn]] void fail(std::string_view source, std::size_t line, const std::string& what) {
  std::ostringstream os;
  os << source << ":" << line << ": " << what;
  throw MapError(os.str());
}

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i >= line.size()) break;
    const std::size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    fields.push_back(line.substr(start, i - start));
  }
  return fields;
}

double parse_field(std::string_view field, std::string_view source, std::size_t line, int column) {
  double value = 0.0;
  const char* begin = field.data();
  const char* end = field.data() + field.size();
  if (!field.empty() && field.front() == '+') ++begin;  // tolerate an explicit plus sign
  const auto [ptr, ec] = std::from_chars(begin, end, value);
  if (ec != std::errc() || ptr != end) {
    fail(source, line,
         "column " + std::to_string(column + 1) + " (" + kColumnNames[column] +
             ") is not a number: '" + std::string(field) + "'");
  }
  if (!std::isfinite(value)) {
    fail(source, line,
         "column " + std::to_string(column + 1) + " (" + kColumnNames[column] +
             ") is not finite: '" + std::string(field) + "'");
  }
  return value;
}

bool segments_intersect(const Waypoint& a, const Waypoint& b, const Waypoint& c,
                        const Waypoint& d) {
  const auto orient = [](const Waypoint& p, const Waypoint& q, const Waypoint& r) {
    const double v = (q.x_m - p.x_m) * (r.y_m - p.y_m) - (q.y_m - p.y_m) * (r.x_m - p.x_m);
    return (v > 0.0) - (v < 0.0);
  };
  const int o1 = orient(a, b, c);
  const int o2 = orient(a, b, d);
  const int o3 = orient(c, d, a);
  const int o4 = orient(c, d, b);
  if (o1 != o2 && o3 != o4) return true;
  // Collinear and overlapping (duplicate points are refused before, so this is a fold back).
  const auto on = [](const Waypoint& p, const Waypoint& q, const Waypoint& r) {
    return std::min(p.x_m, q.x_m) <= r.x_m && r.x_m <= std::max(p.x_m, q.x_m) &&
           std::min(p.y_m, q.y_m) <= r.y_m && r.y_m <= std::max(p.y_m, q.y_m);
  };
  return (o1 == 0 && on(a, b, c)) || (o2 == 0 && on(a, b, d)) || (o3 == 0 && on(c, d, a)) ||
         (o4 == 0 && on(c, d, b));
}

/// Two segments of the closed divider line (i to i+1, j to j+1, i < j) that cross, other than
/// neighbours meeting at their shared waypoint. A sweep along x: each segment is compared
/// only with the segments whose x ranges overlap its own.
std::optional<std::pair<std::size_t, std::size_t>> find_crossing(const std::vector<Waypoint>& w) {
  const std::size_t n = w.size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  const auto lo = [&](std::size_t i) { return std::min(w[i].x_m, w[(i + 1) % n].x_m); };
  const auto hi = [&](std::size_t i) { return std::max(w[i].x_m, w[(i + 1) % n].x_m); };
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return lo(a) < lo(b); });
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = order[k];
    for (std::size_t m = k + 1; m < n && lo(order[m]) <= hi(i); ++m) {
      const std::size_t j = order[m];
      const std::size_t a = std::min(i, j);
      const std::size_t b = std::max(i, j);
      if (b == a + 1 || (a == 0 && b == n - 1)) continue;  // neighbours share a waypoint
      if (segments_intersect(w[a], w[a + 1], w[b], w[(b + 1) % n])) return std::make_pair(a, b);
    }
  }
  return std::nullopt;
}

// One waypoint's checks, against the rules and the waypoint before it (line_of: the file line
// of each waypoint so far).
void check_waypoint(const Waypoint& wp, const Map& map, const std::vector<std::size_t>& line_of,
                    std::string_view source, std::size_t line_no, const MapRules& rules) {
  const double v[3] = {wp.x_m, wp.y_m, wp.s_m};
  const double normal_len = std::hypot(wp.dx, wp.dy);
  if (std::abs(normal_len - 1.0) > rules.normal_tolerance) {
    fail(source, line_no,
         "normal (dx, dy) = (" + fmt(wp.dx) + ", " + fmt(wp.dy) + ") has length " +
             fmt(normal_len) + "; it must be a unit vector (within " +
             fmt(rules.normal_tolerance * 100.0) + "%)");
  }
  for (int c : {0, 1, 2}) {
    if (std::abs(v[c]) > rules.max_abs_coordinate_m) {
      fail(source, line_no,
           std::string(kColumnNames[c]) + " = " + fmt(v[c]) +
               " is out of range: a map's x, y and s must be within +-" +
               fmt(rules.max_abs_coordinate_m) + " m");
    }
  }
  if (map.waypoints.size() >= rules.max_waypoints) {
    fail(source, line_no,
         "too many waypoints: a map may have at most " + std::to_string(rules.max_waypoints));
  }
  if (!map.waypoints.empty() && !(wp.s_m > map.waypoints.back().s_m)) {
    fail(source, line_no,
         "s = " + fmt(wp.s_m) + " does not increase (line " + std::to_string(line_of.back()) +
             " has s = " + fmt(map.waypoints.back().s_m) + ")");
  }
  if (!map.waypoints.empty()) {
    const Waypoint& prev = map.waypoints.back();
    const double chord = std::hypot(wp.x_m - prev.x_m, wp.y_m - prev.y_m);
    const double step = wp.s_m - prev.s_m;
    if (step > rules.max_s_step_ratio * chord + rules.s_step_slack_m ||
        step < chord / rules.max_s_step_ratio - rules.s_step_slack_m) {
      fail(source, line_no,
           "s grows by " + fmt(step) + " m from line " + std::to_string(line_of.back()) +
               ", but the waypoints are " + fmt(chord) +
               " m apart; s is the distance along the road");
    }
  }
}

// Duplicate points: sort indices by x and compare neighbours within the tolerance.
void check_duplicates(const Map& map, const std::vector<std::size_t>& line_of,
                      std::string_view source, const MapRules& rules) {
  std::vector<std::size_t> order(map.waypoints.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return map.waypoints[a].x_m < map.waypoints[b].x_m;
  });
  const double tol = rules.min_point_spacing_m;
  for (std::size_t i = 0; i < order.size(); ++i) {
    const Waypoint& a = map.waypoints[order[i]];
    for (std::size_t j = i + 1; j < order.size(); ++j) {
      const Waypoint& b = map.waypoints[order[j]];
      if (b.x_m - a.x_m > tol) break;
      if (std::hypot(a.x_m - b.x_m, a.y_m - b.y_m) < tol) {
        const std::size_t first = std::min(line_of[order[i]], line_of[order[j]]);
        const std::size_t second = std::max(line_of[order[i]], line_of[order[j]]);
        fail(source, second,
             "waypoint (" + fmt(b.x_m) + ", " + fmt(b.y_m) + ") duplicates the point on line " +
                 std::to_string(first));
      }
    }
  }
}

// The loop's length, and that the road never crosses itself.
void check_loop(Map& map, const std::vector<std::size_t>& line_of, std::string_view source,
                const MapRules& rules) {
  const Waypoint& first = map.waypoints.front();
  const Waypoint& last = map.waypoints.back();
  map.loop_length_m = last.s_m - first.s_m + std::hypot(first.x_m - last.x_m, first.y_m - last.y_m);
  if (!(map.loop_length_m >= rules.min_loop_length_m) ||
      !(map.loop_length_m <= rules.max_loop_length_m)) {
    throw MapError(std::string(source) + ": the loop is " + fmt(map.loop_length_m) +
                   " m long; a map's loop must be " + fmt(rules.min_loop_length_m) + " to " +
                   fmt(rules.max_loop_length_m) + " m");
  }
  if (const auto crossing = find_crossing(map.waypoints)) {
    const std::size_t n = map.waypoints.size();
    const auto seg = [&](std::size_t i) {
      return "lines " + std::to_string(line_of[i]) + "-" + std::to_string(line_of[(i + 1) % n]);
    };
    throw MapError(std::string(source) + ": the road crosses itself: the divider between " +
                   seg(crossing->first) + " crosses it between " + seg(crossing->second));
  }
}

}  // namespace

Map parse_map(std::string_view text, std::string_view source, const MapRules& rules) {
  Map map;
  map.source = std::string(source);
  map.content_hash = fnv1a64(text);
  std::vector<std::size_t> line_of;  // file line of each waypoint

  std::size_t line_no = 0;
  std::size_t pos = 0;
  while (pos < text.size()) {
    std::size_t eol = text.find('\n', pos);
    if (eol == std::string_view::npos) eol = text.size();
    std::string_view line = text.substr(pos, eol - pos);
    pos = eol + 1;
    ++line_no;
    const auto fields = split_fields(line);
    if (fields.empty() || fields.front().front() == '#') continue;
    if (fields.size() != 5) {
      fail(source, line_no,
           "expected 5 numbers (x y s dx dy), found " + std::to_string(fields.size()) + " field" +
               (fields.size() == 1 ? "" : "s"));
    }
    double v[5];
    for (int c = 0; c < 5; ++c) v[c] = parse_field(fields[c], source, line_no, c);
    const Waypoint wp{v[0], v[1], v[2], v[3], v[4]};
    check_waypoint(wp, map, line_of, source, line_no, rules);
    map.waypoints.push_back(wp);
    line_of.push_back(line_no);
  }

  if (map.waypoints.empty()) {
    throw MapError(std::string(source) + ": empty map file (no waypoints)");
  }
  if (map.waypoints.size() < rules.min_waypoints) {
    throw MapError(std::string(source) + ": only " + std::to_string(map.waypoints.size()) +
                   " waypoint" + (map.waypoints.size() == 1 ? "" : "s") +
                   "; a map needs at least " + std::to_string(rules.min_waypoints));
  }

  check_duplicates(map, line_of, source, rules);
  check_loop(map, line_of, source, rules);
  return map;
}

std::string format_map(const std::vector<Waypoint>& waypoints) {
  std::string out;
  char line[160];
  for (const Waypoint& w : waypoints) {
    std::snprintf(line, sizeof line, "%.4f %.4f %.4f %.7f %.7f\n", w.x_m, w.y_m, w.s_m, w.dx, w.dy);
    out += line;
  }
  return out;
}

}  // namespace overtake::core
