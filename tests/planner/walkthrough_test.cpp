// The walkthrough policy: its speed rule in constructed situations, its path, and a drive.

#include <gtest/gtest.h>

#include <cmath>

#include "overtake/planner/policy.hpp"
#include "overtake/planner/walkthrough.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/world.hpp"
#include "sim/test_maps.hpp"

namespace overtake::planner {
namespace {

class WalkthroughTest : public ::testing::Test {
 protected:
  WalkthroughTest() : map_(test::circle_map()), line_(map_) {}

  // The ego at s = 200 in the middle lane at `speed_mps`, no queued path.
  core::Telemetry at_speed(double speed_mps) const {
    core::Telemetry t;
    const core::RoadFrame f = line_.frame(200.0);
    t.ego = {line_.to_cartesian({200.0, 6.0}), f.heading_rad, speed_mps, 200.0, 6.0};
    return t;
  }
  core::CarObservation car(int id, double s, double d, double speed) const {
    const core::FrenetPoint p{s, d};
    return {id, line_.to_cartesian(p), line_.velocity(p, line_.s_rate(p, speed), 0.0), s, d};
  }

  core::Map map_;
  core::ReferenceLine line_;
  PlannerParams params_;
};

TEST_F(WalkthroughTest, RampsUpByTheStepUntilTheTarget) {
  WalkthroughPolicy p(line_, params_);
  const core::Telemetry t = at_speed(0.0);
  (void)p.plan(t);
  EXPECT_NEAR(p.ref_speed_mps(), core::mph_to_mps(0.224), 1e-12);
  for (int i = 0; i < 400; ++i) (void)p.plan(t);
  EXPECT_GE(p.ref_speed_mps(), core::mph_to_mps(49.5));
  EXPECT_LT(p.ref_speed_mps(), core::mph_to_mps(49.5) + core::mph_to_mps(0.224));
}

TEST_F(WalkthroughTest, SlowsBehindACarCloserThan30mInItsLane) {
  WalkthroughPolicy p(line_, params_);
  core::Telemetry t = at_speed(20.0);
  for (int i = 0; i < 100; ++i) (void)p.plan(t);
  const double before = p.ref_speed_mps();
  t.cars = {car(0, 220.0, 6.2, 15.0)};  // 20 m ahead, same lane
  (void)p.plan(t);
  EXPECT_NEAR(p.ref_speed_mps(), before - core::mph_to_mps(0.224), 1e-12);
  EXPECT_EQ(p.lane(), 1);  // the walkthrough never changes lanes
}

TEST_F(WalkthroughTest, IgnoresCarsInOtherLanesOrFartherAhead) {
  WalkthroughPolicy p(line_, params_);
  core::Telemetry t = at_speed(20.0);
  t.cars = {car(0, 215.0, 2.0, 10.0), car(1, 215.0, 10.0, 10.0), car(2, 240.0, 6.0, 22.0),
            car(3, 190.0, 6.0, 25.0)};
  (void)p.plan(t);
  EXPECT_GT(p.ref_speed_mps(), 0.0);  // sped up: nothing counted as too close
}

TEST_F(WalkthroughTest, PathReusesTheQueueAndSpacesNewPointsForTheSpeed) {
  WalkthroughPolicy p(line_, params_);
  core::Telemetry t = at_speed(0.0);
  for (int i = 0; i < 200; ++i) (void)p.plan(t);
  const double v = p.ref_speed_mps();
  auto path = p.plan(t).path;
  ASSERT_EQ(path.size(), 50u);
  // Hand back 40 of them as the queue: they come first, unchanged.
  t.previous_path.assign(path.begin() + 10, path.end());
  t.end_path = line_.to_frenet(t.previous_path.back());
  const auto next = p.plan(t).path;
  ASSERT_EQ(next.size(), 50u);
  for (std::size_t i = 0; i < 40; ++i) EXPECT_EQ(next[i], t.previous_path[i]);
  for (std::size_t i = 40; i < 50; ++i) {
    EXPECT_NEAR(core::distance(next[i], next[i - 1]), v * 0.02, 0.02 * v * 0.02 + 1e-3);
  }
  // New points stay in the middle lane.
  for (const auto& q : next) EXPECT_NEAR(line_.to_frenet(q).d_m, 6.0, 0.3);
}

TEST_F(WalkthroughTest, DrivesAnEmptyRoadAtJustUnderTheLimitWithoutIncident) {
  sim::WorldParams wp;
  wp.traffic.car_count = 0;
  sim::World world(map_, line_, wp, sim::TrafficProfile::faithful, 1);
  auto policy = make_policy("walkthrough", line_, params_);
  ASSERT_TRUE(policy);
  sim::RunOptions opts;
  opts.duration_s = 120.0;
  const auto r = sim::run_drive(
      world, [&](const core::Telemetry& t) { return policy->plan(t); }, opts);
  EXPECT_TRUE(r.incidents.empty());
  EXPECT_LT(core::mps_to_mph(r.peak.speed_mps), 50.0);
  EXPECT_GT(core::mps_to_mph(r.peak.speed_mps), 49.0);
  EXPECT_GT(core::mps_to_mph(r.mean_speed_mps), 44.0);  // includes the ramp from rest
  EXPECT_LT(r.peak.acceleration_mps2, 10.0);
  EXPECT_EQ(r.lane_changes, 0);
}

TEST(PolicyRegistry, ListsAndMakesEveryPolicy) {
  const core::Map map = test::circle_map();
  const core::ReferenceLine line(map);
  const auto policies = list_policies();
  ASSERT_FALSE(policies.empty());
  for (const auto& info : policies) {
    EXPECT_TRUE(make_policy(info.name, line, PlannerParams{})) << info.name;
    EXPECT_FALSE(info.summary.empty());
  }
  EXPECT_EQ(make_policy("no-such-policy", line, PlannerParams{}), nullptr);
}

TEST(PolicyRegistry, OneRefusalForAnUnknownNameInEveryLayer) {
  const std::string text = unknown_policy_text("nope");
  EXPECT_EQ(text.rfind("unknown policy 'nope' (available: reference, walkthrough, ", 0), 0U)
      << text;
  for (const auto& info : list_policies()) EXPECT_NE(text.find(info.name), std::string::npos);
  EXPECT_EQ(unknown_policy_text("x", "a, b"), "unknown policy 'x' (available: a, b)");
}

}  // namespace
}  // namespace overtake::planner
