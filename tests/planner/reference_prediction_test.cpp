// Prediction: lanes, speeds along the road, and cut-ins predicted before the line is crossed.

#include <gtest/gtest.h>

#include "overtake/planner/reference/frenet.hpp"
#include "overtake/planner/reference/prediction.hpp"
#include "planner/reference_support.hpp"

namespace overtake::planner::reference {
namespace {

class PredictionTest : public ::testing::Test {
 protected:
  PredictionTest() : map_(overtake::test::circle_map()), line_(map_) {}
  core::Map map_;
  core::ReferenceLine line_;
  ReferencePredictionParams params_;
  core::RoadParams road_;
};

TEST_F(PredictionTest, FrenetOfAMovingCarRoundTrips) {
  const core::CarObservation c = test::observed_car(line_, 0, 500.0, 9.7, 20.0, -0.4);
  const FrenetState x = frenet_from_cartesian(line_, c.position, c.velocity_mps, c.s_m);
  EXPECT_NEAR(x.s_m, 500.0, 1e-6);
  EXPECT_NEAR(x.d_m, 9.7, 1e-6);
  EXPECT_NEAR(x.d_dot_mps, -0.4, 1e-9);
  EXPECT_NEAR(x.s_dot * road_point(line_, x.s_m, x.d_m).along_scale, 20.0, 1e-9);
}

TEST_F(PredictionTest, RoadPointMatchesTheLine) {
  const RoadPoint p = road_point(line_, 1234.0, 10.0);
  const core::Vec2 q = line_.to_cartesian({1234.0, 10.0});
  EXPECT_NEAR(core::distance(p.position, q), 0.0, 1e-9);
  // Along-road scale at d: the distance between two nearby points of constant d per unit s.
  const core::Vec2 q2 = line_.to_cartesian({1234.001, 10.0});
  EXPECT_NEAR(p.along_scale, core::distance(q, q2) / 0.001, 1e-5);
  EXPECT_NEAR(p.curvature_1pm, line_.curvature_at(1234.0, 10.0), 1e-12);
}

TEST_F(PredictionTest, ALaneKeepingCarDrivesOnInItsLane) {
  const CarPrediction c = test::lane_car(3, 100.0, 6.2, 18.0, 0.15);  // wander-like drift
  EXPECT_FALSE(c.changing);
  EXPECT_EQ(c.lane, 1);
  EXPECT_EQ(c.target_lane, 1);
  EXPECT_NEAR(c.s_at(2.0), 136.0, 1e-9);
  EXPECT_NEAR(c.d_at(3.0), 6.2, 1e-12);
}

TEST_F(PredictionTest, ACarDriftingTowardsALineIsPredictedIntoTheNextLaneBeforeItCrosses) {
  // Lane 0, 0.3 m off centre towards lane 1 and moving that way at 0.8 m/s: a cut-in.
  const CarPrediction c = test::lane_car(1, 100.0, 2.3, 17.9, 0.8);
  EXPECT_TRUE(c.changing);
  EXPECT_EQ(c.lane, 0);
  EXPECT_EQ(c.target_lane, 1);
  EXPECT_TRUE(c.occupies(0));
  EXPECT_TRUE(c.occupies(1));
  EXPECT_GT(c.change_progress, 0.0);
  EXPECT_LT(c.change_progress, 0.5);
  // It ends at the next lane's centre within the lane-change time.
  EXPECT_NEAR(c.d_at(params_.lane_change_duration_s), 6.0, 1e-9);
  EXPECT_GT(c.d_at(1.0), 2.3);
  EXPECT_GT(c.d_dot_at(0.5), 0.8);
}

TEST_F(PredictionTest, ACarFinishingAChangeIsPredictedIntoItsNewLane) {
  // Lane 1 by d (5.0), moving away from lane 2 towards lane 1's centre, fast: ending a change.
  const CarPrediction c = test::lane_car(2, 100.0, 7.0, 20.0, -1.5);
  EXPECT_TRUE(c.changing);
  EXPECT_EQ(c.target_lane, 1);
  EXPECT_NEAR(c.d_at(5.0), 6.0, 1e-9);
}

TEST_F(PredictionTest, ABrakingCarKeepsBrakingForAWhileAndNeverReverses) {
  // Braking at 8 m/s^2 from 10 m/s: for braking_horizon_s (1 s), then steady at 2 m/s.
  const CarPrediction c = test::lane_car(4, 0.0, 6.0, 10.0, 0.0, -8.0);
  EXPECT_NEAR(c.s_dot_at(0.5), 6.0, 1e-9);
  EXPECT_NEAR(c.s_dot_at(3.0), 2.0, 1e-9);
  EXPECT_NEAR(c.s_at(2.0), 10.0 - 4.0 + 2.0, 1e-9);
  // From 6 m/s it stops within that second, and stays stopped.
  const CarPrediction slow = test::lane_car(6, 0.0, 6.0, 6.0, 0.0, -8.0);
  EXPECT_NEAR(slow.s_at(10.0), 36.0 / 16.0, 1e-9);
  EXPECT_EQ(slow.s_dot_at(10.0), 0.0);
  // A mild slowing is not extrapolated.
  const CarPrediction mild = test::lane_car(5, 0.0, 6.0, 10.0, 0.0, -0.5);
  EXPECT_NEAR(mild.s_at(2.0), 20.0, 1e-9);
}

TEST_F(PredictionTest, TracksGiveAccelerationAndForgetCarsPlacedAgain) {
  std::vector<CarTrack> tracks;
  core::Telemetry t;
  t.cars = {test::observed_car(line_, 0, 300.0, 6.0, 20.0),
            test::observed_car(line_, 1, 400.0, 2.0, 20.0)};
  auto first = predict_cars(t, line_, 280.0, 0.0, tracks, params_, road_, 4.7);
  ASSERT_EQ(first.size(), 2u);
  EXPECT_EQ(first[0].s_ddot, 0.0);
  // 0.04 s later: car 0 slowed by 0.32 m/s (8 m/s^2); car 1 jumped 150 m (placed again).
  t.cars = {test::observed_car(line_, 0, 300.8, 6.0, 19.68),
            test::observed_car(line_, 1, 550.0, 2.0, 19.68)};
  auto second = predict_cars(t, line_, 281.0, 0.04, tracks, params_, road_, 4.7);
  EXPECT_NEAR(second[0].s_ddot, -8.0, 0.05);
  EXPECT_EQ(second[1].s_ddot, 0.0);
  EXPECT_EQ(tracks.size(), 2u);
}

TEST_F(PredictionTest, ParkedCarsAreNoTrafficAndTheFirstFramesSlipIsUndone) {
  std::vector<CarTrack> tracks;
  core::Telemetry t;
  // Car 0 waits parked 280 m off the road; car 1 was just placed: its velocity reads its cap
  // (50 mph) as m/s.
  t.cars = {test::observed_car(line_, 0, 300.0, -280.0, 0.0),
            test::observed_car(line_, 1, 400.0, 6.0, 50.0)};
  const auto cars = predict_cars(t, line_, 280.0, 0.0, tracks, params_, road_, 4.7);
  ASSERT_EQ(cars.size(), 1u);
  EXPECT_EQ(cars[0].id, 1);
  EXPECT_NEAR(cars[0].speed_mps, 50.0 / core::kMphPerMps, 1e-6);
}

TEST_F(PredictionTest, ACarBehindIsTakenToSpeedUpALittleAboveItsFastestSeen) {
  std::vector<CarTrack> tracks;
  core::Telemetry t;
  // Seen at 18 m/s, then at 15: it may speed up to 18 + 2 m/s.
  t.cars = {test::observed_car(line_, 0, 250.0, 6.0, 18.0)};
  (void)predict_cars(t, line_, 280.0, 0.0, tracks, params_, road_, 4.7);
  t.cars = {test::observed_car(line_, 0, 250.7, 6.0, 15.0)};
  auto cars = predict_cars(t, line_, 280.0, 0.04, tracks, params_, road_, 4.7);
  ASSERT_EQ(cars.size(), 1u);
  EXPECT_GT(cars[0].s_dot_at(1.0), 15.0 + 1.4);  // at 1.5 m/s^2
  EXPECT_NEAR(cars[0].s_dot_at(30.0), 18.0 + params_.follower_speed_margin_mps, 0.3);
  // A placed car's first frame (its cap read as m/s) tells its cap: 60 mph.
  tracks.clear();
  t.cars = {test::observed_car(line_, 1, 250.0, 6.0, 60.0)};
  cars = predict_cars(t, line_, 280.0, 0.0, tracks, params_, road_, 4.7);
  EXPECT_NEAR(cars[0].speed_mps, core::mph_to_mps(60.0), 1e-6);
  EXPECT_NEAR(cars[0].s_dot_at(30.0), core::mph_to_mps(60.0) + params_.follower_speed_margin_mps,
              0.3);
}

TEST_F(PredictionTest, ACarCloseBehindItsLeaderIsTakenToBrakeInAWave) {
  std::vector<CarTrack> tracks;
  core::Telemetry t;
  // Ahead of the ego: car 0 12 m (bumper to bumper) behind car 1, both at 18 m/s. With a cap
  // of 50 mph it reacts within 0.5 * (50 - 18) = 16 m and brakes towards 18 "mph".
  const double cap_speed = 0.81 * core::mph_to_mps(50.0);
  t.cars = {test::observed_car(line_, 0, 300.0, 6.0, cap_speed),
            test::observed_car(line_, 1, 316.7, 6.0, 18.0)};
  const auto cars = predict_cars(t, line_, 200.0, 0.0, tracks, params_, road_, 4.7);
  ASSERT_EQ(cars.size(), 2u);
  EXPECT_LT(cars[0].s_ddot, -5.0);
  // Down to 18 "mph", then back up to its speed (a surge).
  EXPECT_NEAR(cars[0].s_dot_at(cars[0].brake_time_s), 18.0 / core::kMphPerMps, 0.3);
  EXPECT_NEAR(cars[0].s_dot_at(10.0), cap_speed, 0.1);
  EXPECT_EQ(cars[1].s_ddot, 0.0);  // nothing ahead of it
}

TEST_F(PredictionTest, CarsAcrossTheLapWrapGetSNearTheEgo) {
  std::vector<CarTrack> tracks;
  core::Telemetry t;
  const double end = line_.start_s_m() + line_.length_m();
  t.cars = {test::observed_car(line_, 0, end + 20.0, 6.0, 20.0)};  // just past the wrap
  const auto cars = predict_cars(t, line_, end - 10.0, 0.0, tracks, params_, road_, 4.7);
  EXPECT_NEAR(cars[0].s_m - (end - 10.0), 30.0, 1e-6);
}

}  // namespace
}  // namespace overtake::planner::reference
