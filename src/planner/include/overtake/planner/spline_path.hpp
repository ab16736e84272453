#pragma once
// The path construction the walkthrough and the seed planners share: keep the queued
// points, add a smooth spline through anchors ahead in the target lane, and space new points
// so that the car drives at the reference speed.

#include <vector>

#include "overtake/core/reference_line.hpp"
#include "overtake/core/telemetry.hpp"

namespace overtake::planner {

/// What to build.
struct SplinePathSpec {
  double target_d_m = 6.0;                 ///< lateral position the anchors lie on
  double ref_speed_mps = 0.0;              ///< spacing of the new points
  std::vector<double> anchor_distances_m;  ///< ahead of the end of the queued path, along s
  int path_points = 50;                    ///< queued + new points
  double horizon_x_m = 30.0;               ///< points are spaced by this much of the spline
  double step_s = 0.0;                     ///< time between points: the world's step (required)
};

/// The queued path followed by new points on a natural cubic spline through two points
/// that continue the queued path's heading and the anchors. When the anchors cannot be
/// fitted (they do not advance in the car's frame), or the speed or step is not positive, returns
/// the queued path unchanged.
[[nodiscard]] std::vector<core::Vec2> spline_path(const core::Telemetry& telemetry,
                                                  const core::ReferenceLine& line,
                                                  const SplinePathSpec& spec);

}  // namespace overtake::planner
