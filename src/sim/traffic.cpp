#include "overtake/sim/traffic.hpp"

#include <cmath>

#include "overtake/sim/calm_traffic.hpp"
#include "overtake/sim/faithful_traffic.hpp"

namespace overtake::sim {
namespace {

/// Bodies whose centres are farther apart than this cannot touch (two diagonals of a car,
/// with room to spare).
constexpr double kContactCullM = 12.0;

/// Velocity of a body pushed along `normal` (unit, pointing away from what pushes it) after
/// a contact: what it had towards the other body, relative to it, is taken away.
core::Vec2 after_push(core::Vec2 v, core::Vec2 other_v, core::Vec2 normal, double share) {
  const double closing = core::dot(v - other_v, normal);
  if (closing >= 0.0) return v;
  return v - (share * closing) * normal;
}

/// Speed along the heading (`axis`, unit) of a velocity (a body does not slide sideways).
double speed_along(core::Vec2 v, core::Vec2 axis) {
  return std::max(0.0, core::dot(v, axis));
}

/// Traffic that follows recorded bodies step by step, whatever the ego does.
class ReplayedTraffic final : public TrafficModel {
 public:
  ReplayedTraffic(std::vector<std::vector<TrafficCar>> steps)  // NOLINT(*-explicit-*)
      : steps_(std::move(steps)) {
    if (!steps_.empty()) cars_ = steps_.front();
  }
  void start(const EgoView& /*ego*/) override {}
  void step(const EgoView& /*ego*/, double /*dt_s*/) override {
    if (next_ < steps_.size()) cars_ = steps_[next_];
    if (next_ < steps_.size()) ++next_;
  }
  [[nodiscard]] const std::vector<TrafficCar>& cars() const override { return cars_; }
  void on_contact(std::size_t /*i*/, core::Vec2 /*shift_m*/, double /*speed_mps*/,
                  const core::OrientedBox& /*other*/) override {}
  void archive(core::StateArchive& ar) override {
    ar.part("replayed traffic");
    ar.io_range(next_, 0, steps_.size(), "recorded step");
    if (ar.loading())
      cars_ = steps_.empty() ? std::vector<TrafficCar>{} : steps_[next_ == 0 ? 0 : next_ - 1];
  }

