// Behaviour: RSS and follower gaps, lane costs and the lane choice in constructed situations.

#include <gtest/gtest.h>

#include <cmath>

#include "overtake/core/units.hpp"
#include "overtake/planner/reference/behaviour.hpp"
#include "planner/reference_support.hpp"

namespace overtake::planner::reference {
namespace {

constexpr double kLength = 4.7;
constexpr double kCruise = 22.1;

class BehaviourTest : public ::testing::Test {
 protected:
  /// The ego in `lane` at s = 1000, at cruise speed.
  [[nodiscard]] static EgoSnapshot ego_in(int lane, double speed_mps = kCruise) {
    return {1000.0, speed_mps, core::lane_center_d(lane), 1.0};
  }
  /// Decides `cycles` times on the same scene (0.04 s apart); returns the last decision.
  BehaviourDecision run(const std::vector<CarPrediction>& cars, const EgoSnapshot& ego,
                        int cycles = 1) {
    BehaviourDecision d;
    for (int i = 0; i < cycles; ++i) d = decide(cars, ego, state_, 0.04, kLength, params_, road_);
    return d;
  }
  ReferenceBehaviourParams params_;
  core::RoadParams road_;
  BehaviourState state_;
};

TEST(SafetyGaps, JerkLimitedStopDistanceMatchesAStepByStepStop) {
  for (const double v : {1.0, 5.0, 22.0}) {
    double x = 0.0, speed = v, a = 0.0;
    const double dt = 1e-4;
    while (speed > 0.0) {
      a = std::max(a - 7.0 * dt, -5.0);
      x += speed * dt;
      speed += a * dt;
    }
    EXPECT_NEAR(jerk_limited_stop_distance(v, 5.0, 7.0), x, 0.01 * x + 1e-3) << v;
  }
  EXPECT_EQ(jerk_limited_stop_distance(0.0, 5.0, 7.0), 0.0);
}

TEST(SafetyGaps, RssGapGrowsWithTheSpeedDifference) {
  const ReferenceBehaviourParams p;
  const double same = rss_front_gap(20.0, 20.0, p);
  EXPECT_GT(rss_front_gap(20.0, 15.0, p), same);
  EXPECT_LT(rss_front_gap(20.0, 25.0, p), same);
  EXPECT_GT(rss_front_gap(22.0, 20.0, p), rss_front_gap(20.0, 20.0, p));
  EXPECT_EQ(rss_front_gap(5.0, 30.0, p), p.min_gap_m);
  // Equal speeds: the response distance plus the cost of ramping the brakes up to less than
  // the leader's braking: more than the response distance, and with the defaults 0.7 s of
  // headway at highway speed.
  EXPECT_GT(same, 20.0 * p.response_time_s + 5.0);
  EXPECT_GT(same, 0.7 * 20.0);
}

TEST(SafetyGaps, AFollowerClosingFastHasNoRoomEvenFromFarBehind) {
  const ReferenceBehaviourParams p;
  EXPECT_GT(rear_room(30.0, 2.0, kLength, p), 0.0);  // reacts in time
  EXPECT_LT(rear_room(60.0, 9.0, kLength, p), 0.0);  // reacts only at 10 m: too late
  EXPECT_LT(rear_room(5.5, -1.0, kLength, p), 0.0);  // slower, but already too close
  EXPECT_GT(rear_room(8.0, -1.0, kLength, p), 0.0);
}

TEST_F(BehaviourTest, ASlowLeaderSendsTheEgoToAFreeNextLane) {
  const std::vector<CarPrediction> cars = {test::lane_car(0, 1040.0, 6.0, 16.0)};
  const BehaviourDecision d = run(cars, ego_in(1), 60);
  EXPECT_NE(d.target_lane, 1);
  EXPECT_LT(d.lanes[0].cost, d.lanes[1].cost);
  EXPECT_LT(d.lanes[2].cost, d.lanes[1].cost);
  EXPECT_TRUE(d.lanes[0].enterable);
  EXPECT_TRUE(d.lanes[2].enterable);
}

TEST_F(BehaviourTest, TheMiddleLaneIsUsedToReachAFasterFarLane) {
  // Ego in lane 0 behind a slow car; lane 1 has a slow car far enough ahead to enter, lane 2
  // is free.
  const std::vector<CarPrediction> cars = {test::lane_car(0, 1035.0, 2.0, 15.0),
                                           test::lane_car(1, 1060.0, 6.0, 15.5)};
  const BehaviourDecision d = run(cars, ego_in(0), 60);
  EXPECT_LT(d.lanes[2].cost, d.lanes[1].cost);
  EXPECT_EQ(d.goal_lane, 2);
  EXPECT_EQ(d.target_lane, 1);
}

TEST_F(BehaviourTest, EquallyBlockedLanesAreNotWorthAChange) {
  std::vector<CarPrediction> cars;
  for (int l = 0; l < 3; ++l)
    cars.push_back(test::lane_car(l, 1030.0, core::lane_center_d(l), 15.0));
  for (int i = 0; i < 200; ++i) {
    const BehaviourDecision d = run(cars, ego_in(1, 15.0));
    EXPECT_EQ(d.target_lane, 1);
  }
}

TEST_F(BehaviourTest, HysteresisKeepsTheLaneForATinyGain) {
  // The next lane is only slightly faster than our own.
  const std::vector<CarPrediction> cars = {test::lane_car(0, 1030.0, 6.0, 20.0),
                                           test::lane_car(1, 1030.0, 2.0, 20.1),
                                           test::lane_car(2, 1030.0, 10.0, 20.1)};
  EXPECT_EQ(run(cars, ego_in(1, 20.0), 100).target_lane, 1);
}

TEST_F(BehaviourTest, ACarAlongsideOrClosingFastBehindClosesTheLane) {
  const std::vector<CarPrediction> cars = {
      test::lane_car(0, 1030.0, 6.0, 14.0),   // slow leader
      test::lane_car(1, 1002.0, 2.0, 22.0),   // alongside in lane 0
      test::lane_car(2, 950.0, 10.0, 31.0)};  // lane 2: closing at 9 m/s from 50 m
  const BehaviourDecision d = run(cars, ego_in(1), 60);
  EXPECT_TRUE(d.lanes[0].alongside);
  EXPECT_FALSE(d.lanes[0].enterable);
  EXPECT_FALSE(d.lanes[2].enterable);
  EXPECT_EQ(d.target_lane, 1);
}

TEST_F(BehaviourTest, ACarClosingFastBehindMakesTheOwnLaneCostly) {
  const std::vector<CarPrediction> cars = {test::lane_car(0, 960.0, 6.0, 30.0)};
  const BehaviourDecision d = run(cars, ego_in(1, 18.0));
  EXPECT_GT(d.lanes[1].rear_threat, 0.5);
  EXPECT_GT(d.lanes[1].cost, d.lanes[0].cost);
}

TEST_F(BehaviourTest, ACutInIsCountedInTheLaneItEnters) {
  // A car in lane 0 drifting into lane 1, 25 m ahead: lane 1's leader.
  const std::vector<CarPrediction> cars = {test::lane_car(0, 1030.0, 2.4, 17.9, 0.9)};
  const BehaviourDecision d = run(cars, ego_in(1));
  EXPECT_EQ(d.lanes[1].leader, 0);
  EXPECT_LT(d.lanes[1].expected_speed_mps, kCruise);
}

TEST_F(BehaviourTest, NoLaneChangesAtACrawl) {
  const std::vector<CarPrediction> cars = {test::lane_car(0, 1010.0, 6.0, 2.0)};
  const BehaviourDecision d = run(cars, ego_in(1, 3.0), 60);
  EXPECT_FALSE(d.lanes[0].enterable);
  EXPECT_EQ(d.target_lane, 1);
}

TEST_F(BehaviourTest, PassingAHeldUpQueueIsSpeedCapped) {
  // Lane 0: a queue at 5 m/s just ahead (it may cut in); the ego's lane is free.
  const std::vector<CarPrediction> cars = {test::lane_car(0, 1030.0, 2.0, 5.0),
                                           test::lane_car(1, 1045.0, 2.0, 5.0)};
  const BehaviourDecision d = run(cars, ego_in(1));
  EXPECT_NEAR(d.speed_mps, 5.0 + params_.passing_speed_mps, 1e-9);
}

TEST_F(BehaviourTest, ANextLaneIsEnterableWithAShareOfTheRssGapAhead) {
  // Lane 0's leader between the change's share of the RSS gap and the full gap.
  const double rss = rss_front_gap(kCruise, 15.0, params_);
  const std::vector<CarPrediction> cars = {
      test::lane_car(0, 1000.0 + kLength + 0.75 * rss, 2.0, 15.0)};
  const BehaviourDecision d = run(cars, ego_in(1));
  EXPECT_NEAR(d.lanes[0].entry_rss_gap_m, rss, 1e-9);
  EXPECT_TRUE(d.lanes[0].rear_ok);
  EXPECT_TRUE(d.lanes[0].enterable);
  EXPECT_EQ(d.lanes[2].entry_rss_gap_m, 0.0);  // no leader
  EXPECT_TRUE(d.lanes[2].enterable);
}

/// The ego in the right lane behind a car at its own speed, a car pacing it just ahead in the
/// middle lane (too close to enter behind or pass through) and the left lane free.
class BoxedInTest : public BehaviourTest {
 protected:
  static constexpr double kPace = 18.0;
  [[nodiscard]] static std::vector<CarPrediction> scene(double middle_gap_m) {
    return {test::lane_car(0, 1000.0 + kLength + 20.0, 10.0, kPace),
            test::lane_car(1, 1000.0 + kLength + middle_gap_m, 6.0, kPace)};
  }
};

TEST_F(BoxedInTest, TheEgoDropsBackBehindTheCarPacingIt) {
  const BehaviourDecision d = run(scene(3.0), ego_in(2, kPace));
  EXPECT_EQ(d.goal_lane, 2);  // no change now: the middle lane has no room
  EXPECT_FALSE(d.lanes[1].passable);
  EXPECT_NEAR(d.speed_mps, kPace - params_.gap_seek_drop_mps, 1e-9);
}

TEST_F(BoxedInTest, NoDropWithoutGapSeekingOrWithRoomToEnter) {
  ReferenceBehaviourParams off = params_;
  off.gap_seek_gain = 0.0;
  BehaviourState state;
  EXPECT_NEAR(decide(scene(3.0), ego_in(2, kPace), state, 0.04, kLength, off, road_).speed_mps,
              params_.cruise_speed_mps, 1e-9);
  // Enough room ahead in the middle lane: the ego changes lanes instead.
  BehaviourState fresh;
  const double room = rss_front_gap(kPace, kPace, params_) + 1.0;
  const BehaviourDecision d =
      decide(scene(room), ego_in(2, kPace), fresh, 0.04, kLength, params_, road_);
  EXPECT_TRUE(d.lanes[1].enterable);
  EXPECT_NEAR(d.speed_mps, params_.cruise_speed_mps, 1e-9);
}

}  // namespace
}  // namespace overtake::planner::reference
