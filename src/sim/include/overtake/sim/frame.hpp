#pragma once
// One step of a run as those who watch it see it (a replay recording, a live view): the ego,
// every car, and the scorecard's running figures. A value, so that watchers need neither the
// world nor the referee.

#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/sim/referee.hpp"
#include "overtake/sim/safety.hpp"

namespace overtake::sim {

/// A traffic car's body in a frame.
struct CarPose {
  int id = 0;
  core::Vec2 position;   ///< centre of its body (m)
  double yaw_rad = 0.0;  ///< where its body points
  double speed_mps = 0.0;
  friend bool operator==(const CarPose&, const CarPose&) = default;
};

/// The state after one step (step 0: before the first).
struct Frame {
  long step = 0;  ///< t = step * step_s
  core::Vec2 position;
  double yaw_rad = 0.0;
  double speed_mps = 0.0;
  double s_m = 0.0;  ///< on the reference line
  double d_m = 0.0;
  StrictFigures strict;  ///< the referee's strict figures at this step
  SafetyFigures safety;  ///< TTC and headway at this step (infinity: none)
  double distance_m = 0.0;
  double incident_free_m = 0.0;
  double best_incident_free_m = 0.0;
  std::vector<CarPose> cars;
};

}  // namespace overtake::sim
