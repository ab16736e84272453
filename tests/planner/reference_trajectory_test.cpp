// Trajectory layer: the Cartesian and collision checks on known paths, and the planner's
// choice in constructed situations.

#include <gtest/gtest.h>

#include <cmath>

#include "overtake/core/units.hpp"
#include "overtake/planner/reference/trajectory.hpp"
#include "planner/reference_support.hpp"

namespace overtake::planner::reference {
namespace {

class TrajectoryTest : public ::testing::Test {
 protected:
  TrajectoryTest() : map_(overtake::test::circle_map()), line_(map_) {}

  /// Lateral hold at d, longitudinal quartic from v0 to v1 over t.
  [[nodiscard]] static Trajectory straight(double d, double v0, double v1, double t,
                                           double s0 = 1000.0) {
    Trajectory tr;
    tr.lateral = quintic(d, 0.0, 0.0, d, 0.0, 0.0, 1.0);
    tr.longitudinal.poly = quartic(s0, v0, 0.0, v1, 0.0, t);
    tr.end_lane = core::lane_of(d);
    return tr;
  }
  /// A lane change from lane `from` to `to` over t at constant speed v.
  [[nodiscard]] static Trajectory change(int from, int to, double v, double t, double s0 = 1000.0) {
    Trajectory tr;
    tr.lateral = quintic(core::lane_center_d(from), 0.0, 0.0, core::lane_center_d(to), 0.0, 0.0, t);
    tr.longitudinal.poly = quartic(s0, v, 0.0, v, 0.0, 1.0);
    tr.end_lane = to;
    return tr;
  }

