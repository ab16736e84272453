#include "overtake/learn/observation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace overtake::learn {

namespace {

float clamped(double x, double lo, double hi) {
  return static_cast<float>(std::clamp(x, lo, hi));
}

// The signed distance along the loop from `from` to `to`, in [-L/2, L/2).
double loop_delta(double from, double to, double loop_length_m) {
  if (!(loop_length_m > 0.0)) return to - from;
  double d = std::fmod(to - from, loop_length_m);
  if (d < -loop_length_m / 2) d += loop_length_m;
  if (d >= loop_length_m / 2) d -= loop_length_m;
  return d;
}

struct Nearest {
  double gap_m = std::numeric_limits<double>::infinity();
  const core::CarObservation* car = nullptr;
};

}  // namespace

void observe(const core::Telemetry& t, const EgoContext& ego, const core::RoadParams& road,
             double loop_length_m, double car_length_m, const ObservationParams& p,
             std::span<float> out) {
  const int lanes = road.lane_count;
  if (lanes < 1 || lanes > static_cast<int>(kMaxLanes)) {
    throw std::invalid_argument("observe: a road of " + std::to_string(lanes) + " lanes (1 to " +
                                std::to_string(kMaxLanes) + " are observed)");
  }
  if (out.size() != observation_size(lanes)) {
    throw std::invalid_argument("observe: the output holds " + std::to_string(out.size()) +
                                " floats, not " + std::to_string(observation_size(lanes)));
  }
  const double half_lane = road.lane_width_m / 2.0;
  const int lane = std::clamp(core::lane_of(t.ego.d_m, road), 0, lanes - 1);
  const double v = t.ego.speed_mps;
  out[0] = clamped(v / p.speed_scale_mps, 0.0, 2.0);
  out[1] = clamped((t.ego.d_m - core::lane_center_d(lane, road)) / half_lane, -2.0, 2.0);
  out[2] = lanes > 1 ? static_cast<float>(lane) / static_cast<float>(lanes - 1) : 0.0F;
  out[3] = clamped(ego.accel_mps2 / p.accel_scale_mps2, -1.0, 1.0);
  out[4] = clamped(ego.manoeuvre_s / p.time_scale_s, 0.0, 1.0);
  out[5] = clamped(ego.target_speed_mps / p.speed_scale_mps, 0.0, 2.0);
  out[6] = clamped(ego.target_lane - lane, -1.0, 1.0);
  // The nearest car ahead and behind in each lane, bumper to bumper, within range.
  std::array<Nearest, kMaxLanes> ahead{};
  std::array<Nearest, kMaxLanes> behind{};
  for (const core::CarObservation& c : t.cars) {
    const int l = core::lane_of(c.d_m, road);
    if (l < 0 || l >= lanes) continue;
    const double ds = loop_delta(t.ego.s_m, c.s_m, loop_length_m);
    const double gap = std::max(0.0, std::abs(ds) - car_length_m);
    if (gap > p.range_m) continue;
    Nearest& n =
        ds >= 0.0 ? ahead[static_cast<std::size_t>(l)] : behind[static_cast<std::size_t>(l)];
    if (gap < n.gap_m) n = {gap, &c};
  }
  std::size_t at = kEgoFeatures;
  for (int l = 0; l < lanes; ++l) {
    for (const Nearest* n :
         {&ahead[static_cast<std::size_t>(l)], &behind[static_cast<std::size_t>(l)]}) {
      if (n->car == nullptr) {
        for (std::size_t k = 0; k < kSlotFeatures; ++k) out[at + k] = 0.0F;
      } else {
        const double speed = std::hypot(n->car->velocity_mps.x, n->car->velocity_mps.y);
        out[at] = 1.0F;
        out[at + 1] = clamped(n->gap_m / p.range_m, 0.0, 1.0);
        out[at + 2] = clamped((speed - v) / p.speed_scale_mps, -1.0, 1.0);
        out[at + 3] = clamped((n->car->d_m - core::lane_center_d(l, road)) / half_lane, -1.0, 1.0);
      }
      at += kSlotFeatures;
    }
  }
}

}  // namespace overtake::learn
