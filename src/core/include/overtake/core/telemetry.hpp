#pragma once
// The plain structs through which the simulator and the planners meet: what a planner is
// told each cycle, and what it answers. SI units; the protocol converts at its edge.

#include <vector>

#include "overtake/core/geometry.hpp"

namespace overtake::core {

/// The ego car as the simulator reports it.
struct EgoObservation {
  Vec2 position;
  double yaw_rad = 0.0;    ///< heading, counter-clockwise from +x, in [0, 2*pi)
  double speed_mps = 0.0;  ///< distance moved in the last step over the step time
  double s_m = 0.0;
  double d_m = 0.0;
  friend bool operator==(const EgoObservation&, const EgoObservation&) = default;
};

/// One other car, as reported by sensor fusion: `[id, x, y, vx, vy, s, d]`.
struct CarObservation {
  int id = 0;
  Vec2 position;
  Vec2 velocity_mps;  ///< in map axes
  double s_m = 0.0;
  double d_m = 0.0;
  friend bool operator==(const CarObservation&, const CarObservation&) = default;
};

/// A sensor-fusion row `[id, x, y, vx, vy, s, d]` as a CarObservation (the id already checked
/// to be a whole number).
[[nodiscard]] inline CarObservation car_from_row(const double (&row)[7]) {
  CarObservation c;
  c.id = static_cast<int>(row[0]);
  c.position = {row[1], row[2]};
  c.velocity_mps = {row[3], row[4]};
  c.s_m = row[5];
  c.d_m = row[6];
  return c;
}

/// Everything a planner is told at one cycle.
struct Telemetry {
  EgoObservation ego;
  std::vector<Vec2> previous_path;  ///< points still queued, in driving order
  FrenetPoint end_path;             ///< Frenet of the last queued point; 0, 0 when none
  std::vector<CarObservation> cars;
  friend bool operator==(const Telemetry&, const Telemetry&) = default;
};

/// Rounds every number of a telemetry as the original's wire format does (see
/// wire_number.hpp); yaw and speed are rounded in degrees and mph, as they are sent.
[[nodiscard]] Telemetry round_like_wire(Telemetry t);

/// Rounds path points as the original does when it reads a planner's reply.
[[nodiscard]] std::vector<Vec2> round_like_wire(std::vector<Vec2> path);

}  // namespace overtake::core
