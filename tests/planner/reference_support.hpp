#pragma once
// Helpers for the reference planner's tests: a circular test road, cars and egos placed in
// Frenet coordinates, and the sanitizer switch that scales long runs down.

#include <cstdlib>
#include <string>

#include "overtake/core/reference_line.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/planner/reference/prediction.hpp"
#include "sim/test_maps.hpp"

namespace overtake::planner::reference::test {

/// True under the AddressSanitizer preset (runs are scaled down there).
[[nodiscard]] inline bool sanitized() {
  const char* v = std::getenv("OVERTAKE_SANITIZED");
  return v != nullptr && std::string(v) == "1";
}

/// A car observed at (s, d) moving along its lane at `speed_mps` and sideways at `d_dot_mps`.
[[nodiscard]] inline core::CarObservation observed_car(const core::ReferenceLine& line, int id,
                                                       double s_m, double d_m, double speed_mps,
                                                       double d_dot_mps = 0.0) {
  const core::FrenetPoint p{line.wrap_s(s_m), d_m};
  return {id, line.to_cartesian(p), line.velocity(p, line.s_rate(p, speed_mps), d_dot_mps), p.s_m,
          p.d_m};
}

/// A prediction of a car at (s, d) keeping its lane at `speed_mps` (s in metres ~ s units on
/// the large test circle).
[[nodiscard]] inline CarPrediction lane_car(int id, double s_m, double d_m, double speed_mps,
                                            double d_dot_mps = 0.0, double accel_mps2 = 0.0) {
  return predict_car(id, s_m, speed_mps, accel_mps2, speed_mps, d_m, d_dot_mps,
                     ReferencePredictionParams{}, core::RoadParams{});
}

/// The ego at s in the middle of `lane`, at rest or moving along the road, nothing queued.
[[nodiscard]] inline core::Telemetry ego_at(const core::ReferenceLine& line, double s_m, double d_m,
                                            double speed_mps) {
  core::Telemetry t;
  const core::RoadFrame f = line.frame(s_m);
  t.ego = {line.to_cartesian({s_m, d_m}), f.heading_rad, speed_mps, line.wrap_s(s_m), d_m};
  return t;
}

}  // namespace overtake::planner::reference::test
