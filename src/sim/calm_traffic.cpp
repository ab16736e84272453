// Calm traffic, the model: construction, the step (scripted cars, or the calm profile's
// decisions and motion, then placement), the bodies it publishes, contacts, scripts. Driving
// is in calm_driving.cpp, placement in calm_placement.cpp.

#include "overtake/sim/calm_traffic.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "calm_internal.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/units.hpp"

namespace overtake::sim {
namespace {

constexpr std::uint64_t kSpawnStream = 0;
constexpr std::uint64_t kFirstCarStream = 100;
/// Below this speed a footprint takes the road's heading instead of the velocity's.
constexpr double kStationaryMps = 0.1;

}  // namespace

CalmTraffic::CalmTraffic(const core::Map& map, const core::ReferenceLine& line,
                         const core::WaypointFrenet& chords, const TrafficParams& params,
                         const core::RoadParams& road, const core::CarFootprint& car,
                         std::uint64_t seed)
    : map_(map),
      line_(line),
      chords_(chords),
      params_(params),
      road_(road),
      car_(car),
      spawn_rng_(core::derive_seed(seed, kSpawnStream)) {
  assert(!map.waypoints.empty());
  assert(road.lane_count >= 1 && road.lane_count <= 32);
  const auto n = static_cast<std::size_t>(std::max(0, params.car_count));
  cars_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    cars_[i].rng = core::Rng(core::derive_seed(seed, kFirstCarStream + i));
  }
  vehicles_.reserve(n + 1);
  decisions_.reserve(n);
  positions_.resize(n);
  publish();
}

void CalmTraffic::start(const EgoView& ego) {
  using Where = CalmImpl::Where;
  positions_.resize(cars_.size());
  const int n = static_cast<int>(cars_.size());
  for (int i = 0; i < n; ++i) {
    if (CalmImpl::try_place(*this, i, i, ego, true, Where::either)) continue;
    if (CalmImpl::try_place(*this, i, i, ego, true, Where::ahead)) continue;
    if (CalmImpl::try_place(*this, i, i, ego, true, Where::behind)) continue;
    CalmImpl::place_fallback(*this, i, ego);
  }
  frames_to_batch_ = spawn_rng_.uniform_int(params_.placement.batch_min_frames,
                                            params_.placement.batch_max_frames);
  publish();
}

void CalmTraffic::step(const EgoView& ego, double dt_s) {
  assert(dt_s > 0.0);
  const std::size_t n = cars_.size();
  if (scripted_) {
    decisions_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      CalmCar& c = cars_[i];
      CalmCar::Script& m = *c.script;
      Decision& dec = decisions_[i];
      dec = {};
      const double v = c.speed_mps;
      if (m.brake_left_s > 0.0) {
        dec.new_speed_mps = std::max(0.0, v - m.brake_mps2 * dt_s);
        m.brake_left_s -= dt_s;
        if (m.brake_left_s <= 0.0) m.target_speed_mps = dec.new_speed_mps;  // then hold it
      } else if (v < m.target_speed_mps) {
        dec.new_speed_mps = std::min(m.target_speed_mps, v + m.rate_mps2 * dt_s);
      } else {
        dec.new_speed_mps = std::max(m.target_speed_mps, v - m.rate_mps2 * dt_s);
      }
      dec.change_to_lane = m.change_to_lane;
      m.change_to_lane = -1;
    }
    for (std::size_t i = 0; i < n; ++i) CalmImpl::move(*this, cars_[i], decisions_[i], dt_s);
    ego_prev_speed_mps_ = ego.speed_mps;
    publish();
    return;
  }
  const double ego_s = line_.wrap_s(ego.frenet.s_m);
  CalmImpl::build_vehicles(*this, ego, ego_s, dt_s);
  decisions_.resize(n);
  CalmImpl::decide_calm(*this, dt_s);
  for (std::size_t i = 0; i < n; ++i) CalmImpl::move(*this, cars_[i], decisions_[i], dt_s);
  ego_prev_speed_mps_ = ego.speed_mps;

  for (CalmCar& c : cars_) {
    c.far = std::abs(CalmImpl::ahead(*this, ego_s, c.s_m)) > params_.placement.despawn_distance_m;
  }
  if (--frames_to_batch_ <= 0) {
    const int batch =
        spawn_rng_.uniform_int(params_.placement.batch_min_cars, params_.placement.batch_max_cars);
    int tried = 0;
    for (std::size_t i = 0; i < n && tried < batch; ++i) {
      if (!cars_[i].far) continue;
      ++tried;
      (void)CalmImpl::try_place(*this, static_cast<int>(i), static_cast<int>(n), ego, false,
                                CalmImpl::Where::either);
    }
    frames_to_batch_ = spawn_rng_.uniform_int(params_.placement.batch_min_frames,
                                              params_.placement.batch_max_frames);
  }
  publish();
}

