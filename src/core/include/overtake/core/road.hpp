#pragma once
// The road's lane layout: lanes numbered from the divider outward, each `lane_width_m` wide.

#include <algorithm>
#include <cmath>

namespace overtake::core {

/// Lane layout of the highway.
struct RoadParams {
  int lane_count = 3;
  double lane_width_m = 4.0;
  friend bool operator==(const RoadParams&, const RoadParams&) = default;
};

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
