// Calm traffic, the model: construction, the step (scripted cars, or the calm profile's
// decisions and motion, then placement), the bodies it publishes, contacts, scripts. Driving
// is in calm_driving.cpp, placement in calm_placement.cpp.

#include "overtake/sim/calm_traffic.hpp"

#include <algorithm>
#include <bit>
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
    for (std::size_t i = 0; i < n; ++i) CalmImpl::move(*this, i, decisions_[i], dt_s);
    ego_prev_speed_mps_ = ego.speed_mps;
    publish();
    return;
  }
  const double ego_s = line_.wrap_s(ego.frenet.s_m);
  CalmImpl::build_vehicles(*this, ego, ego_s, dt_s);
  decisions_.resize(n);
  CalmImpl::decide_calm(*this, dt_s);
  for (std::size_t i = 0; i < n; ++i) CalmImpl::move(*this, i, decisions_[i], dt_s);
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
  lane_scales_.resize(cars_.size());
  for (std::size_t i = 0; i < cars_.size(); ++i) CalmImpl::publish_car(*this, i);
}

void CalmImpl::publish_car(CalmTraffic& t, std::size_t i) {
  const CalmCar& c = t.cars_[i];
  TrafficCar& b = t.bodies_[i];
  const core::ReferenceLine& line = t.line_;
  const core::FrenetPoint p{line.wrap_s(c.s_m), c.d_m};
  // line.velocity(p, line.s_rate(p, speed), d_rate) and line.to_cartesian(p), the line
  // looked up once.
  const core::ReferenceLine::Sample at = line.sample(p.s_m);
  const double metres_per_s = line.metres_per_s(at, p.d_m);
  t.lane_scales_[i] = {std::bit_cast<std::uint64_t>(p.s_m), std::bit_cast<std::uint64_t>(p.d_m),
                       metres_per_s, true};
  const core::Vec2 v = line.velocity(at, p.d_m, c.speed_mps / metres_per_s, c.d_rate_mps);
  b.id = static_cast<int>(i);
  b.position = line.to_cartesian(at, p.d_m);
  b.heading_rad =
      core::norm(v) < kStationaryMps ? line.frame(p.s_m).heading_rad : std::atan2(v.y, v.x);
  b.speed_mps = c.speed_mps;
  b.reported_velocity_mps = v;
  b.closest_waypoint = t.chords_.closest(b.position, b.closest_waypoint);
  b.map_frenet = t.chords_.to_frenet(b.position, b.closest_waypoint);
  b.lane = c.lane;
  b.parked = false;
}

void CalmTraffic::on_contact(std::size_t i, core::Vec2 shift_m, double speed_mps,
                             const core::OrientedBox& /*other*/) {
  CalmCar& c = cars_[i];
  const core::RoadFrame fr = line_.frame(line_.wrap_s(c.s_m));
  c.s_m = line_.wrap_s(c.s_m + core::dot(shift_m, fr.tangent) / fr.ds_scale);
  c.d_m += core::dot(shift_m, fr.normal);
  c.speed_mps = std::max(0.0, speed_mps);
  // Only this car's body changes: publishing the others again gives what they have (the
  // closest waypoint found from the one found before is that one).
  CalmImpl::publish_car(*this, i);
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

// ----- checkpoints -------------------------------------------------------------------------

namespace overtake::sim {

void CalmTraffic::archive(core::StateArchive& ar) {
  ar.part("calm traffic");
  const int lanes = road_.lane_count;
  const std::size_t n = cars_.size();
  ar.io(spawn_rng_, "spawn stream");
  ar.io(frames_to_batch_, "frames to batch");
  ar.io(scripted_, "scripted");
  ar.io_speed(ego_prev_speed_mps_, "ego's previous speed");
  ar.require(ar.io_length(n, n, "cars") == n, "the checkpoint has another number of cars");
  for (CalmCar& c : cars_) {
    ar.io_metres(c.s_m, "s");
    ar.io_metres(c.d_m, "d");
    ar.io_speed(c.speed_mps, "speed");
    ar.io_speed(c.accel_mps2, "acceleration");
    ar.io_speed(c.d_rate_mps, "lateral speed");
    ar.io_speed(c.cruise_mps, "cruise speed");
    ar.io_range(c.lane, 0, lanes - 1, "lane");
    ar.io_optional(c.manoeuvre, "lane change", [lanes](core::StateArchive& a, LaneManoeuvre& m) {
      a.io_range(m.from_lane, 0, lanes - 1, "lane change from");
      a.io_range(m.to_lane, 0, lanes - 1, "lane change to");
      a.io_metres(m.from_d_m, "lane change start d");
      a.io(m.elapsed_s, "lane change elapsed");
      a.io(m.duration_s, "lane change duration");
    });
    ar.io(c.since_lane_change_s, "since lane change");
    ar.io(c.held_up, "held up");
    ar.io(c.since_held_up_s, "since held up");
    ar.io(c.wander_phase_rad, "wander phase");
    ar.io(c.wander_omega_rps, "wander frequency");
    ar.io_metres(c.lane_offset_m, "wander offset");
    ar.io_optional(c.script, "script", [lanes](core::StateArchive& a, CalmCar::Script& s) {
      a.io_speed(s.target_speed_mps, "script speed");
      a.io_speed(s.rate_mps2, "script rate");
      a.io_speed(s.brake_mps2, "script braking");
      a.io(s.brake_left_s, "script braking left");
      a.io_range(s.change_to_lane, -1, lanes - 1, "script lane change");
    });
    ar.io(c.far, "far");
    ar.io(c.rng, "car stream");
  }
  const std::size_t bodies = ar.io_length(bodies_.size(), n, "bodies");
  if (ar.loading()) bodies_.resize(bodies);
  for (TrafficCar& b : bodies_) archive_car(ar, b, lanes, chords_.size());
  // The ego's acceleration at the last step is read by placement: the vehicles of the last
  // step carry over.
  ar.io_vector(vehicles_, n + 1, "vehicles", [n](core::StateArchive& a, Vehicle& v) {
    a.io_metres(v.s_m, "vehicle s");
    a.io_speed(v.speed_mps, "vehicle speed");
    a.io_speed(v.accel_mps2, "vehicle acceleration");
    a.io(v.follow_lanes, "vehicle lanes");
    a.io(v.now_lanes, "vehicle lanes");
    a.io_range(v.car, -1, static_cast<int>(n) - 1, "vehicle car");
  });
  if (ar.loading()) {
    decisions_.assign(n, Decision{});
    positions_.assign(n, core::Vec2{});
  }
}

}  // namespace overtake::sim
