#pragma once
// (ours) Calm traffic: IDM following and MOBIL lane changes on the reference line, cars kept
// in Frenet coordinates with a small sinusoidal wander and minimum-jerk lane changes; also
// the cars of scripted scenarios, which keep their lane and speed until an event.

#include <cstdint>
#include <optional>
#include <vector>

#include "overtake/core/random.hpp"
#include "overtake/sim/traffic.hpp"

namespace overtake::sim {

/// A lane change under way.
struct LaneManoeuvre {
  int from_lane = 0;
  int to_lane = 0;
  double from_d_m = 0.0;   ///< lateral position when it started
  double elapsed_s = 0.0;  ///< time into it (its clock runs slower when the car crawls)
  double duration_s = 0.0;
};

/// One calm (or scripted) car, in Frenet coordinates of the reference line.
struct CalmCar {
  double s_m = 0.0;
  double d_m = 0.0;
  double speed_mps = 0.0;   ///< along its lane
  double accel_mps2 = 0.0;  ///< along its lane, over the last step
  double d_rate_mps = 0.0;  ///< lateral speed (dd/dt)
  double cruise_mps = 0.0;  ///< the speed it wants to drive
  int lane = 1;             ///< lane it keeps, or moves to during a lane change
  std::optional<LaneManoeuvre> manoeuvre;
  double since_lane_change_s = 1e9;
  bool held_up = false;          ///< reacting to a vehicle ahead (this step)
  double since_held_up_s = 1e9;  ///< time since it last reacted to a vehicle ahead
  // wander
  double wander_phase_rad = 0.0;
  double wander_omega_rps = 0.0;
  double lane_offset_m = 0.0;  ///< current wander offset from the lane centre
  /// Set for a car of a scripted scenario: it keeps its lane and speed until an event.
  struct Script {
    double target_speed_mps = 0.0;
    double rate_mps2 = 3.0;     ///< how fast it reaches the target speed
    double brake_mps2 = 0.0;    ///< braking under way ...
    double brake_left_s = 0.0;  ///< ... for this much longer
    int change_to_lane = -1;    ///< a lane change to start at the next step
  };
  std::optional<Script> script;
  bool far = false;  ///< farther than the despawn distance; waiting to be placed again
  core::Rng rng;     ///< this car's own random stream
};

class CalmTraffic final : public TrafficModel {
 public:
  CalmTraffic(const core::Map& map, const core::ReferenceLine& line,
              const core::WaypointFrenet& chords, const TrafficParams& params,
              const core::RoadParams& road, const core::CarFootprint& car, std::uint64_t seed);

  /// Places every car before the first step (no car behind the ego in the ego's lane).
  void start(const EgoView& ego) override;
  void step(const EgoView& ego, double dt_s) override;
  [[nodiscard]] const std::vector<TrafficCar>& cars() const override { return bodies_; }
  void on_contact(std::size_t i, core::Vec2 shift_m, double speed_mps,
                  const core::OrientedBox& other) override;
  void archive(core::StateArchive& ar) override;

  [[nodiscard]] const std::vector<CalmCar>& calm_cars() const { return cars_; }
  /// Testing hook: replaces the cars (ids are reassigned in order).
  void set_cars(std::vector<CalmCar> cars);
  /// The scenario's cars, scripted.
  void set_script(const std::vector<ScriptedCar>& cars);
  void apply_event(const ScenarioEvent& event);

 private:
  void publish();

  const core::Map& map_;
  const core::ReferenceLine& line_;
  const core::WaypointFrenet& chords_;
  TrafficParams params_;
  core::RoadParams road_;
  core::CarFootprint car_;
  core::Rng spawn_rng_;
  int frames_to_batch_ = 0;
  bool scripted_ = false;
  std::vector<CalmCar> cars_;
  std::vector<TrafficCar> bodies_;
  // Per-step scratch, reused so that step() does not allocate.
  struct Vehicle {     // a car or the ego as the others see it this step
    double s_m = 0.0;  // wrapped
    double speed_mps = 0.0;
    double accel_mps2 = 0.0;    // over the last step
    unsigned follow_lanes = 0;  // lanes it occupies for following (bit per lane)
    unsigned now_lanes = 0;     // lanes it counts in for lane-clear checks
    int car = -1;               // index into cars_, -1 for the ego
  };
  struct Decision {           // what a car does this step, from the previous frame
    double accel_mps2 = 0.0;  // applied
    double idm_mps2 = 0.0;    // plain IDM, unclamped, for MOBIL
    double new_speed_mps = 0.0;
    int leader = -1;            // index into vehicles_, -1 when none
    double leader_gap_m = 0.0;  // centre to centre along s
    int change_to_lane = -1;    // start a lane change into this lane, -1 for none
  };
  std::vector<Vehicle> vehicles_;
  std::vector<Decision> decisions_;
  std::vector<core::Vec2> positions_;
  double ego_prev_speed_mps_ = -1.0;  // the ego's speed at the previous step (-1: none yet)
  // Cache (rebuilt, not saved): the line's metres per unit of s at each car's s and d as
  // publish() last asked for them (by their bits); a car's next move asks at the same point
  // unless something moved it in between.
  struct LaneScale {
    std::uint64_t s_bits = 0;
    std::uint64_t d_bits = 0;
    double metres_per_s = 0.0;
    bool valid = false;
  };
  std::vector<LaneScale> lane_scales_;
  friend struct CalmImpl;
};

}  // namespace overtake::sim
