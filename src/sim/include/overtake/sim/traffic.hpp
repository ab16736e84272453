#pragma once
// The twelve other cars as bodies on the road: what the world, the telemetry and the viewers
// see of them, the profiles that drive them (faithful_traffic.hpp: the original's rules;
// calm_traffic.hpp: ours, and scripted scenarios), and contact between bodies.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/map.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/state_archive.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/core/waypoint_frenet.hpp"
#include "overtake/sim/params.hpp"
#include "overtake/sim/scenario.hpp"

namespace overtake::sim {

/// How traffic behaves.
enum class TrafficProfile {
  faithful,  ///< the original simulator's rules
  calm,      ///< (ours) IDM following with MOBIL lane changes
};

[[nodiscard]] std::optional<TrafficProfile> parse_traffic_profile(std::string_view name);
[[nodiscard]] std::string_view to_string(TrafficProfile p);

/// The ego as traffic sees it: a body to react to and to keep clear of.
struct EgoView {
  core::OrientedBox body;  ///< its footprint now
  double speed_mps = 0.0;
  core::FrenetPoint frenet;      ///< on the reference line
  core::FrenetPoint map_frenet;  ///< as the original measures it (waypoint chords)
  std::size_t closest_waypoint = 0;
};

/// One traffic car as a body: where it is, where it points, how fast it goes.
struct TrafficCar {
  int id = 0;
  core::Vec2 position;       ///< centre of its body
  double heading_rad = 0.0;  ///< where its body points
  double speed_mps = 0.0;    ///< along its heading
  /// What sensor fusion reports as its velocity: heading * speed, except on the first frame
  /// after it was placed, when the original reports its speed cap read as m/s.
  core::Vec2 reported_velocity_mps;
  core::FrenetPoint map_frenet;  ///< s and d as the original reports them (waypoint chords)
  std::size_t closest_waypoint = 0;
  int lane = 1;         ///< the lane it keeps, or moves into
  bool parked = false;  ///< waiting off the road to be placed (not a body on the road)
};

/// What drives the cars. Implementations keep their own state and publish the bodies.
class TrafficModel {
 public:
  virtual ~TrafficModel() = default;
  /// Before the first step.
  virtual void start(const EgoView& ego) = 0;
  /// One step of dt_s: every car decides from the frame before, then all move, then cars
  /// far from the ego are placed again.
  virtual void step(const EgoView& ego, double dt_s) = 0;
  [[nodiscard]] virtual const std::vector<TrafficCar>& cars() const = 0;
  /// A contact pushed car i by `shift_m` and left it `speed_mps` along its heading; `other`
  /// is the body it touched (the car's reaction is the model's).
  virtual void on_contact(std::size_t i, core::Vec2 shift_m, double speed_mps,
                          const core::OrientedBox& other) = 0;
  /// Writes or restores every piece of state that carries from one step to the next (a
  /// checkpoint). Restoring needs a model built with the same params and the same map.
  virtual void archive(core::StateArchive& ar) = 0;
};

/// A traffic car's body through a checkpoint; `lanes` and `waypoints` bound what is read.
void archive_car(core::StateArchive& ar, TrafficCar& car, int lanes, std::size_t waypoints);

struct OpenRoadTable;

/// All traffic. Deterministic from the seed. Keeps references to the map, its line and its
/// chords, which must outlive it.
class Traffic {
 public:
  /// `open_road`: faithful traffic's table of the line (null: built here).
  Traffic(const core::Map& map, const core::ReferenceLine& line, const core::WaypointFrenet& chords,
          const TrafficParams& params, const core::RoadParams& road, const core::CarFootprint& car,
          TrafficProfile profile, std::uint64_t seed,
          std::shared_ptr<const OpenRoadTable> open_road = nullptr);
  ~Traffic();
  Traffic(const Traffic&) = delete;
  Traffic& operator=(const Traffic&) = delete;

  /// Before the first step: faithful, every car parked off the road (the first batch places
  /// 1-3 at the first step); calm, all twelve placed around the ego.
  void place_initial(const EgoView& ego);
  /// Advances one step of dt_s (see TrafficModel::step).
  void step(const EgoView& ego, double dt_s);
  /// Separates bodies that overlap after a step. The ego goes where its path takes it, so
  /// only traffic is pushed: out of the ego, and pairs of cars apart; a push takes away the
  /// speed with which they closed. Returns the id of a car that touched the ego, if any.
  std::optional<int> resolve_contacts(const EgoView& ego);

  [[nodiscard]] const std::vector<TrafficCar>& cars() const { return model_->cars(); }
  /// A car as sensor fusion reports it (exact values; rounding is the caller's).
  [[nodiscard]] core::CarObservation observe(const TrafficCar& car) const;
  /// The car's footprint in map axes.
  [[nodiscard]] core::OrientedBox footprint(const TrafficCar& car) const;
  [[nodiscard]] TrafficProfile profile() const { return profile_; }
  [[nodiscard]] TrafficModel& model() { return *model_; }
  [[nodiscard]] const TrafficModel& model() const { return *model_; }

  /// Replaces the random traffic by a scenario's scripted cars: they keep their lane and
  /// speed (no following, no re-placement) until an event (apply_event) says otherwise.
  void set_script(const std::vector<ScriptedCar>& cars);
  /// Applies one scenario event to the scripted car it names.
  void apply_event(const ScenarioEvent& event);
  [[nodiscard]] bool scripted() const { return scripted_; }

  /// Replaces the traffic by recorded bodies: now the cars are `steps[0]`, after the k-th
  /// step from now `steps[k]`, whatever the ego does (a cut scenario's replayed traffic;
  /// after the last recorded step they stay where they were). Contacts do not move them.
  void set_replayed(std::vector<std::vector<TrafficCar>> steps);
  [[nodiscard]] bool replayed() const { return replayed_; }

  /// The model's state through a checkpoint (the model must be of the same kind: the
  /// profile, or scripted).
  void archive(core::StateArchive& ar);

 private:
  const core::Map& map_;
  const core::ReferenceLine& line_;
  const core::WaypointFrenet& chords_;
  TrafficParams params_;
  core::RoadParams road_;
  core::CarFootprint car_;
  TrafficProfile profile_;
  std::uint64_t seed_;
  bool scripted_ = false;
  bool replayed_ = false;
  std::unique_ptr<TrafficModel> model_;
  // Caches for the contact checks (rebuilt from the cars, not saved): each car's heading as
  // a unit vector, and the ego's.
  std::vector<core::HeadingUnit> units_;
  core::HeadingUnit ego_unit_;
};

}  // namespace overtake::sim
