// Each seed policy's decision rule in a constructed situation, asserting the lane and speed
// decision its write-up describes.

#include <gtest/gtest.h>

#include "overtake/core/units.hpp"
#include "overtake/planner/seed_policies.hpp"
#include "sim/test_maps.hpp"

namespace overtake::planner {
namespace {

class SeedPolicyTest : public ::testing::Test {
 protected:
  SeedPolicyTest() : map_(test::circle_map()), line_(map_) {}

  // Ego at s = 500 in `lane`, at `speed_mps`, no queued path.
  core::Telemetry ego(int lane, double speed_mps) const {
    core::Telemetry t;
    const double d = core::lane_center_d(lane);
    t.ego = {line_.to_cartesian({500.0, d}), line_.frame(500.0).heading_rad, speed_mps, 500.0, d};
    return t;
  }
  core::CarObservation car(int id, double gap_m, int lane, double speed_mps) const {
    const core::FrenetPoint p{500.0 + gap_m, core::lane_center_d(lane)};
    return {id, line_.to_cartesian(p), line_.velocity(p, line_.s_rate(p, speed_mps), 0.0),
            line_.wrap_s(p.s_m), p.d_m};
  }
  // Runs `cycles` plans of `policy` on `t` (a fresh telemetry each time).
  template <class P>
  void run(P& policy, const core::Telemetry& t, int cycles) {
    for (int i = 0; i < cycles; ++i) (void)policy.plan(t);
  }
  // Brings a policy's reference speed up to about `mph` on an empty road.
  template <class P>
  void warm_up(P& policy, int lane, double mph) {
    const core::Telemetry t = ego(lane, core::mph_to_mps(mph));
    while (policy.ref_speed_mps() < core::mph_to_mps(mph)) (void)policy.plan(t);
  }

