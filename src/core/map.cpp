#include "overtake/core/map.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <charconv>
#include <cmath>
#include <fstream>
#include <numeric>
#include <sstream>

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
           "expected 5 numbers (x y s dx dy), found " + std::to_string(fields.size()) +
               " field" + (fields.size() == 1 ? "" : "s"));
    }
    double v[5];
    for (int c = 0; c < 5; ++c) v[c] = parse_field(fields[c], source, line_no, c);
    const Waypoint wp{v[0], v[1], v[2], v[3], v[4]};
    const double normal_len = std::hypot(wp.dx, wp.dy);
    if (std::abs(normal_len - 1.0) > rules.normal_tolerance) {
      fail(source, line_no,
           "normal (dx, dy) = (" + fmt(wp.dx) + ", " + fmt(wp.dy) + ") has length " +
               fmt(normal_len) + "; it must be a unit vector (within " +
               fmt(rules.normal_tolerance * 100.0) + "%)");
    }
    if (!map.waypoints.empty() && !(wp.s_m > map.waypoints.back().s_m)) {
      fail(source, line_no,
           "s = " + fmt(wp.s_m) + " does not increase (line " + std::to_string(line_of.back()) +
               " has s = " + fmt(map.waypoints.back().s_m) + ")");
    }
    map.waypoints.push_back(wp);
    line_of.push_back(line_no);
  }

  if (map.waypoints.empty()) {
    throw MapError(std::string(source) + ": empty map file (no waypoints)");
  }
  if (map.waypoints.size() < rules.min_waypoints) {
    throw MapError(std::string(source) + ": only " + std::to_string(map.waypoints.size()) +
                   " waypoint" + (map.waypoints.size() == 1 ? "" : "s") + "; a map needs at least " +
                   std::to_string(rules.min_waypoints));
  }

  // Duplicate points: sort indices by x and compare neighbours within the tolerance.
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

  const Waypoint& first = map.waypoints.front();
  const Waypoint& last = map.waypoints.back();
  map.loop_length_m = last.s_m - first.s_m + std::hypot(first.x_m - last.x_m, first.y_m - last.y_m);
  return map;
}

Map load_map_file(const std::filesystem::path& path, const MapRules& rules) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MapError(path.string() + ": cannot open map file");
  std::ostringstream buf;
  buf << in.rdbuf();
  if (in.bad()) throw MapError(path.string() + ": error while reading map file");
  return parse_map(buf.str(), path.string(), rules);
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
