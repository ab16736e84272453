#pragma once
// The "walkthrough" policy the seed planners start from: keep the lane, raise the reference
// speed by a fixed step per cycle up to just under the limit, lower it while a car ahead in
// the lane is closer than a threshold (its position projected to the end of the queued
// path), and drive a spline through anchors 30, 60 and 90 m ahead, reusing the queued path.

#include "overtake/core/reference_line.hpp"
#include "overtake/planner/params.hpp"
#include "overtake/planner/policy.hpp"

namespace overtake::planner {

/// True when a car ahead in `lane`, projected `ahead_time_s` forward at its speed, is within
/// `too_close_m` of `from_s_m` along the road.
[[nodiscard]] bool car_too_close(const core::Telemetry& t, const core::ReferenceLine& line,
                                 int lane, double from_s_m, double ahead_time_s, double too_close_m,
                                 const core::RoadParams& road);

/// The walkthrough policy.
class WalkthroughPolicy final : public Policy {
 public:
  WalkthroughPolicy(const core::ReferenceLine& line, const PlannerParams& params);
  [[nodiscard]] core::PlanResult plan(const core::Telemetry& telemetry) override;
  bool archive_state(core::StateArchive& ar) override;
  [[nodiscard]] double ref_speed_mps() const { return ref_speed_mps_; }
  [[nodiscard]] int lane() const { return lane_; }

 private:
  const core::ReferenceLine& line_;
  core::RoadParams road_;
  double step_s_;  // the world's step: new points are this far apart in time
  WalkthroughParams p_;
  int lane_;
  double ref_speed_mps_ = 0.0;
};

}  // namespace overtake::planner
