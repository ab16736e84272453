#pragma once
// The world's fixed step: the simulator advances by it, the planners space their path points
// by it (one point is driven per step).

namespace overtake::core {

/// The original simulator's step (50 Hz): the default of the one config key, world.step_s,
/// that the world and the planners both take their step from.
inline constexpr double kDefaultStepS = 0.02;

}  // namespace overtake::core
