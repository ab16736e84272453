#pragma once
// Scripted scenarios: a start state for the ego, cars placed by hand that keep their lane and
// speed unless an event says otherwise, and timed events (lane changes, braking, speed
// changes). Used by tests and by `--scenario FILE`.

#include <optional>
#include <string>
#include <vector>

namespace overtake::sim {

/// A car placed by the script.
struct ScriptedCar {
  double s_m = 0.0;  ///< absolute s on the map (wrapped)
  int lane = 1;
  double speed_mps = 0.0;  ///< its speed, held until an event changes it
};

/// What an event does.
enum class ScenarioAction {
  change_lane,  ///< move to `lane` (a lane change of the traffic's usual duration)
  brake,        ///< decelerate at `rate_mps2` for `duration_s`, then hold the speed reached
  set_speed,    ///< change speed to `speed_mps` at `rate_mps2` (up or down)
};

/// One timed event.
struct ScenarioEvent {
  double t_s = 0.0;
  int car = 0;  ///< index into Scenario::cars
  ScenarioAction action = ScenarioAction::set_speed;
  int lane = 0;
  double speed_mps = 0.0;
  double rate_mps2 = 0.0;
  double duration_s = 0.0;
};

/// A whole scenario.
struct Scenario {
  std::string name;
  std::optional<double> duration_s;  ///< default run length
  double ego_s_m = 124.8336;
  double ego_d_m = 6.164833;
  double ego_speed_mps = 0.0;         ///< the ego starts at this speed along its lane
  std::vector<ScriptedCar> cars;      ///< replace the random traffic (ids in order)
  std::vector<ScenarioEvent> events;  ///< sorted by time when loaded
};

}  // namespace overtake::sim
