#pragma once
// The twelve other cars: placement and re-placement around the ego, lane keeping with a
// small wander, following, and lane changes, in one of two profiles.

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/map.hpp"
#include "overtake/core/random.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/sim/params.hpp"
#include "overtake/sim/scenario.hpp"

namespace overtake::sim {

/// How traffic behaves.
enum class TrafficProfile {
  faithful,  ///< the original simulator's rules (bang-bang following, gap-held lane changes)
  calm,      ///< (ours) IDM following with MOBIL lane changes
};

[[nodiscard]] std::optional<TrafficProfile> parse_traffic_profile(std::string_view name);
[[nodiscard]] std::string_view to_string(TrafficProfile p);

/// The ego as traffic sees it (for following, lane-clear checks and placement).
struct EgoView {
  double s_m = 0.0;
  double d_m = 0.0;
  double speed_mps = 0.0;
};

/// A lane change under way.
struct LaneManoeuvre {
  int from_lane = 0;
  int to_lane = 0;
  double from_d_m = 0.0;  ///< lateral position when it started
  double elapsed_s = 0.0;  ///< time into it (its clock runs slower when the car crawls)
  double duration_s = 0.0;
};

/// One traffic car. Position and motion in Frenet coordinates of the reference line.
struct TrafficCar {
  int id = 0;
  double s_m = 0.0;
  double d_m = 0.0;
  double speed_mps = 0.0;     ///< along its lane
  double accel_mps2 = 0.0;    ///< along its lane, over the last step
  double d_rate_mps = 0.0;    ///< lateral speed (dd/dt)
  double cruise_mps = 0.0;    ///< the speed it wants to drive
  int lane = 1;               ///< lane it keeps, or moves to during a lane change
  std::optional<LaneManoeuvre> manoeuvre;
  double since_lane_change_s = 1e9;
  // faithful lane-change bookkeeping
  std::optional<int> candidate_lane;
  int clear_steps = 0;
  bool held_up = false;       ///< reacting to a vehicle ahead (this step)
  double since_held_up_s = 1e9;  ///< time since it last reacted to a vehicle ahead
  // wander
  double wander_phase_rad = 0.0;
  double wander_omega_rps = 0.0;
  double lane_offset_m = 0.0;  ///< current wander offset from the lane centre
  /// Set for a car of a scripted scenario: it keeps its lane and speed until an event.
  struct Script {
    double target_speed_mps = 0.0;
    double rate_mps2 = 3.0;       ///< how fast it reaches the target speed
    double brake_mps2 = 0.0;      ///< braking under way ...
    double brake_left_s = 0.0;    ///< ... for this much longer
    int change_to_lane = -1;      ///< a lane change to start at the next step
  };
  std::optional<Script> script;
  bool far = false;            ///< farther than the despawn distance; waiting to be placed again
  core::Rng rng;               ///< this car's own random stream
};

/// All traffic. Deterministic from the seed. Keeps a reference to the line and map.
class Traffic {
 public:
  Traffic(const core::Map& map, const core::ReferenceLine& line, const TrafficParams& params,
          const core::RoadParams& road, TrafficProfile profile, std::uint64_t seed);

  /// Places every car before the first step (no car behind the ego in the ego's lane).
  void place_initial(const EgoView& ego);
  /// Advances one step of dt_s: every car decides from the current frame, then all move,
  /// then far cars are placed again in batches.
  void step(const EgoView& ego, double dt_s);

  [[nodiscard]] const std::vector<TrafficCar>& cars() const { return cars_; }
  /// A car as sensor fusion reports it (exact values; rounding is the caller's).
  [[nodiscard]] core::CarObservation observe(const TrafficCar& car) const;
  /// The car's footprint in map axes.
  [[nodiscard]] core::OrientedBox footprint(const TrafficCar& car) const;
  [[nodiscard]] TrafficProfile profile() const { return profile_; }

  /// Testing hook: replaces the cars (ids are reassigned in order).
  void set_cars(std::vector<TrafficCar> cars);

  /// Replaces the random traffic by a scenario's scripted cars: they keep their lane and
  /// speed (no following, no re-placement) until an event (apply_event) says otherwise.
  void set_script(const std::vector<ScriptedCar>& cars);
  /// Applies one scenario event to the scripted car it names.
  void apply_event(const ScenarioEvent& event);
  [[nodiscard]] bool scripted() const { return scripted_; }

 private:
  const core::Map& map_;
  const core::ReferenceLine& line_;
  TrafficParams params_;
  core::RoadParams road_;
  TrafficProfile profile_;
  core::Rng spawn_rng_;
  int frames_to_batch_ = 0;
  bool scripted_ = false;
  std::vector<TrafficCar> cars_;
  // Per-step scratch, reused so that step() does not allocate.
  struct Vehicle {               // a car or the ego as the others see it this step
    double s_m = 0.0;            // wrapped
    double speed_mps = 0.0;
    double accel_mps2 = 0.0;     // over the last step
    unsigned follow_lanes = 0;   // lanes it occupies for following (bit per lane)
    unsigned now_lanes = 0;      // lanes it counts in for lane-clear checks
    int car = -1;                // index into cars_, -1 for the ego
  };
  struct Decision {              // what a car does this step, from the previous frame
    double accel_mps2 = 0.0;     // applied
    double idm_mps2 = 0.0;       // (calm) plain IDM, unclamped, for MOBIL
    double new_speed_mps = 0.0;
    int leader = -1;             // index into vehicles_, -1 when none
    double leader_gap_m = 0.0;   // centre to centre along s
    int change_to_lane = -1;     // start a lane change into this lane, -1 for none
  };
  std::vector<Vehicle> vehicles_;
  std::vector<Decision> decisions_;
  std::vector<core::Vec2> positions_;
  double ego_prev_speed_mps_ = -1.0;  // the ego's speed at the previous step (-1: none yet)
  // implementation helpers live in traffic.cpp
  friend struct TrafficImpl;
};

}  // namespace overtake::sim
