#pragma once
// Scenarios: scripted (a start state for the ego, cars placed by hand that keep their lane and
// speed unless an event says otherwise, and timed events: lane changes, braking, speed
// changes) or cut from a recorded run (its world checkpointed at the start, its traffic
// reactive or replayed); and what a scenario expects of the planner. Used by tests,
// `--scenario FILE` and `bench --scenarios DIR`.

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

/// A scenario cut from a recorded run (`overtake cut`).
struct ScenarioCut {
  std::string checkpoint;   ///< the world at the start (sim::encode_checkpoint's bytes)
  bool replayed = false;    ///< traffic follows `recorded` instead of driving by its rules
  std::string recorded;     ///< replayed: sim::encode_recorded_traffic's bytes
  double start_s = 0.0;     ///< the run's time at the start (the scenario keeps its clock)
  double at_s = 0.0;        ///< the moment it was cut around
  double lead_in_s = 0.0;   ///< the first seconds are for the planner to settle (not judged)
  std::string map;          ///< the map it needs (a path as written in the file; "" built-in)
  std::string from_replay;  ///< the replay it was cut from, as the cut named it
  std::string incident;     ///< the incident near the moment, as the cut named it
  /// A cut of a run of a planner from outside: what it was told and answered before the start
  /// (sim::encode_warm_up's bytes; empty when the scenario has none), played to such a planner
  /// before the scenario starts (docs/scenarios.md).
  std::string warm_up;
  double warm_up_start_s = 0.0;  ///< the run's time at the warm-up's first cycle
  long warm_up_cycles = 0;       ///< as the file says (checked against the bytes)
  std::string from_policy;       ///< the planner of the run it was cut from
};

/// What a scenario expects of a planner, over the judged part (after the lead-in); unset
/// limits are not checked. `bench --scenarios` turns these into pass or fail.
struct ScenarioExpect {
  std::optional<int> max_at_fault_collisions;
  std::optional<int> max_collisions;
  std::optional<int> max_incidents;  ///< of every type
  /// Reaches this lane (its d within the lane) ...
  std::optional<int> reach_lane;
  /// ... within this many seconds of the scenario's start.
  double reach_lane_by_s = 0.0;
  std::optional<double> min_distance_m;  ///< drives at least this far
  /// True unless a limit is set (a scenario without expectations expects no at-fault
  /// collision).
  [[nodiscard]] bool any() const {
    return max_at_fault_collisions || max_collisions || max_incidents || reach_lane ||
           min_distance_m;
  }
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
  std::string description;
  std::optional<ScenarioCut> cut;  ///< set for a scenario cut from a run (no ego, cars, events)
  ScenarioExpect expect;
};

}  // namespace overtake::sim
