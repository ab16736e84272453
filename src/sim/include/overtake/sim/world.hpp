#pragma once
// The headless world: fixed steps of the ego (perfect controller on its path queue) and the
// traffic, deterministic from a seed. It judges nothing: the run's scorecard (scorecard.hpp)
// watches it step by step.

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "overtake/core/map.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/core/waypoint_frenet.hpp"
#include "overtake/sim/params.hpp"
#include "overtake/sim/referee.hpp"
#include "overtake/sim/scenario.hpp"
#include "overtake/sim/traffic.hpp"

namespace overtake::sim {

/// The ego's exact state.
struct EgoState {
  core::Vec2 position;
  double yaw_rad = 0.0;
  double speed_mps = 0.0;
  core::FrenetPoint frenet;      ///< on the reference line
  core::FrenetPoint map_frenet;  ///< as the original measures and reports it (waypoint chords)
  std::size_t closest_waypoint = 0;
};

/// One simulated world. The map and line must outlive it.
class World {
 public:
  /// `open_road`: faithful traffic's table of this line, road and params, shared by worlds of
  /// one map (build_open_road_table; null: built here). The same world either way.
  World(const core::Map& map, const core::ReferenceLine& line, const WorldParams& params,
        TrafficProfile profile, std::uint64_t seed,
        std::shared_ptr<const OpenRoadTable> open_road = nullptr);
  /// A scripted world: the scenario's start state, its cars instead of random traffic, and
  /// its events at their times. An ego starting at speed has one second of path queued
  /// along its lane at that speed.
  /// The ego starts at rest at the chord point of (ego.start_s_m, ego.start_d_m), rounded to
  /// whole centimetres, facing the chord's heading rounded to a whole degree.
  World(const core::Map& map, const core::ReferenceLine& line, const WorldParams& params,
        const Scenario& scenario);

  /// What the planner is told now (rounded as on the wire when the params say so).
  [[nodiscard]] core::Telemetry telemetry() const;
  /// Takes a planner's path: rounds it as the original reads it, then trims it by the
  /// original's rule (path_queue.hpp) and makes the rest the ego's queue.
  void apply_path(std::vector<core::Vec2> path);
  /// Advances one step: traffic decides and moves, the ego moves onto its next point (with
  /// one point left it stays and the point is dropped), bodies that touch are pushed apart.
  void step();
  /// The ego after the last step, as the referee sees it (with the car that touched it in
  /// that step, if any).
  [[nodiscard]] EgoFrame ego_frame() const;

  [[nodiscard]] double time_s() const { return static_cast<double>(steps_) * params_.step_s; }
  [[nodiscard]] long steps() const { return steps_; }
  [[nodiscard]] const EgoState& ego() const { return ego_; }
  [[nodiscard]] const std::deque<core::Vec2>& queue() const { return queue_; }
  [[nodiscard]] const Traffic& traffic() const { return traffic_; }
  [[nodiscard]] Traffic& traffic_for_testing() { return traffic_; }
  [[nodiscard]] const WorldParams& params() const { return params_; }
  [[nodiscard]] const core::ReferenceLine& line() const { return line_; }
  /// The map's waypoint chords, on which the original measures s and d.
  [[nodiscard]] const core::WaypointFrenet& chords() const { return chords_; }
  /// The ego's footprint in map axes.
  [[nodiscard]] core::OrientedBox ego_footprint() const;

  /// Writes or restores the world's whole state: the clock, the ego and its queue, the
  /// traffic model's state, the pending contact and the scenario's next event. Restoring
  /// needs a world made the same way (map, params, profile or scenario); the seed does not
  /// matter, the random streams are part of the state.
  void archive(core::StateArchive& ar);
  /// From now on the cars follow recorded bodies (Traffic::set_replayed).
  void replay_traffic(std::vector<std::vector<TrafficCar>> steps);
  /// Keeps, at each step, the cars as traffic moved them, before contacts pushed them apart
  /// (moved_cars): what replayed traffic must follow for its contacts to happen as they did.
  void keep_moved_cars(bool keep) { keep_moved_ = keep; }
  [[nodiscard]] const std::vector<TrafficCar>& moved_cars() const { return moved_; }

 private:
  [[nodiscard]] EgoView ego_view() const;
  void place_ego(core::FrenetPoint start);
  void update_ego_frenet();

  const core::ReferenceLine& line_;
  core::WaypointFrenet chords_;
  WorldParams params_;
  EgoState ego_;
  std::deque<core::Vec2> queue_;
  Traffic traffic_;
  std::optional<int> contact_;  // a car that touched the ego in the last step
  long steps_ = 0;
  std::vector<ScenarioEvent> events_;  // pending, in time order
  std::size_t next_event_ = 0;
  bool keep_moved_ = false;
  std::vector<TrafficCar> moved_;  // the cars before contacts, when kept
};

}  // namespace overtake::sim
