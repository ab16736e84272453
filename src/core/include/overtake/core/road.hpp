#pragma once
// The road's lane layout (lanes numbered from the divider outward, each `lane_width_m` wide)
// and the cars' footprint: facts every module shares, each given once in the config.

#include <algorithm>
#include <cmath>

namespace overtake::core {

/// Lane layout of the highway.
struct RoadParams {
  int lane_count = 3;
  double lane_width_m = 4.0;
  friend bool operator==(const RoadParams&, const RoadParams&) = default;
};

/// (ours) The footprint of every car, the ego's included: the original's collider size is a
/// scene setting.
struct CarFootprint {
  double length_m = 4.7;
  double width_m = 1.9;
  friend bool operator==(const CarFootprint&, const CarFootprint&) = default;
};

/// The road's width: d of its outer edge (the divider is at d = 0).
[[nodiscard]] constexpr double road_width_m(const RoadParams& road = {}) {
  return road.lane_count * road.lane_width_m;
}

/// Centre of lane `lane` (d, metres).
[[nodiscard]] constexpr double lane_center_d(int lane, const RoadParams& road = {}) {
  return road.lane_width_m * (lane + 0.5);
}

/// The lane that `d_m` lies in, clamped to the road's lanes.
[[nodiscard]] inline int lane_of(double d_m, const RoadParams& road = {}) {
  const int lane = static_cast<int>(std::floor(d_m / road.lane_width_m));
  return std::clamp(lane, 0, road.lane_count - 1);
}

}  // namespace overtake::core
