#include "overtake/sim/recorded_traffic.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>

#include "overtake/core/state_archive.hpp"

namespace overtake::sim {
namespace {

constexpr std::size_t kMaxSteps = std::size_t{1} << 20U;  // 5.8 hours at 50 steps per second
constexpr std::size_t kMaxCars = 256;
constexpr std::size_t kDoubles = 8;

std::array<double*, kDoubles> doubles_of(TrafficCar& c) {
  return {&c.position.x,
          &c.position.y,
          &c.heading_rad,
          &c.speed_mps,
          &c.reported_velocity_mps.x,
          &c.reported_velocity_mps.y,
          &c.map_frenet.s_m,
          &c.map_frenet.d_m};
}

/// Reads or writes the steps; `prev` holds each car index's bits one step before.
void archive_steps(core::StateArchive& ar, RecordedTraffic& steps, int lanes,
                   std::size_t waypoints) {
  ar.part("recorded traffic");
  const std::size_t n = ar.io_length(steps.size(), kMaxSteps, "steps");
  if (ar.loading()) steps.assign(n, {});
  std::vector<std::array<std::uint64_t, kDoubles>> prev;
  for (std::vector<TrafficCar>& cars : steps) {
    const std::size_t m = ar.io_length(cars.size(), kMaxCars, "cars in a step");
    if (ar.loading()) cars.assign(m, TrafficCar{});
    if (prev.size() < m) prev.resize(m, {});
    for (std::size_t k = 0; k < m; ++k) {
      TrafficCar& c = cars[k];
      ar.io_range(c.id, 0, 65535, "car id");
      ar.io_range(c.lane, 0, lanes - 1, "car lane");
      ar.io(c.parked, "car parked");
      ar.io_range(c.closest_waypoint, 0, waypoints == 0 ? 0 : waypoints - 1, "car waypoint");
      // Positions and s, d within any run's reach; heading, speed and velocity bounded too.
      static constexpr std::array<double, kDoubles> kLimit = {
          core::StateArchive::kMaxMetres, core::StateArchive::kMaxMetres,
          core::StateArchive::kMaxValue,  core::StateArchive::kMaxSpeed,
          core::StateArchive::kMaxSpeed,  core::StateArchive::kMaxSpeed,
          core::StateArchive::kMaxMetres, core::StateArchive::kMaxMetres};
      for (std::size_t f = 0; f < kDoubles; ++f) {
        double* v = doubles_of(c)[f];
        ar.io_delta(*v, prev[k][f], "car value", kLimit[f]);
        ar.require(std::isfinite(*v), "car value: not finite");
      }
    }
  }
}

}  // namespace

std::string encode_recorded_traffic(const RecordedTraffic& steps) {
  core::StateArchive ar;
  RecordedTraffic copy = steps;
  archive_steps(ar, copy, 1 << 30, std::size_t{1} << 62U);
  return ar.take();
}

RecordedTraffic decode_recorded_traffic(std::string_view bytes, std::string_view name, int lanes,
                                        std::size_t waypoints) {
  core::StateArchive ar(bytes, std::string(name));
  RecordedTraffic steps;
  archive_steps(ar, steps, lanes, waypoints);
  ar.expect_end();
  return steps;
}

}  // namespace overtake::sim
