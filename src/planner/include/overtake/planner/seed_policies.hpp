#pragma once
// The planners of the five seed write-ups, one policy each (seed000 ... seed004),
// so that all are measured on the same roads and traffic. Each keeps the walkthrough's
// trajectory (queued path reused, spline through anchors ahead in the target lane, points
// spaced for the reference speed) and its own decision rules, with its numbers. Where a
// write-up is silent, the walkthrough's behaviour is used; each class says where.

#include <vector>

#include "overtake/core/reference_line.hpp"
#include "overtake/planner/params.hpp"
#include "overtake/planner/policy.hpp"

namespace overtake::planner {

/// Another car as a seed planner sees it, relative to the s it plans from.
struct SeenCar {
  double gap_m = 0.0;      ///< along the road from the planning s; negative: behind
  double speed_mps = 0.0;  ///< |velocity|
  double d_m = 0.0;
};

/// What the seed policies share: lane, reference speed, the walkthrough's numbers and path.
class SeedPolicyBase : public Policy {
 public:
  bool archive_state(core::StateArchive& ar) override;
  [[nodiscard]] int lane() const { return lane_; }
  [[nodiscard]] double ref_speed_mps() const { return ref_speed_mps_; }

 protected:
  SeedPolicyBase(const core::ReferenceLine& line, const PlannerParams& params);
  /// The s the planner reasons from: the end of the queued path, or the car.
  [[nodiscard]] static double planning_s(const core::Telemetry& t);
  /// Every car; with `project`, its s moved forward by its speed over the queued path's time
  /// (as the walkthrough does).
  [[nodiscard]] std::vector<SeenCar> seen_cars(const core::Telemetry& t, bool project) const;
  /// The walkthrough's lane test: d within half a lane of the lane's centre.
  [[nodiscard]] bool in_lane(double d_m, int lane) const;
  /// The walkthrough's "too close": a car in our lane less than too_close_m ahead.
  [[nodiscard]] bool too_close(const std::vector<SeenCar>& cars) const;
  void speed_up(double step_mps);
  void slow_down(double step_mps);
  [[nodiscard]] std::vector<core::Vec2> path(const core::Telemetry& t,
                                             const std::vector<double>& anchors_m,
                                             int points) const;
  [[nodiscard]] std::vector<core::Vec2> path(const core::Telemetry& t) const {
    return path(t, base_.anchor_distances_m, base_.path_points);
  }
  [[nodiscard]] int lane_count() const { return road_.lane_count; }

  const core::ReferenceLine& line_;
  core::RoadParams road_;
  double step_s_;  // the world's step: new points are this far apart in time
  WalkthroughParams base_;
  int lane_;
  double ref_speed_mps_ = 0.0;
};

/// seed000 (write-up 000): nearest gap ahead and behind and the
/// speed ahead per lane; when too close, a lane change needs gaps that grow with speed ahead
/// (10 m x speed/49.5 mph) and shrink with speed behind (20 m x 49.5 mph/speed); from the
/// middle lane a lane with no car ahead is preferred, then the side with more room whose
/// leader is faster or that has 60 m free. Silent in the write-up, walkthrough used: the
/// initial gap of a lane with no car (a large value, `no_car_gap_m`) and, from an outer lane,
/// a middle lane with no car ahead counts as faster.
class Seed000Policy final : public SeedPolicyBase {
 public:
  Seed000Policy(const core::ReferenceLine& line, const PlannerParams& params);
  [[nodiscard]] core::PlanResult plan(const core::Telemetry& t) override;

 private:
  Seed000Params p_;
};

/// seed001 (write-up 001): counts the cycles spent slowing behind a
/// car; after more than 40 it changes lane, left first, if no car is within 35 m ahead or
/// behind in that lane. Silent: the counter is never reset except by a lane change.
class Seed001Policy final : public SeedPolicyBase {
 public:
  Seed001Policy(const core::ReferenceLine& line, const PlannerParams& params);
  [[nodiscard]] core::PlanResult plan(const core::Telemetry& t) override;
  [[nodiscard]] int patience() const { return too_longer_; }
  bool archive_state(core::StateArchive& ar) override;

 private:
  Seed001Params p_;
  int too_longer_ = 0;
};

/// seed002 (write-up 002): a lane is in "proximity" when a car is
/// within 30 m ahead or 5 m behind; when too close it moves to an adjacent lane with no
/// proximity, else slows and stays; 80-point paths. Silent: left is tried before right, and
/// the speed is kept (not lowered) in the cycle that changes lane.
class Seed002Policy final : public SeedPolicyBase {
 public:
  Seed002Policy(const core::ReferenceLine& line, const PlannerParams& params);
  [[nodiscard]] core::PlanResult plan(const core::Telemetry& t) override;

 private:
  Seed002Params p_;
};

/// seed003 (write-up 003): prioritised rules: from the middle lane
/// with both sides safe, the side whose slowest car is faster; else left, else right; else
/// slow to the target speed of the car ahead (and try back to the middle); at speed, return
/// to the middle lane; accelerate by 0.424 mph per cycle after a lane change
/// (allow_strong_acc), else 0.224. Silent: the front safety distance (the too-close 30 m)
/// and when allow_strong_acc clears (when slowing behind a car with no lane change).
class Seed003Policy final : public SeedPolicyBase {
 public:
  Seed003Policy(const core::ReferenceLine& line, const PlannerParams& params);
  [[nodiscard]] core::PlanResult plan(const core::Telemetry& t) override;
  [[nodiscard]] bool strong_acceleration() const { return allow_strong_acc_; }
  bool archive_state(core::StateArchive& ar) override;

 private:
  Seed003Params p_;
  bool allow_strong_acc_ = false;
};

/// seed004 (write-up 004): behind a close car the reference speed
/// moves toward the car's speed by (ref - other)/30 per cycle — with the write-up's units,
/// ref in mph and the other car's speed in m/s; a lane is free when no car is within 20 m
/// ahead or 10 m behind and no faster car is 10-20 m behind (again mph against m/s, as
/// written); right is tried before left; while changing lanes the first anchor is 45 m ahead
/// instead of 30.
class Seed004Policy final : public SeedPolicyBase {
 public:
  Seed004Policy(const core::ReferenceLine& line, const PlannerParams& params);
  [[nodiscard]] core::PlanResult plan(const core::Telemetry& t) override;
  /// The write-up's isLaneFree, on raw (unprojected) sensor s.
  [[nodiscard]] bool lane_free(const core::Telemetry& t, int lane, double my_s_m) const;

 private:
  Seed004Params p_;
};

}  // namespace overtake::planner
