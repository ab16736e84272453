#pragma once
// The ego's path queue and the original's rule for taking a new path.

#include <span>
#include <vector>

#include "overtake/core/geometry.hpp"

namespace overtake::sim {

/// The part of `path` that replaces the ego's queue when the car stands at `car`:
/// find the point nearest to the car; if it is not the first, drop it and every point
/// before it; if it is the first, drop it only when the car stands on it (within
/// `stand_on_tolerance_m`). Ties go to the earliest point.
[[nodiscard]] std::vector<core::Vec2> trim_new_path(std::span<const core::Vec2> path,
                                                    core::Vec2 car, double stand_on_tolerance_m);

}  // namespace overtake::sim