void CalmTraffic::publish() {
  bodies_.resize(cars_.size());
  for (std::size_t i = 0; i < cars_.size(); ++i) {
    const CalmCar& c = cars_[i];
    TrafficCar& b = bodies_[i];
    const core::FrenetPoint p{line_.wrap_s(c.s_m), c.d_m};
    const core::Vec2 v = line_.velocity(p, line_.s_rate(p, c.speed_mps), c.d_rate_mps);
    b.id = static_cast<int>(i);
    b.position = line_.to_cartesian(p);
    b.heading_rad =
        core::norm(v) < kStationaryMps ? line_.frame(p.s_m).heading_rad : std::atan2(v.y, v.x);
    b.speed_mps = c.speed_mps;
    b.reported_velocity_mps = v;
    b.closest_waypoint = chords_.closest(b.position, b.closest_waypoint);
    b.map_frenet = chords_.to_frenet(b.position, b.closest_waypoint);
    b.lane = c.lane;
    b.parked = false;
  }
}

void CalmTraffic::on_contact(std::size_t i, core::Vec2 shift_m, double speed_mps,
                             const core::OrientedBox& /*other*/) {
  CalmCar& c = cars_[i];
  const core::RoadFrame fr = line_.frame(line_.wrap_s(c.s_m));
  c.s_m = line_.wrap_s(c.s_m + core::dot(shift_m, fr.tangent) / fr.ds_scale);
  c.d_m += core::dot(shift_m, fr.normal);
  c.speed_mps = std::max(0.0, speed_mps);
  publish();
}

void CalmTraffic::set_cars(std::vector<CalmCar> cars) {
  cars_ = std::move(cars);
  for (CalmCar& c : cars_) c.s_m = line_.wrap_s(c.s_m);
  positions_.resize(cars_.size());
  publish();
}

void CalmTraffic::set_script(const std::vector<ScriptedCar>& cars) {
  std::vector<CalmCar> out;
  out.reserve(cars.size());
  for (const ScriptedCar& sc : cars) {
    CalmCar c;
    c.s_m = line_.wrap_s(sc.s_m);
    c.lane = sc.lane;
    c.d_m = core::lane_center_d(sc.lane, road_);
    c.speed_mps = sc.speed_mps;
    c.cruise_mps = sc.speed_mps;
    c.wander_omega_rps = 0.0;  // scripted cars keep to the lane centre
    c.script = CalmCar::Script{sc.speed_mps};
    out.push_back(std::move(c));
  }
  set_cars(std::move(out));
  scripted_ = true;
}

void CalmTraffic::apply_event(const ScenarioEvent& e) {
  if (e.car < 0 || static_cast<std::size_t>(e.car) >= cars_.size()) return;
  CalmCar& c = cars_[static_cast<std::size_t>(e.car)];
  if (!c.script) return;
  CalmCar::Script& m = *c.script;
  switch (e.action) {
    case ScenarioAction::change_lane:
      if (e.lane != c.lane && e.lane >= 0 && e.lane < road_.lane_count) m.change_to_lane = e.lane;
      break;
    case ScenarioAction::brake:
      m.brake_mps2 = e.rate_mps2;
      m.brake_left_s = e.duration_s;
      break;
    case ScenarioAction::set_speed:
      m.brake_left_s = 0.0;
      m.target_speed_mps = e.speed_mps;
      m.rate_mps2 = e.rate_mps2;
      break;
  }
}

}  // namespace overtake::sim
