#pragma once
// The agent's observation: a fixed layout of float32, about [-1, 1], read from the telemetry a
// planner is told (so that a policy learned on it drives from any planner's seat), and the
// little the environment remembers between decisions (docs/learning.md, "Observation").

#include <cstddef>
#include <span>

#include "overtake/core/road.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/learn/params.hpp"

namespace overtake::learn {

/// The ego's features, first: speed, offset from its lane's centre, lane, acceleration, time
/// in the current manoeuvre, the target speed, and the target lane relative to its lane.
inline constexpr std::size_t kEgoFeatures = 7;
/// Each slot (a lane's nearest car ahead, then behind; lane 0 first): present (1 or 0), gap,
/// speed relative to the ego's, offset from that lane's centre. An absent car's are all 0.
inline constexpr std::size_t kSlotFeatures = 4;

/// The most lanes a road may have to be observed.
inline constexpr std::size_t kMaxLanes = 8;

/// The number of floats of one observation on a road of `lanes` lanes (31 for 3).
[[nodiscard]] constexpr std::size_t observation_size(int lanes) {
  return kEgoFeatures + static_cast<std::size_t>(lanes) * 2 * kSlotFeatures;
}

/// What the observation needs besides the telemetry: the agent's targets and its memory.
struct EgoContext {
  int target_lane = 1;
  double target_speed_mps = 0.0;
  double accel_mps2 = 0.0;   ///< the ego's speed change over the last decision, per second
  double manoeuvre_s = 0.0;  ///< time since the target lane last changed
};

/// Writes the observation of `t` into `out` (observation_size(road.lane_count) floats).
/// `loop_length_m` wraps s; `car_length_m` turns centre distances into gaps.
void observe(const core::Telemetry& t, const EgoContext& ego, const core::RoadParams& road,
             double loop_length_m, double car_length_m, const ObservationParams& p,
             std::span<float> out);

}  // namespace overtake::learn
