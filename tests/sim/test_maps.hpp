#pragma once
// Maps for the simulator's tests, built with the core API.

#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "overtake/core/map.hpp"
#include "overtake/core/units.hpp"

namespace overtake::test {

/// A circular loop of `radius_m` centred on (radius + 100, radius + 100), waypoints about
/// `spacing_m` apart on the divider, s = cumulative chord length starting at 0. It runs
/// counter-clockwise; the normals point away from the centre, i.e. to the right of travel,
/// as d does. The default is about 6.9 km long with 182 waypoints, like the original's.
[[nodiscard]] inline core::Map circle_map(double radius_m = 1100.0, double spacing_m = 38.0) {
  const int count = static_cast<int>(std::lround(2.0 * core::kPi * radius_m / spacing_m));
  const double step_rad = 2.0 * core::kPi / count;
  const double chord_m = 2.0 * radius_m * std::sin(0.5 * step_rad);
  const double cx = radius_m + 100.0;
  const double cy = radius_m + 100.0;
  std::string text;
  char line[200];
  for (int i = 0; i < count; ++i) {
    const double a = step_rad * i;
    std::snprintf(line, sizeof line, "%.10f %.10f %.10f %.12f %.12f\n", cx + radius_m * std::cos(a),
                  cy + radius_m * std::sin(a), chord_m * i, std::cos(a), std::sin(a));
    text += line;
  }
  return core::parse_map(text, "test:circle");
}

/// A stadium: two straights of `straight_m` joined by half circles of `radius_m`, run
/// counter-clockwise from (0, 0) along +x; waypoints about `spacing_m` apart, normals to the
/// right of travel, s = cumulative chord length.
[[nodiscard]] inline core::Map stadium_map(double straight_m = 1500.0, double radius_m = 300.0,
                                           double spacing_m = 30.0) {
  std::vector<std::array<double, 4>> pts;  // x, y, normal x, normal y
  const auto straight = [&](double x0, double y0, double dir) {
    const int n = static_cast<int>(std::lround(straight_m / spacing_m));
    for (int i = 0; i < n; ++i) pts.push_back({x0 + dir * straight_m * i / n, y0, 0.0, -dir});
  };
  const auto bend = [&](double cx, double cy, double a0) {
    const int n = static_cast<int>(std::lround(core::kPi * radius_m / spacing_m));
    for (int i = 0; i < n; ++i) {
      const double a = a0 + core::kPi * i / n;
      pts.push_back(
          {cx + radius_m * std::cos(a), cy + radius_m * std::sin(a), std::cos(a), std::sin(a)});
    }
  };
  straight(0.0, 0.0, 1.0);
  bend(straight_m, radius_m, -0.5 * core::kPi);
  straight(straight_m, 2.0 * radius_m, -1.0);
  bend(0.0, radius_m, 0.5 * core::kPi);
  std::string text;
  char line[200];
  double s = 0.0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (i > 0) s += std::hypot(pts[i][0] - pts[i - 1][0], pts[i][1] - pts[i - 1][1]);
    std::snprintf(line, sizeof line, "%.6f %.6f %.6f %.9f %.9f\n", pts[i][0], pts[i][1], s,
                  pts[i][2], pts[i][3]);
    text += line;
  }
  return core::parse_map(text, "test:stadium");
}

/// A loop whose first six waypoints are the original map's first six (x, y, s, dx, dy, as
/// the original's highway_map.csv gives them: the stretch where its ego starts), closed by a
/// stadium-like return 1 km north of it.
[[nodiscard]] inline core::Map original_start_map() {
  std::string text =
      "784.6001 1135.571 0 -0.02359831 -0.9997216\n"
      "815.2679 1134.93 30.6744785308838 -0.01099479 -0.9999396\n"
      "844.6398 1134.911 60.0463714599609 -0.002048373 -0.9999979\n"
      "875.0436 1134.808 90.4504146575928 -0.001847863 -0.9999983\n"
      "905.283 1134.799 120.689735412598 0.004131136 -0.9999915\n"
      "934.9677 1135.055 150.375551223755 0.05904382 -0.9982554\n";
  // The return: a half circle of radius 500 m to the left, a straight back west, a half
  // circle down to the first waypoint's line.
  std::vector<std::array<double, 4>> pts;
  const double r = 500.0;
  const core::Vec2 east{964.9677, 1135.055};
  const core::Vec2 west{754.6001, 1135.571};
  for (int i = 0; i <= 8; ++i) pts.push_back({east.x + 30.0 * i, east.y, 0.0, -1.0});
  const double ex = east.x + 240.0;
  for (int i = 1; i < 52; ++i) {
    const double a = -0.5 * core::kPi + core::kPi * i / 52.0;
    pts.push_back({ex + r * std::cos(a), east.y + r + r * std::sin(a), std::cos(a), std::sin(a)});
  }
  const double top = east.y + 2.0 * r;
  const double wx = west.x - 240.0;
  const int back = static_cast<int>(std::lround((ex - wx) / 30.0));
  for (int i = 0; i <= back; ++i) pts.push_back({ex - (ex - wx) * i / back, top, 0.0, 1.0});
  for (int i = 1; i < 52; ++i) {
    const double a = 0.5 * core::kPi + core::kPi * i / 52.0;
    pts.push_back({wx + r * std::cos(a), east.y + r + r * std::sin(a), std::cos(a), std::sin(a)});
  }
  for (int i = 0; i <= 7; ++i) pts.push_back({wx + 30.0 * i, west.y, 0.0, -1.0});
  char line[200];
  double s = 150.375551223755;
  double px = 934.9677;
  double py = 1135.055;
  for (const auto& p : pts) {
    s += std::hypot(p[0] - px, p[1] - py);
    px = p[0];
    py = p[1];
    std::snprintf(line, sizeof line, "%.4f %.4f %.6f %.9f %.9f\n", p[0], p[1], s, p[2], p[3]);
    text += line;
  }
  return core::parse_map(text, "test:original-start");
}

}  // namespace overtake::test
