#pragma once
// What an agent's action asks of the executor (the reference planner's trajectory layer): the
// lane and speed it drives toward, moved by a meta-action or set by a continuous one. One
// rule for the environment and for a learned policy driving as a planner.

#include <cstdint>

#include "overtake/learn/observation.hpp"

namespace overtake::learn {

/// A meta-action (0 keep, 1 left, 2 right, 3 faster, 4 slower) on the targets: left and right
/// by one lane within the road's `lanes`, faster and slower by `speed_step_mps` within
/// [0, `cruise_mps`]. An action out of 0..4 changes nothing (the callers refuse it first).
void apply_meta(EgoContext& ego, std::int64_t action, int lanes, double cruise_mps,
                double speed_step_mps);

/// A continuous action on the targets: `speed` in [0, 1] of `cruise_mps`, `lane` in [-1, 1]
/// across the road (-1 the left lane, 1 the right, rounded to a lane).
void apply_continuous(EgoContext& ego, float speed, float lane, int lanes, double cruise_mps);

}  // namespace overtake::learn
