#pragma once
// How near the ego is to touching a car: the importance score of rare-event estimation
// (`overtake risk`, docs/evaluation.md, "Rare events"). It is the evaluator's, computed from the
// world's exact bodies, never shown to a planner.
//
// For each car on the road, the two bodies' separation along the road and across it (bumper
// to bumper and side to side, on the waypoint chords as the safety monitor measures them) is
// carried forward at their present velocities for up to `horizon_s`; the bodies touch when
// both gaps reach 0 (the separating axis). The margin is the least, over the cars and over that
// time, of the larger of the two gaps (the gap across weighted by `lateral_weight`, since lanes
// are closer side by side than cars are in line) plus `time_weight_mps` times how far ahead it
// is: a contact now is 0, one predicted 1 s ahead at constant velocity `time_weight_mps` metres.

#include <cstddef>
#include <optional>

#include "overtake/core/road.hpp"

namespace overtake::sim {

class World;

/// The score's parameters (risk's config: `score`).
struct ProximityParams {
  double horizon_s = 3.0;        ///< how far ahead the bodies are carried forward
  double time_weight_mps = 3.0;  ///< a predicted contact this many metres per second ahead
  double lateral_weight = 2.0;   ///< the gap across the road counts this many times
  double range_m = 120.0;        ///< cars farther along the road than this are not looked at
  friend bool operator==(const ProximityParams&, const ProximityParams&) = default;
};

/// One car relative to the ego, on the waypoint chords: the car's s and d minus the ego's
/// (s wrapped to the nearer way round the loop), and its velocity along and across the road
/// minus the ego's.
struct RelativeMotion {
  double ds_m = 0.0;
  double dd_m = 0.0;
  double dvs_mps = 0.0;
  double dvd_mps = 0.0;
};

/// The margin of one car (metres; at most 0 when the bodies touch now): the least over t in
/// [0, horizon_s] of max(|ds + dvs t| - length, lateral_weight (|dd + dvd t| - width)) +
/// time_weight_mps t. The function is convex in t, so its least value is at an end or where
/// two of its linear pieces meet; all are tried.
[[nodiscard]] double predicted_margin_m(const RelativeMotion& rel, const core::CarFootprint& car,
                                        const ProximityParams& params);

/// The least margin over the cars on the road, and which car it is (none: no car within
/// range_m, the margin then infinite).
struct Proximity {
  double margin_m = 0.0;
  std::optional<std::size_t> car;
};
[[nodiscard]] Proximity proximity(const World& world, const ProximityParams& params);

}  // namespace overtake::sim
