#pragma once
// Maps for the simulator's tests, built with the core API.

#include <cmath>
#include <cstdio>
#include <string>

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

}  // namespace overtake::test
