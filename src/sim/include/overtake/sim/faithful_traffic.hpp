#pragma once
// Faithful traffic: the original's CarAIControl and CarTraffic rules driving car bodies.
//
// Each car is a body (position, heading, speed) that steers towards the lane point of its
// target waypoint and works its throttle and brake towards a desired speed:
// - the speed cap drawn at placement is the desired speed; throttle is 0.04 per mph of
//   shortfall (times a slow wander of 0.9-1.0) against drag, so a car settles well below it;
// - one ray straight ahead from its front meets the first body (a car or the ego): inside
//   0.5 m * (own cap in mph - that body's speed in m/s), bumper to bumper and not clamped,
//   the desired speed becomes the body's speed in m/s, read as mph (about 0.45 of it);
// - reacting (or when the ray meets nothing at all: its distance reads 0), faster than
//   15 mph, 100 steps after its last change and within 15 m of its next waypoint, it counts
//   steps on which the lane beside it is clear; after more than 50 it switches lane at once
//   and steers over;
// - placed 2-3 waypoints behind or 4-5 ahead of the ego's closest waypoint, exactly on it;
//   re-placed in batches once more than 200 m (straight line) from the ego; at the start
//   every car waits parked off the road;
// - after touching another car or the ego it slows (when the other is in front) and veers
//   away for a second.
// What the source leaves to its scene (engine, drag, brakes, steering response, how far a
// ray sees, the wander) is ours, calibrated against telemetry recorded from the original
// (docs/fidelity.md).

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <vector>

#include "overtake/core/random.hpp"
#include "overtake/sim/traffic.hpp"

namespace overtake::sim {

/// A smooth random signal in [0, 1] (value noise, quintic between lattice points drawn from
/// the stream), sampled at non-decreasing coordinates: the original's Perlin wander.
class SmoothNoise {
 public:
  explicit SmoothNoise(std::uint64_t seed = 0);
  /// The signal at `x` (x must not go back).
  [[nodiscard]] double at(double x);
  /// Through a checkpoint; a lattice cell outside [0, max_cell] is refused (catching up to
  /// it would take that many draws).
  void archive(core::StateArchive& ar, long max_cell);

 private:
  [[nodiscard]] double draw();
  core::Rng rng_;
  long cell_ = 0;
  double v0_ = 0.5;
  double v1_ = 0.5;
};

/// What a car's ray met at its last step.
enum class SightKind { nothing, scenery, car, ego };

/// Whether a ray along the road from lane k's centre at s stays on the road for the whole
/// horizon (it then meets nothing): lanes x bins of 1 m of s from the line's start. It depends
/// on the line, the road and the faithful params only, so one table may serve every world of
/// a map (the learning environment's, say): a world built without one builds its own.
struct OpenRoadTable {
  std::vector<unsigned char> open;
  std::size_t bins = 0;
};

[[nodiscard]] std::shared_ptr<const OpenRoadTable> build_open_road_table(
    const core::ReferenceLine& line, const core::RoadParams& road, const FaithfulTrafficParams& f);

class FaithfulTraffic final : public TrafficModel {
 public:
  /// One car's driver: the state the original's CarAIControl keeps.
  struct Driver {
    double cap_mps = 0.0;             ///< speed cap (drawn at placement)
    std::size_t target_waypoint = 0;  ///< the waypoint it steers for
    int lane_change_time = 0;         ///< steps since its last lane change (saturates)
    std::vector<int> clear_counts;    ///< counted clear steps, per target lane
    bool staged = false;              ///< waiting in the queue to be placed
    bool fresh = false;               ///< placed this frame (reports its cap as m/s)
    double avoid_until_s = -1.0;      ///< evasive action after a contact, until then ...
    double avoid_slowdown = 1.0;      ///< ... desired speed times this ...
    double avoid_offset_m = 0.0;      ///< ... and the target offset sideways by this
    SmoothNoise noise;
    // What it saw and decided at its last step (for tests and viewers).
    SightKind sight = SightKind::nothing;
    int sight_car = -1;             ///< index of the car it saw
    double sight_distance_m = 0.0;  ///< 0 when the ray met nothing
    bool reacting = false;
    double desired_mph = 0.0;
    double pedal = 0.0;  ///< throttle (> 0) or brake (< 0), in [-1, 1]
  };

