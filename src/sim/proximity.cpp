#include "overtake/sim/proximity.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "overtake/sim/world.hpp"

namespace overtake::sim {

double predicted_margin_m(const RelativeMotion& rel, const core::CarFootprint& car,
                          const ProximityParams& params) {
  // The four linear pieces a + b t: +-(ds + dvs t) - length and k (+-(dd + dvd t) - width),
  // each plus the time weight; the margin is the largest of them.
  const double k = params.lateral_weight;
  const double c = params.time_weight_mps;
  const std::array<double, 4> a{rel.ds_m - car.length_m, -rel.ds_m - car.length_m,
                                k * (rel.dd_m - car.width_m), k * (-rel.dd_m - car.width_m)};
  const std::array<double, 4> b{rel.dvs_mps + c, -rel.dvs_mps + c, k * rel.dvd_mps + c,
                                -k * rel.dvd_mps + c};
  const auto at = [&](double t) {
    double m = -std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < 4; ++i) m = std::max(m, a[i] + b[i] * t);
    return m;
  };
  const double h = params.horizon_s;
  double least = std::min(at(0.0), at(h));
  for (std::size_t i = 0; i < 4; ++i) {
    for (std::size_t j = i + 1; j < 4; ++j) {
      const double db = b[i] - b[j];
      if (db == 0.0) continue;
      const double t = (a[j] - a[i]) / db;
      if (t > 0.0 && t < h) least = std::min(least, at(t));
    }
  }
  return least;
}

Proximity proximity(const World& world, const ProximityParams& params) {
  const core::WaypointFrenet& chords = world.chords();
  const core::CarFootprint& car = world.params().car;
  const EgoState& ego = world.ego();
  const double loop = chords.loop_length_m();
  const auto velocity = [&chords](double heading_rad, double speed_mps, std::size_t waypoint) {
    const core::Vec2 v{speed_mps * std::cos(heading_rad), speed_mps * std::sin(heading_rad)};
    return std::array<double, 2>{core::dot(v, chords.forward(waypoint)),
                                 core::dot(v, chords.normal(waypoint))};
  };
  const auto ego_v = velocity(ego.yaw_rad, ego.speed_mps, ego.closest_waypoint);
  Proximity out{std::numeric_limits<double>::infinity(), std::nullopt};
  const std::vector<TrafficCar>& cars = world.traffic().cars();
  for (std::size_t i = 0; i < cars.size(); ++i) {
    const TrafficCar& c = cars[i];
    if (c.parked) continue;
    double ds = std::fmod(c.map_frenet.s_m - ego.map_frenet.s_m, loop);
    if (ds > 0.5 * loop) ds -= loop;
    if (ds < -0.5 * loop) ds += loop;
    if (std::abs(ds) > params.range_m) continue;
    const auto v = velocity(c.heading_rad, c.speed_mps, c.closest_waypoint);
    const RelativeMotion rel{ds, c.map_frenet.d_m - ego.map_frenet.d_m, v[0] - ego_v[0],
                             v[1] - ego_v[1]};
    const double m = predicted_margin_m(rel, car, params);
    if (m < out.margin_m) out = {m, i};
  }
  return out;
}

}  // namespace overtake::sim