  core::Map map_;
  core::ReferenceLine line_;
  ReferenceParams params_;
  core::RoadParams road_;
  core::CarFootprint car_;
};

TEST_F(TrajectoryTest, AGentlePathPassesTheCartesianCheck) {
  const KinematicReport r =
      check_kinematics(straight(6.0, 20.0, 21.0, 4.0), line_, params_.trajectory);
  EXPECT_TRUE(r.ok);
  EXPECT_LT(r.peak_accel_mps2, 1.0);
  EXPECT_LT(r.peak_speed_mps, params_.trajectory.max_speed_mps);
}

TEST_F(TrajectoryTest, SpeedingIsCaught) {
  const KinematicReport r =
      check_kinematics(straight(6.0, 22.0, 23.0, 2.0), line_, params_.trajectory);
  EXPECT_FALSE(r.ok);
  EXPECT_GT(r.peak_speed_mps, params_.trajectory.max_speed_mps);
  EXPECT_LT(r.first_violation_s, 2.0);
}

TEST_F(TrajectoryTest, HardBrakingAndJerkAreCaught) {
  // 20 -> 5 m/s in 1.5 s: peak deceleration 15 m/s^2 and jerk 40 m/s^3.
  const KinematicReport r =
      check_kinematics(straight(6.0, 20.0, 5.0, 1.5), line_, params_.trajectory);
  EXPECT_FALSE(r.ok);
  EXPECT_GT(r.peak_accel_mps2, params_.trajectory.max_accel_mps2);
  EXPECT_GT(r.peak_jerk_mps3, params_.trajectory.max_jerk_mps3);
  EXPECT_NEAR(r.first_violation_s, 0.0, 1e-9);
}

TEST_F(TrajectoryTest, TheCurvatureCountsInTheTotalAcceleration) {
  // A tight circle: at 20 m/s on radius ~1100 m, v^2 k is 0.36 m/s^2 ...
  const KinematicReport r =
      check_kinematics(straight(6.0, 20.0, 20.0, 1.0), line_, params_.trajectory);
  EXPECT_NEAR(r.peak_accel_mps2, 400.0 / 1094.0, 0.02);
  // ... and a 1 s lane change adds a lateral acceleration of 5.8 * 4 / 1 = 23 m/s^2.
  const KinematicReport fast = check_kinematics(change(1, 0, 20.0, 1.0), line_, params_.trajectory);
  EXPECT_FALSE(fast.ok);
  EXPECT_TRUE(check_kinematics(change(1, 0, 20.0, 4.0), line_, params_.trajectory).ok);
}

TEST_F(TrajectoryTest, DrivingIntoASlowerCarIsACollision) {
  const std::vector<CarPrediction> cars = {test::lane_car(0, 1030.0, 6.0, 10.0)};
  const CollisionReport r =
      check_collisions(straight(6.0, 20.0, 20.0, 1.0), cars, 0.0, 1.0, params_, road_, car_);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.car_id, 0);
  // It closes 10 m/s on a 30 m gap; the margins make it a bit earlier than 2.5 s.
  EXPECT_GT(r.first_collision_s, 1.8);
  EXPECT_LT(r.first_collision_s, 2.6);
}

TEST_F(TrajectoryTest, CarsInOtherLanesAndFollowersAreNoCollision) {
  const std::vector<CarPrediction> cars = {
      test::lane_car(0, 1010.0, 2.3, 10.0),  // lane 0, wandering
      test::lane_car(1, 990.0, 10.0, 25.0),  // lane 2, passing
      test::lane_car(2, 985.0, 6.0, 24.0)};  // follows the ego
  EXPECT_TRUE(
      check_collisions(straight(6.0, 20.0, 20.0, 1.0), cars, 0.0, 1.0, params_, road_, car_).ok);
}

TEST_F(TrajectoryTest, ACutInAheadIsACollisionForTheLaneKeeper) {
  // 20 m ahead in lane 0, drifting into lane 1 at 17.9 m/s; the ego keeps 21.9 m/s.
  const std::vector<CarPrediction> cars = {test::lane_car(0, 1020.0, 2.5, 17.9, 1.0)};
  const CollisionReport r =
      check_collisions(straight(6.0, 21.9, 21.9, 1.0), cars, 0.0, 1.0, params_, road_, car_);
  EXPECT_FALSE(r.ok);
}

TEST_F(TrajectoryTest, ChangingLanesInFrontOfAFastCarFailsItsRoomToBrake) {
  // Lane 0 has a car 25 m behind at 30 m/s; the ego at 20 m/s moves over in 4 s.
  const std::vector<CarPrediction> fast = {test::lane_car(0, 975.0, 2.0, 30.0)};
  EXPECT_FALSE(check_collisions(change(1, 0, 20.0, 4.0), fast, 0.0, 1.0, params_, road_, car_).ok);
  // The same car at 21 m/s leaves room.
  const std::vector<CarPrediction> slow = {test::lane_car(0, 975.0, 2.0, 21.0)};
  EXPECT_TRUE(check_collisions(change(1, 0, 20.0, 4.0), slow, 0.0, 1.0, params_, road_, car_).ok);
}

// A plan that ends half across a lane leaves the car coming up that lane behind it unseen (its
// sensor looks straight ahead from its middle): the car keeps coming, and the next plan
// starts where this one ends. The guard asks for unseen_guard_s of closing to spare there.
TEST_F(TrajectoryTest, APlanEndingAcrossTheWayOfAnUnseeingCarNeedsTimeToSpare) {
  // The ego at 15 m/s drifts from lane 1 towards lane 0 over 10 s: at the horizon's end (5 s)
  // its middle is on the line, 2 m beside the middle of a car coming up lane 0 at 20 m/s, 15 m
  // behind then (centre to centre): 9.3 m beyond the margin, 1.86 s of closing at 5 m/s.
  const Trajectory drift = change(1, 0, 15.0, 10.0);
  ASSERT_NEAR(params_.trajectory.horizon_s, 5.0, 1e-12);
  const std::vector<CarPrediction> cars = {test::lane_car(0, 960.0, 2.0, 20.0)};
  // Off (the default), only the horizon is checked: the car is never within the margin.
  EXPECT_TRUE(check_collisions(drift, cars, 0.0, 1.0, params_, road_, car_).ok);
  ReferenceParams guarded = params_;
  guarded.trajectory.unseen_guard_s = 3.0;
  const CollisionReport r = check_collisions(drift, cars, 0.0, 1.0, guarded, road_, car_);
  EXPECT_FALSE(r.ok);
  EXPECT_EQ(r.car_id, 0);
  EXPECT_TRUE(r.from_behind);
  EXPECT_NEAR(r.first_collision_s, 5.0, 1e-9);
  // 1.86 s to spare is enough for a guard of 1.5 s ...
  guarded.trajectory.unseen_guard_s = 1.5;
  EXPECT_TRUE(check_collisions(drift, cars, 0.0, 1.0, guarded, road_, car_).ok);
  // ... and a change that is over by then leaves the car the seen follower's check alone.
  guarded.trajectory.unseen_guard_s = 3.0;
  EXPECT_TRUE(check_collisions(change(1, 0, 15.0, 4.0), cars, 0.0, 1.0, guarded, road_, car_).ok);
}

TEST_F(TrajectoryTest, TheBandAroundALaneLineIsKnown) {
  EXPECT_TRUE(in_line_band(4.5, 0.8, road_));
  EXPECT_TRUE(in_line_band(7.3, 0.8, road_));
  EXPECT_FALSE(in_line_band(6.0, 0.8, road_));
  EXPECT_FALSE(in_line_band(0.5, 0.8, road_));  // the road's edge is not a lane line
}

class PlanTest : public TrajectoryTest {
 protected:
  [[nodiscard]] TrajectoryPlan plan(const FrenetState& start, int target_lane,
                                    const std::vector<CarPrediction>& cars,
                                    double band_s = 0.0) const {
    TrajectoryRequest req;
    req.start = start;
    req.target_lane = target_lane;
    req.wanted_speed_mps = params_.behaviour.cruise_speed_mps;
    req.band_time_s = band_s;
    req.cars = &cars;
    return plan_trajectory(line_, req, params_, road_, car_);
  }
};

TEST_F(PlanTest, OnAFreeRoadItSpeedsUpSmoothlyFromTheExactStartState) {
  const FrenetState start{1000.0, 15.0, 0.8, 6.1, 0.05, -0.02};
  const TrajectoryPlan p = plan(start, 1, {});
  ASSERT_EQ(p.status, PlanStatus::feasible);
  const FrenetState at0 = p.trajectory.at(0.0);
  EXPECT_NEAR(at0.s_m, start.s_m, 1e-9);
  EXPECT_NEAR(at0.s_dot, start.s_dot, 1e-9);
  EXPECT_NEAR(at0.s_ddot, start.s_ddot, 1e-9);
  EXPECT_NEAR(at0.d_m, start.d_m, 1e-9);
  EXPECT_NEAR(at0.d_dot_mps, start.d_dot_mps, 1e-9);
  EXPECT_NEAR(at0.d_ddot_mps2, start.d_ddot_mps2, 1e-9);
  const FrenetState later = p.trajectory.at(6.0);
  EXPECT_GT(later.s_dot, 20.0);
  EXPECT_NEAR(later.d_m, 6.0, 0.01);
  EXPECT_TRUE(check_kinematics(p.trajectory, line_, params_.trajectory).ok);
}

TEST_F(PlanTest, ItChangesLaneWhereBehaviourAsks) {
  const FrenetState start{1000.0, 20.0, 0.0, 6.0, 0.0, 0.0};
  const TrajectoryPlan p = plan(start, 0, {});
  ASSERT_EQ(p.status, PlanStatus::feasible);
  EXPECT_EQ(p.trajectory.end_lane, 0);
  EXPECT_NEAR(p.trajectory.at(p.trajectory.lateral.duration_s + 0.1).d_m, 2.0, 1e-9);
}

TEST_F(PlanTest, ItStaysWhenTheTargetLaneIsTaken) {
  // A car alongside in lane 0: the change would hit it.
  const std::vector<CarPrediction> cars = {test::lane_car(0, 1001.0, 2.0, 20.0)};
  const TrajectoryPlan p = plan({1000.0, 20.0, 0.0, 6.0, 0.0, 0.0}, 0, cars);
  EXPECT_EQ(p.status, PlanStatus::feasible);
  EXPECT_EQ(p.trajectory.end_lane, 1);
}

TEST_F(PlanTest, ItSlowsBehindAStoppedCarAndStopsShortOfIt) {
  const std::vector<CarPrediction> cars = {test::lane_car(0, 1080.0, 6.0, 0.0)};
  const TrajectoryPlan p = plan({1000.0, 20.0, 0.0, 6.0, 0.0, 0.0}, 1, cars);
  EXPECT_NE(p.status, PlanStatus::least_bad);
  double min_gap = 1e9;
  for (double t = 0.0; t <= 12.0; t += 0.1)
    min_gap = std::min(min_gap, 1080.0 - p.trajectory.at(t).s_m);
  EXPECT_GT(min_gap, car_.length_m);
  EXPECT_LT(p.trajectory.at(0.5).s_ddot, -0.5);
}

TEST_F(PlanTest, TheCostTermsAddUpToTheCostExactly) {
  const std::vector<CarPrediction> slow = {test::lane_car(0, 1040.0, 6.0, 12.0)};
  for (const TrajectoryPlan& p : {plan({1000.0, 15.0, 0.8, 6.1, 0.05, -0.02}, 1, {}),
                                  plan({1000.0, 20.0, 0.0, 6.0, 0.0, 0.0}, 0, {}),
                                  plan({1000.0, 20.0, 0.0, 6.0, 0.0, 0.0}, 1, slow)}) {
    ASSERT_NE(p.status, PlanStatus::fallback);
    EXPECT_EQ(p.cost_terms.total(), p.cost);  // bit for bit: the planner's order of additions
  }
}

TEST_F(PlanTest, TheCostTermsSayWhyALaneWasChosen) {
  // Keeping the lane from its centre: no lateral manoeuvre to pay for, and no lane cost.
  const TrajectoryPlan keep = plan({1000.0, 20.0, 0.0, 6.0, 0.0, 0.0}, 1, {});
  ASSERT_EQ(keep.status, PlanStatus::feasible);
  EXPECT_EQ(keep.trajectory.end_lane, 1);
  EXPECT_EQ(keep.cost_terms.lateral_time, 0.0);
  EXPECT_EQ(keep.cost_terms.off_target_lane, 0.0);
  EXPECT_EQ(keep.cost_terms.early_lane, 0.0);
  EXPECT_EQ(keep.cost_terms.lane, 0.0);

  // Changing to behaviour's lane: a lateral manoeuvre with its time and jerk, in the lane asked.
  const TrajectoryPlan change = plan({1000.0, 20.0, 0.0, 6.0, 0.0, 0.0}, 0, {});
  ASSERT_EQ(change.status, PlanStatus::feasible);
  ASSERT_EQ(change.trajectory.end_lane, 0);
  EXPECT_NEAR(change.cost_terms.lateral_time,
              params_.trajectory.lat_time_weight * change.trajectory.lateral.duration_s, 1e-12);
  EXPECT_GT(change.cost_terms.lateral_jerk, 0.0);
  EXPECT_EQ(change.cost_terms.off_target_lane, 0.0);

  // Behaviour's lane is taken: staying costs the lane weight for ending one lane away.
  const std::vector<CarPrediction> alongside = {test::lane_car(0, 1001.0, 2.0, 20.0)};
  const TrajectoryPlan stay = plan({1000.0, 20.0, 0.0, 6.0, 0.0, 0.0}, 0, alongside);
  ASSERT_EQ(stay.status, PlanStatus::feasible);
  ASSERT_EQ(stay.trajectory.end_lane, 1);
  EXPECT_EQ(stay.cost_terms.off_target_lane, params_.trajectory.lane_weight);
}

TEST_F(PlanTest, BehindASlowCarTheProgressTermGrows) {
  const FrenetState start{1000.0, 20.0, 0.0, 6.0, 0.0, 0.0};
  const TrajectoryPlan free_road = plan(start, 1, {});
  // A car at 12 m/s 40 m ahead in every lane: no way around it.
  std::vector<CarPrediction> slow;
  for (int l = 0; l < 3; ++l)
    slow.push_back(test::lane_car(l, 1040.0, core::lane_center_d(l), 12.0));
  const TrajectoryPlan behind = plan(start, 1, slow);
  ASSERT_EQ(free_road.status, PlanStatus::feasible);
  ASSERT_NE(behind.status, PlanStatus::fallback);
  // Held to 12 m/s for most of the horizon: tens of metres short of the wanted speed's.
  EXPECT_GT(behind.cost_terms.progress,
            free_road.cost_terms.progress + 10.0 * params_.trajectory.progress_weight);
  EXPECT_GT(behind.cost, free_road.cost);
}

/// Time a trajectory stays in a lane-line band from its start, added to `already_s`.
double band_time(const Trajectory& t, double already_s, const ReferenceTrajectoryParams& p) {
  double band = already_s;
  for (double x = 0.0; x < 10.0; x += 0.02) {
    if (!in_line_band(t.at(x).d_m, p.line_band_m, core::RoadParams{})) break;
    band += 0.02;
  }
  return band;
}

TEST_F(PlanTest, ItNeverLingersOnALaneLine) {
  // On the line between lanes 1 and 0, drifting towards lane 0, 0.5 s spent on it already:
  // whichever lane it ends in, it is off the line within the limit.
  const FrenetState start{1000.0, 20.0, 0.0, 4.2, -0.2, 0.0};
  const TrajectoryPlan p = plan(start, 1, {}, 0.5);
  EXPECT_LE(band_time(p.trajectory, 0.5, params_.trajectory),
            params_.trajectory.max_band_time_s + 0.1);
}

TEST_F(PlanTest, WhenEveryWayOffTheLineTakesTooLongItTakesTheQuickest) {
  const FrenetState start{1000.0, 20.0, 0.0, 4.2, -0.2, 0.0};
  const TrajectoryPlan p = plan(start, 1, {}, 2.0);
  EXPECT_LT(band_time(p.trajectory, 2.0, params_.trajectory), 4.0);
}

TEST_F(PlanTest, WithNothingFeasibleItBrakesWithinTheJerkLimit) {
  // A car stopped 8 m ahead in every lane: no candidate avoids it.
  std::vector<CarPrediction> cars;
  for (int l = 0; l < 3; ++l)
    cars.push_back(test::lane_car(l, 1012.0, core::lane_center_d(l), 0.0));
  const TrajectoryPlan p = plan({1000.0, 20.0, 0.0, 6.0, 0.0, 0.0}, 1, cars);
  EXPECT_NE(p.status, PlanStatus::feasible);
  const double a0 = p.trajectory.at(0.0).s_ddot;
  EXPECT_LT(p.trajectory.at(1.0).s_ddot, a0);  // braking builds up
  EXPECT_GE(p.trajectory.at(1.0).s_ddot, -params_.trajectory.max_accel_mps2 - 1e-9);
}

}  // namespace
}  // namespace overtake::planner::reference