  /// `open_road`: the table of the line, road and params (null: built here).
  FaithfulTraffic(const core::WaypointFrenet& chords, const core::ReferenceLine& line,
                  const TrafficParams& params, const core::RoadParams& road,
                  const core::CarFootprint& car, std::uint64_t seed,
                  std::shared_ptr<const OpenRoadTable> open_road = nullptr);

  void start(const EgoView& ego) override;
  void step(const EgoView& ego, double dt_s) override;
  [[nodiscard]] const std::vector<TrafficCar>& cars() const override { return cars_; }
  void on_contact(std::size_t i, core::Vec2 shift_m, double speed_mps,
                  const core::OrientedBox& other) override;
  void archive(core::StateArchive& ar) override;

  [[nodiscard]] const std::vector<Driver>& drivers() const { return drivers_; }
  [[nodiscard]] double time_s() const { return time_s_; }
  /// Where car i waits before it is placed.
  [[nodiscard]] core::Vec2 parked_position(std::size_t i) const { return parked_[i]; }

  /// Testing: puts car i on its lane's point at chord s (the waypoint before it steering),
  /// driving at `speed_mps` with cap `cap_mps`, settled (its last lane change long ago).
  void put_on_road_for_testing(std::size_t i, double s_m, int lane, double speed_mps,
                               double cap_mps);
  /// Each car's heading as a unit vector, cached (core::HeadingUnit gives the exact unit of
  /// any heading asked for): the contact checks share it.
  [[nodiscard]] std::vector<core::HeadingUnit>& heading_units() { return units_; }
  /// Testing: no more batches; cars stay where they are.
  void hold_batches_for_testing() { batches_held_ = true; }

 private:
  struct Sight {
    SightKind kind = SightKind::nothing;
    int car = -1;
    double distance_m = 0.0;
    double body_speed_mps = 0.0;
  };
  struct Command {
    double pedal = 0.0;
    double steer = 0.0;  // in [-1, 1], positive to the right
    int new_lane = -1;
  };

  [[nodiscard]] core::OrientedBox body(std::size_t i) const;
  /// What car i's ray meets; `ego_axis`: heading_unit of the ego's heading; `ego_reach_m`:
  /// the ego body's reach from a ray (as body_reach_m_).
  [[nodiscard]] Sight look(std::size_t i, const EgoView& ego, core::Vec2 ego_axis,
                           double ego_reach_m);
  [[nodiscard]] bool road_open_ahead(std::size_t i) const;
  [[nodiscard]] bool lane_clear(std::size_t i, int lane, const EgoView& ego) const;
  [[nodiscard]] int count_lane_change(std::size_t i, const EgoView& ego);
  [[nodiscard]] Command decide(std::size_t i, const EgoView& ego, core::Vec2 ego_axis,
                               double ego_reach_m);
  void move(std::size_t i, const Command& c, double dt_s);
  void batch(const EgoView& ego);
  void spawn(std::size_t i, const EgoView& ego);
  void park(std::size_t i);
  void refresh_frenet(std::size_t i);

  const core::WaypointFrenet& chords_;
  const core::ReferenceLine& line_;
  TrafficParams params_;
  FaithfulTrafficParams f_;
  core::RoadParams road_;
  core::CarFootprint car_;
  core::Rng spawn_rng_;
  std::vector<TrafficCar> cars_;
  std::vector<Driver> drivers_;
  std::vector<core::Vec2> parked_;
  std::vector<Command> commands_;
  std::deque<std::size_t> queue_;  // staged cars, in the order they went far
  bool init_ = true;               // the first frame places a batch at once
  bool batches_held_ = false;
  int frame_counter_ = 0;
  int frames_to_batch_ = 0;
  double time_s_ = 0.0;
  std::shared_ptr<const OpenRoadTable> open_road_;  // never null
  // Caches, rebuilt from the state above (not saved in checkpoints): each car's heading as
  // a unit vector (its ray's direction and its body's axis), the ego's, and how far from a
  // ray a car's body can reach (half its diagonal plus slack).
  std::vector<core::HeadingUnit> units_;
  core::HeadingUnit ego_unit_;
  double body_reach_m_ = 0.0;
  // Scratch of look(): the bodies near a ray, with the least distance along it at which the
  // ray could meet each (`order`: the car's index, the ego after the cars).
  struct NearRay {
    double least_t_m = 0.0;
    std::size_t order = 0;
  };
  std::vector<NearRay> near_ray_;
};

}  // namespace overtake::sim