 private:
  std::vector<std::vector<TrafficCar>> steps_;
  std::vector<TrafficCar> cars_;
  std::size_t next_ = 1;  // the recorded step the next world step moves the cars to
};

}  // namespace

void archive_car(core::StateArchive& ar, TrafficCar& car, int lanes, std::size_t waypoints) {
  ar.io_range(car.id, 0, 65535, "car id");
  ar.io(car.position, "car position");
  ar.io(car.heading_rad, "car heading");
  ar.io_speed(car.speed_mps, "car speed");
  ar.io_speed(car.reported_velocity_mps.x, "car reported velocity");
  ar.io_speed(car.reported_velocity_mps.y, "car reported velocity");
  ar.io(car.map_frenet, "car s and d");
  ar.io_range(car.closest_waypoint, 0, waypoints == 0 ? 0 : waypoints - 1, "car waypoint");
  ar.io_range(car.lane, 0, lanes - 1, "car lane");
  ar.io(car.parked, "car parked");
}

std::optional<TrafficProfile> parse_traffic_profile(std::string_view name) {
  if (name == "faithful") return TrafficProfile::faithful;
  if (name == "calm") return TrafficProfile::calm;
  return std::nullopt;
}

std::string_view to_string(TrafficProfile p) {
  switch (p) {
    case TrafficProfile::faithful:
      return "faithful";
    case TrafficProfile::calm:
      return "calm";
  }
  return "faithful";
}

Traffic::Traffic(const core::Map& map, const core::ReferenceLine& line,
                 const core::WaypointFrenet& chords, const TrafficParams& params,
                 const core::RoadParams& road, const core::CarFootprint& car,
                 TrafficProfile profile, std::uint64_t seed,
                 std::shared_ptr<const OpenRoadTable> open_road)
    : map_(map),
      line_(line),
      chords_(chords),
      params_(params),
      road_(road),
      car_(car),
      profile_(profile),
      seed_(seed) {
  if (profile == TrafficProfile::faithful) {
    model_ = std::make_unique<FaithfulTraffic>(chords, line, params, road, car, seed,
                                               std::move(open_road));
  } else {
    model_ = std::make_unique<CalmTraffic>(map, line, chords, params, road, car, seed);
  }
}

Traffic::~Traffic() = default;

void Traffic::place_initial(const EgoView& ego) {
  model_->start(ego);
}

void Traffic::step(const EgoView& ego, double dt_s) {
  model_->step(ego, dt_s);
}

std::optional<int> Traffic::resolve_contacts(const EgoView& ego) {
  std::optional<int> touched;
  const std::vector<TrafficCar>& cars = model_->cars();
  // Faithful traffic has its cars' units cached already, for the headings they moved to.
  auto* faithful = dynamic_cast<FaithfulTraffic*>(model_.get());
  std::vector<core::HeadingUnit>& units = faithful != nullptr ? faithful->heading_units() : units_;
  units.resize(cars.size());
  // A contact may move the cars (and calm traffic turns them), so each unit is asked for
  // with the heading of the moment; the cache only saves the sine and cosine.
  const auto unit = [&](std::size_t i) { return units[i].of(cars[i].heading_rad); };
  const core::Vec2 ego_axis = ego_unit_.of(ego.body.heading_rad);
  const core::Vec2 ego_v = ego.speed_mps * ego_axis;
  const double cull_sq = kContactCullM * kContactCullM;
  // The ego first: it is not moved, the car is pushed out of it.
  for (std::size_t i = 0; i < cars.size(); ++i) {
    const TrafficCar& c = cars[i];
    if (c.parked || core::distance_sq(c.position, ego.body.center) > cull_sq) continue;
    const core::OrientedBox box = footprint(c);
    const core::Vec2 axis = unit(i);
    const std::optional<core::Penetration> pen =
        core::box_penetration(ego.body, ego_axis, box, axis);
    if (!pen || pen->depth_m <= 0.0) continue;
    const core::Vec2 v = after_push(c.speed_mps * axis, ego_v, pen->normal, 1.0);
    model_->on_contact(i, pen->depth_m * pen->normal, speed_along(v, axis), ego.body);
    if (!touched) touched = c.id;
  }
  // Then pairs of cars: each moves half the way, and they share what they closed with.
  for (std::size_t i = 0; i < cars.size(); ++i) {
    for (std::size_t j = i + 1; j < cars.size(); ++j) {
      const TrafficCar& a = cars[i];
      const TrafficCar& b = cars[j];
      if (a.parked || b.parked || core::distance_sq(a.position, b.position) > cull_sq) continue;
      const core::OrientedBox box_a = footprint(a);
      const core::OrientedBox box_b = footprint(b);
      const core::Vec2 axis_a = unit(i);
      const core::Vec2 axis_b = unit(j);
      const std::optional<core::Penetration> pen =
          core::box_penetration(box_a, axis_a, box_b, axis_b);
      if (!pen || pen->depth_m <= 0.0) continue;
      const core::Vec2 va = a.speed_mps * axis_a;
      const core::Vec2 vb = b.speed_mps * axis_b;
      const core::Vec2 new_b = after_push(vb, va, pen->normal, 0.5);
      const core::Vec2 new_a = after_push(va, vb, -1.0 * pen->normal, 0.5);
      const double half = 0.5 * pen->depth_m;
      const double speed_a = speed_along(new_a, axis_a);
      const double speed_b = speed_along(new_b, axis_b);
      model_->on_contact(i, -half * pen->normal, speed_a, box_b);
      model_->on_contact(j, half * pen->normal, speed_b, box_a);
    }
  }
  return touched;
}

core::CarObservation Traffic::observe(const TrafficCar& car) const {
  core::CarObservation o;
  o.id = car.id;
  o.position = car.position;
  o.velocity_mps = car.reported_velocity_mps;
  o.s_m = car.map_frenet.s_m;
  o.d_m = car.map_frenet.d_m;
  return o;
}

core::OrientedBox Traffic::footprint(const TrafficCar& car) const {
  return {car.position, car.heading_rad, car_.length_m, car_.width_m};
}

void Traffic::set_script(const std::vector<ScriptedCar>& cars) {
  auto calm = std::make_unique<CalmTraffic>(map_, line_, chords_, params_, road_, car_, seed_);
  calm->set_script(cars);
  model_ = std::move(calm);
  scripted_ = true;
}

void Traffic::set_replayed(std::vector<std::vector<TrafficCar>> steps) {
  model_ = std::make_unique<ReplayedTraffic>(std::move(steps));
  replayed_ = true;
  scripted_ = false;
}

void Traffic::archive(core::StateArchive& ar) {
  model_->archive(ar);
}

void Traffic::apply_event(const ScenarioEvent& event) {
  if (!scripted_) return;
  static_cast<CalmTraffic&>(*model_).apply_event(event);
}

}  // namespace overtake::sim