  core::Map map_;
  core::ReferenceLine line_;
  PlannerParams params_;
};

TEST_F(SeedPolicyTest, Seed000PrefersAnEmptyLaneFromTheMiddle) {
  Seed000Policy p(line_, params_);
  warm_up(p, 1, 40.0);
  core::Telemetry t = ego(1, core::mph_to_mps(40.0));
  t.cars = {car(0, 20.0, 1, 15.0), car(1, 50.0, 0, 20.0)};  // slow car ahead; left lane busy
  const double before = p.ref_speed_mps();
  (void)p.plan(t);
  EXPECT_EQ(p.lane(), 2);  // the right lane has no car: preferred
  EXPECT_NEAR(p.ref_speed_mps(), before - params_.walkthrough.speed_step_mps, 1e-12);
}

TEST_F(SeedPolicyTest, Seed000NeedsMoreRoomBehindWhenSlow) {
  Seed000Policy p(line_, params_);
  warm_up(p, 1, 20.0);
  core::Telemetry t = ego(1, core::mph_to_mps(20.0));
  // At 20 mph the minimum gap behind is 20 x 49.5 / 20 = 49.5 m: a car 40 m behind blocks.
  t.cars = {car(0, 20.0, 1, 5.0), car(1, -40.0, 0, 20.0), car(2, -40.0, 2, 20.0)};
  (void)p.plan(t);
  EXPECT_EQ(p.lane(), 1);
  t.cars = {car(0, 20.0, 1, 5.0), car(1, -60.0, 0, 20.0), car(2, -40.0, 2, 20.0)};
  (void)p.plan(t);
  EXPECT_EQ(p.lane(), 0);
}

TEST_F(SeedPolicyTest, Seed001ChangesLaneOnlyAfter40CyclesOfSlowing) {
  Seed001Policy p(line_, params_);
  warm_up(p, 1, 45.0);
  core::Telemetry t = ego(1, core::mph_to_mps(45.0));
  t.cars = {car(0, 20.0, 1, 15.0), car(1, 36.0, 0, 20.0)};  // left lane clear beyond 35 m
  run(p, t, 40);
  EXPECT_EQ(p.lane(), 1);
  EXPECT_EQ(p.patience(), 40);
  (void)p.plan(t);
  EXPECT_EQ(p.lane(), 0);  // 41st cycle: left first
  EXPECT_EQ(p.patience(), 0);
}

TEST_F(SeedPolicyTest, Seed001Needs35mFrontAndRear) {
  Seed001Policy p(line_, params_);
  warm_up(p, 1, 45.0);
  core::Telemetry t = ego(1, core::mph_to_mps(45.0));
  t.cars = {car(0, 20.0, 1, 15.0), car(1, -30.0, 0, 20.0), car(2, 30.0, 2, 20.0)};
  run(p, t, 60);
  EXPECT_EQ(p.lane(), 1);  // both sides have a car within 35 m
}

TEST_F(SeedPolicyTest, Seed002UsesProximity30AheadAnd5Behind) {
  Seed002Policy p(line_, params_);
  warm_up(p, 1, 45.0);
  core::Telemetry t = ego(1, core::mph_to_mps(45.0));
  t.cars = {car(0, 20.0, 1, 15.0), car(1, 25.0, 0, 20.0), car(2, -6.0, 2, 20.0)};
  (void)p.plan(t);
  EXPECT_EQ(p.lane(), 2);  // left has a car 25 m ahead; right's car is 6 m behind: free
  const auto path = p.plan(ego(2, core::mph_to_mps(45.0))).path;
  EXPECT_EQ(path.size(), 80u);
}

TEST_F(SeedPolicyTest, Seed002SlowsAndStaysWhenBothSidesAreInProximity) {
  Seed002Policy p(line_, params_);
  warm_up(p, 1, 45.0);
  core::Telemetry t = ego(1, core::mph_to_mps(45.0));
  t.cars = {car(0, 20.0, 1, 15.0), car(1, 10.0, 0, 20.0), car(2, -3.0, 2, 20.0)};
  const double before = p.ref_speed_mps();
  (void)p.plan(t);
  EXPECT_EQ(p.lane(), 1);
  EXPECT_LT(p.ref_speed_mps(), before);
}

TEST_F(SeedPolicyTest, Seed003PicksTheSideWithTheFasterSlowestCarAndAcceleratesStrongly) {
  Seed003Policy p(line_, params_);
  warm_up(p, 1, 40.0);
  core::Telemetry t = ego(1, core::mph_to_mps(40.0));
  // Both sides safe (cars beyond 30 m ahead); the left lane's slowest car is slower.
  t.cars = {car(0, 20.0, 1, 15.0), car(1, 60.0, 0, 12.0), car(2, 60.0, 2, 18.0)};
  (void)p.plan(t);
  EXPECT_EQ(p.lane(), 2);
  EXPECT_TRUE(p.strong_acceleration());
  const double before = p.ref_speed_mps();
  (void)p.plan(ego(2, core::mph_to_mps(40.0)));
  EXPECT_NEAR(p.ref_speed_mps() - before, core::mph_to_mps(0.424), 1e-12);
}

TEST_F(SeedPolicyTest, Seed003FollowsAtTheTargetSpeedWhenBoxedIn) {
  Seed003Policy p(line_, params_);
  warm_up(p, 1, 45.0);
  core::Telemetry t = ego(1, core::mph_to_mps(45.0));
  t.cars = {car(0, 20.0, 1, 15.0), car(1, 10.0, 0, 20.0), car(2, -3.0, 2, 20.0)};
  run(p, t, 300);
  EXPECT_EQ(p.lane(), 1);
  EXPECT_NEAR(p.ref_speed_mps(), 15.0, 1e-9);  // the car ahead's speed
  EXPECT_FALSE(p.strong_acceleration());
}

TEST_F(SeedPolicyTest, Seed003ReturnsToTheMiddleLaneAtSpeed) {
  Seed003Policy p(line_, params_);
  warm_up(p, 0, 49.5);
  (void)p.plan(ego(0, core::mph_to_mps(49.5)));
  EXPECT_EQ(p.lane(), 1);
}

TEST_F(SeedPolicyTest, Seed004TriesRightFirstWith20AheadAnd10Behind) {
  Seed004Policy p(line_, params_);
  warm_up(p, 1, 45.0);
  core::Telemetry t = ego(1, core::mph_to_mps(45.0));
  t.cars = {car(0, 20.0, 1, 15.0), car(1, 40.0, 0, 20.0), car(2, 40.0, 2, 20.0)};
  (void)p.plan(t);
  EXPECT_EQ(p.lane(), 2);
  // A lane change takes the first anchor 45 m ahead: the path still has 50 points.
  EXPECT_EQ(p.plan(t).path.size(), 50u);
}

TEST_F(SeedPolicyTest, Seed004LaneFreeRules) {
  Seed004Policy p(line_, params_);
  core::Telemetry t = ego(1, 20.0);
  t.cars = {car(0, 15.0, 2, 20.0)};
  EXPECT_FALSE(p.lane_free(t, 2, 500.0));  // within 20 m ahead
  t.cars = {car(0, -8.0, 2, 20.0)};
  EXPECT_FALSE(p.lane_free(t, 2, 500.0));  // within 10 m behind
  t.cars = {car(0, -15.0, 2, 20.0)};
  // 10-20 m behind and "faster": the write-up compares mph (44.7) with m/s (20): not faster.
  EXPECT_TRUE(p.lane_free(t, 2, 500.0));
  t.cars = {car(0, -15.0, 2, 50.0)};
  EXPECT_FALSE(p.lane_free(t, 2, 500.0));
  t.cars = {car(0, 25.0, 2, 20.0), car(1, -25.0, 2, 30.0)};
  EXPECT_TRUE(p.lane_free(t, 2, 500.0));
}

TEST_F(SeedPolicyTest, Seed004MatchesSpeedByAThirtiethPerCycle) {
  Seed004Policy p(line_, params_);
  warm_up(p, 1, 45.0);
  const double before = p.ref_speed_mps();
  core::Telemetry t = ego(1, core::mph_to_mps(45.0));
  // A slow car 20 m ahead, and both neighbouring lanes busy within 20 m: no lane change.
  t.cars = {car(0, 20.0, 1, 15.0), car(1, 5.0, 0, 20.0), car(2, 5.0, 2, 20.0)};
  (void)p.plan(t);
  // ref_vel -= (ref_vel - 15) / 30 with ref_vel in mph and 15 m/s read as 15 mph.
  const double expected = before - (before - core::mph_to_mps(15.0)) / 30.0;
  EXPECT_NEAR(p.ref_speed_mps(), expected, 1e-9);
  EXPECT_EQ(p.lane(), 1);
}

}  // namespace
}  // namespace overtake::planner
