#include "overtake/sim/referee.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/units.hpp"
#include "overtake/sim/params.hpp"

namespace overtake::sim {
namespace {

constexpr double kDt = 0.02;
constexpr double kLaneCentreD = 6.0;  // middle lane
constexpr double kDistanceTol = 1e-9;
constexpr double kFigureTol = 0.05;     // m/s^2, for the constant-acceleration run
constexpr double kCircleRelTol = 0.02;  // 2 %

using Counts = std::array<int, kIncidentTypeCount>;

int count_of(const Referee& r, IncidentType t) {
  return r.counts()[static_cast<std::size_t>(t)];
}

std::vector<Incident> of_type(const Referee& r, IncidentType t) {
  std::vector<Incident> out;
  for (const Incident& i : r.incidents()) {
    if (i.type == t) out.push_back(i);
  }
  return out;
}

/// Drives the ego along a straight road on +x: each step advances x by speed * dt, then the
/// referee sees the frame. d is given directly (it does not move the position). Unless
/// `from_rest`, the car was already going at its first step's speed.
struct StraightDriver {
  Referee referee{RefereeParams{}, kDt};
  double x_m = 0.0;
  long steps = 0;
  bool from_rest = false;

  void step(double speed_mps, double d_m = kLaneCentreD,
            std::optional<int> collided_with = std::nullopt) {
    if (steps == 0 && !from_rest) referee.set_initial_speed(speed_mps);
    x_m += speed_mps * kDt;
    ++steps;
    referee.observe(
        {steps * kDt, {x_m, 0.0}, speed_mps, x_m, d_m, d_m, collided_with, std::nullopt});
  }
  void hold(double speed_mps, double seconds, double d_m = kLaneCentreD) {
    const long n = std::lround(seconds / kDt);
    for (long i = 0; i < n; ++i) step(speed_mps, d_m);
  }
};

TEST(RefereeNames, ToStringGivesTheReportNames) {
  EXPECT_EQ(to_string(IncidentType::collision), "collision");
  EXPECT_EQ(to_string(IncidentType::speeding), "speeding");
  EXPECT_EQ(to_string(IncidentType::max_acceleration), "max_acceleration");
  EXPECT_EQ(to_string(IncidentType::max_jerk), "max_jerk");
  EXPECT_EQ(to_string(IncidentType::outside_lane), "outside_lane");
}

TEST(RefereeSetup, RejectsAZeroStepOrEmptyWindows) {
  EXPECT_THROW(Referee(RefereeParams{}, 0.0), std::invalid_argument);
  RefereeParams p;
  p.accel_block_steps = 0;
  EXPECT_THROW(Referee(p, kDt), std::invalid_argument);
}

TEST(RefereeIdle, NoFramesNoFigures) {
  const Referee r{RefereeParams{}, kDt};
  EXPECT_TRUE(r.incidents().empty());
  EXPECT_EQ(r.counts(), Counts{});
  EXPECT_EQ(r.peaks(), Peaks{});
  EXPECT_EQ(r.distance_m(), 0.0);
}

TEST(RefereeIdle, StationaryEgoGivesNoIncidentAndZeroFigures) {
  StraightDriver drv;
  drv.hold(0.0, 10.0);
  EXPECT_TRUE(drv.referee.incidents().empty());
  EXPECT_EQ(drv.referee.peaks(), Peaks{});
  EXPECT_EQ(drv.referee.distance_m(), 0.0);
  EXPECT_EQ(drv.referee.best_incident_free_m(), 0.0);
}

TEST(RefereeIdle, CleanCruiseCountsDistanceOnly) {
  StraightDriver drv;
  drv.hold(20.0, 10.0);
  EXPECT_TRUE(drv.referee.incidents().empty());
  // The first frame has no predecessor: 499 steps of 0.4 m.
  EXPECT_NEAR(drv.referee.distance_m(), 499 * 0.4, kDistanceTol * 1e3);
  EXPECT_DOUBLE_EQ(drv.referee.incident_free_m(), drv.referee.distance_m());
  EXPECT_DOUBLE_EQ(drv.referee.peaks().speed_mps, 20.0);
  EXPECT_NEAR(drv.referee.peaks().acceleration_mps2, 0.0, 1e-9);
  EXPECT_NEAR(drv.referee.peaks().strict_acceleration_mps2, 0.0, 1e-6);
}

// --- speeding ---------------------------------------------------------------------------

TEST(RefereeSpeeding, OneStepAbove50MphCountsOnce) {
  StraightDriver drv;
  drv.hold(core::mph_to_mps(40.0), 2.0);
  drv.step(core::mph_to_mps(51.0));
  drv.hold(core::mph_to_mps(40.0), 2.0);
  ASSERT_EQ(count_of(drv.referee, IncidentType::speeding), 1);
  const Incident i = of_type(drv.referee, IncidentType::speeding).front();
  EXPECT_DOUBLE_EQ(i.value, core::mph_to_mps(51.0));
  EXPECT_NEAR(i.t_s, 2.02, 1e-9);
  EXPECT_EQ(i.lane, 1);
}

TEST(RefereeSpeeding, ExactlyTheLimitIsNotSpeeding) {
  StraightDriver drv;
  drv.hold(RefereeParams{}.speed_limit_mps, 3.0);
  EXPECT_EQ(count_of(drv.referee, IncidentType::speeding), 0);
}

TEST(RefereeSpeeding, PersistingSpeedCountsOncePerSecond) {
  StraightDriver drv;
  drv.hold(core::mph_to_mps(40.0), 1.0);
  drv.hold(core::mph_to_mps(51.0), 2.5);
  drv.hold(core::mph_to_mps(40.0), 1.0);
  const std::vector<Incident> inc = of_type(drv.referee, IncidentType::speeding);
  ASSERT_EQ(inc.size(), 3u);
  EXPECT_NEAR(inc[0].t_s, 1.02, 1e-9);
  EXPECT_NEAR(inc[1].t_s, 2.02, 1e-9);
  EXPECT_NEAR(inc[2].t_s, 3.02, 1e-9);
}

// --- outside of lane --------------------------------------------------------------------

TEST(RefereeOutsideLane, StraddleLongerThanThreeSecondsCountsOnce) {
  StraightDriver drv;
  drv.hold(20.0, 1.0);
  drv.hold(20.0, 3.1, 4.0);
  drv.hold(20.0, 1.0);
  ASSERT_EQ(count_of(drv.referee, IncidentType::outside_lane), 1);
  const Incident& i = drv.referee.incidents().front();
  EXPECT_DOUBLE_EQ(i.value, 4.0);
  EXPECT_NEAR(i.t_s, 1.0 + 151 * kDt, 1e-9);  // the 151st consecutive step
}

TEST(RefereeOutsideLane, StraddleShorterThanThreeSecondsIsFine) {
  StraightDriver drv;
  drv.hold(20.0, 1.0);
  drv.hold(20.0, 2.9, 4.0);
  drv.hold(20.0, 1.0);
  drv.hold(20.0, 2.9, 8.7);  // the other line, counter restarted
  EXPECT_EQ(count_of(drv.referee, IncidentType::outside_lane), 0);
}

TEST(RefereeOutsideLane, StraddleCounterResetsWhenLeavingTheBand) {
  StraightDriver drv;
  drv.hold(20.0, 2.0, 4.5);
  drv.step(20.0, 5.0);  // one step out of the band
  drv.hold(20.0, 2.0, 3.3);
  EXPECT_EQ(count_of(drv.referee, IncidentType::outside_lane), 0);
}

TEST(RefereeOutsideLane, StraddlePastThreeSecondsCountsEachFurtherSecond) {
  StraightDriver drv;
  drv.hold(20.0, 4.2, 7.9);  // counts at steps 151 and 201
  EXPECT_EQ(count_of(drv.referee, IncidentType::outside_lane), 2);
}

TEST(RefereeOutsideLane, OffTheRoadForOneStep) {
  for (const double d : {0.7, 11.3}) {
    StraightDriver drv;
    drv.hold(20.0, 1.0);
    drv.step(20.0, d);
    drv.hold(20.0, 1.0);
    ASSERT_EQ(count_of(drv.referee, IncidentType::outside_lane), 1) << "d = " << d;
    EXPECT_DOUBLE_EQ(drv.referee.incidents().front().value, d);
    EXPECT_EQ(drv.referee.incidents().front().lane, d < 6.0 ? 0 : 2);
  }
  for (const double d : {0.9, 11.1}) {
    StraightDriver drv;
    drv.hold(20.0, 1.0);
    drv.step(20.0, d);
    drv.hold(20.0, 1.0);
    EXPECT_EQ(count_of(drv.referee, IncidentType::outside_lane), 0) << "d = " << d;
  }
}

// The road's outer edge follows the lane layout: on four lanes of 4 m it is at 16 m, and the
// margin keeps d over 15.2 m outside.
TEST(RefereeOutsideLane, TheEdgeFollowsTheLanes) {
  core::RoadParams four_lanes;
  four_lanes.lane_count = 4;
  for (const auto& [d, outside] :
       {std::pair{11.3, false}, std::pair{15.1, false}, std::pair{15.3, true}}) {
    StraightDriver drv;
    drv.referee = Referee{RefereeParams{}, kDt, four_lanes};
    drv.hold(20.0, 1.0);
    drv.step(20.0, d);
    drv.hold(20.0, 1.0);
    EXPECT_EQ(count_of(drv.referee, IncidentType::outside_lane), outside ? 1 : 0) << "d = " << d;
  }
  RefereeParams wide_margin;
  wide_margin.edge_margin_m = 1.5;
  StraightDriver drv;
  drv.referee = Referee{wide_margin, kDt};
  drv.hold(20.0, 1.0);
  drv.step(20.0, 10.6);
  drv.hold(20.0, 1.0);
  EXPECT_EQ(count_of(drv.referee, IncidentType::outside_lane), 1);
}

// --- acceleration and jerk --------------------------------------------------------------

TEST(RefereeAcceleration, ShortHardBrakePassesTheRubricButNotTheStrictFigures) {
  StraightDriver drv;
  drv.hold(20.0, 2.0);
  double v = 20.0;
  for (int i = 0; i < 3; ++i) {  // 0.06 s at 25 m/s^2
    v -= 25.0 * kDt;
    drv.step(v);
  }
  drv.hold(v, 3.0);
  const Peaks& pk = drv.referee.peaks();
  EXPECT_EQ(count_of(drv.referee, IncidentType::max_acceleration), 0);
  EXPECT_EQ(count_of(drv.referee, IncidentType::max_jerk), 0);
  EXPECT_LT(pk.acceleration_mps2, 10.0);
  EXPECT_LT(pk.jerk_mps3, 10.0);
  EXPECT_GT(pk.strict_acceleration_mps2, 10.0);
  EXPECT_GT(pk.strict_jerk_mps3, 10.0);
  // 1.5 m/s lost within 0.1 s windows: a triangular kernel of 4, 5, 4 steps.
  EXPECT_NEAR(pk.strict_acceleration_mps2, 0.5 * 13 * kDt / (0.1 * 0.1), 1e-6);
}

TEST(RefereeAcceleration, ConstantAccelerationReadsTheSameUnderBothRules) {
  StraightDriver drv;
  double v = 2.0;
  for (int i = 0; i < 250; ++i) {  // 5 s at 2 m/s^2, up to 12 m/s
    v += 2.0 * kDt;
    drv.step(v);
  }
  const Peaks& pk = drv.referee.peaks();
  EXPECT_NEAR(pk.acceleration_mps2, 2.0, kFigureTol);
  EXPECT_NEAR(pk.strict_acceleration_mps2, 2.0, kFigureTol);
  // The original's first group of totals compares with 0: about 2 m/s^3 once, then 0.
  EXPECT_LT(pk.jerk_mps3, 2.0);
  EXPECT_TRUE(drv.referee.incidents().empty());
}

TEST(RefereeAcceleration, CircleGivesNormalAcceleration) {
  constexpr double kRadius = 150.0;
  constexpr double kSpeed = 20.0;
  Referee r{RefereeParams{}, kDt};
  r.set_initial_speed(kSpeed);
  for (int i = 1; i <= 500; ++i) {
    const double angle = kSpeed * i * kDt / kRadius;
    const core::Vec2 p{kRadius * std::sin(angle), kRadius * (1.0 - std::cos(angle))};
    r.observe({i * kDt, p, kSpeed, kRadius * angle, kLaneCentreD, kLaneCentreD, std::nullopt,
               std::nullopt});
  }
  const double expected = kSpeed * kSpeed / kRadius;  // 2.67 m/s^2
  EXPECT_NEAR(r.peaks().acceleration_mps2, expected, kCircleRelTol * expected);
  EXPECT_NEAR(r.peaks().strict_acceleration_mps2, expected, kCircleRelTol * expected);
  // The first group of totals compares with 0 (the original's start): once, 2.67 m/s^3.
  EXPECT_NEAR(r.peaks().jerk_mps3, expected, kCircleRelTol * expected);
  EXPECT_TRUE(r.incidents().empty());
}

/// The rubric's peak acceleration after one block at 10 m/s, from rest or already moving.
double first_block_peak(bool from_rest, int* counted) {
  StraightDriver drv;
  drv.from_rest = from_rest;
  drv.hold(10.0, 0.2);
  *counted = count_of(drv.referee, IncidentType::max_acceleration);
  return drv.referee.peaks().acceleration_mps2;
}

TEST(RefereeAcceleration, TheFirstBlockComparesWithRest) {
  // The original's first block compares its mean speed with 0: a car that is already
  // moving when the referee starts reads a jump.
  int counted = 0;
  EXPECT_NEAR(first_block_peak(true, &counted), 10.0 / 0.2, 1e-9);
  EXPECT_EQ(counted, 1);
  EXPECT_NEAR(first_block_peak(false, &counted), 0.0, 1e-9);
  EXPECT_EQ(counted, 0);
}

TEST(RefereeAcceleration, SustainedHardAccelerationCountsEveryBlock) {
  RefereeParams p;
  p.speed_limit_mps = 1000.0;  // this test is about acceleration only
  Referee r{p, kDt};
  double x = 0.0;
  double v = 0.0;
  for (int i = 1; i <= 150; ++i) {  // 3 s at 12 m/s^2
    v += 12.0 * kDt;
    x += v * kDt;
    r.observe({i * kDt, {x, 0.0}, v, x, kLaneCentreD, kLaneCentreD, std::nullopt, std::nullopt});
  }
  // Not latched: every block at or over the limit counts. The first block (to 0.2 s)
  // compares its mean speed, 1.32 m/s, with rest: 6.6 m/s^2; the 14 others read 12.
  EXPECT_EQ(count_of(r, IncidentType::max_acceleration), 14);
  EXPECT_NEAR(r.peaks().acceleration_mps2, 12.0, 1e-6);
  EXPECT_NEAR(r.incidents().front().t_s, 0.4, 1e-9);
  EXPECT_NEAR(r.incidents().front().value, 12.0, 1e-6);
}

/// Acceleration ramping at `jerk` m/s^3 from rest for 2.4 s (two full groups of totals).
Referee ramp(double jerk) {
  RefereeParams p;
  p.speed_limit_mps = 1000.0;
  Referee r{p, kDt};
  double x = 0.0;
  double v = 0.0;
  double a = 0.0;
  for (int i = 1; i <= 120; ++i) {
    a += jerk * kDt;
    v += a * kDt;
    x += v * kDt;
    r.observe({i * kDt, {x, 0.0}, v, x, kLaneCentreD, kLaneCentreD, std::nullopt, std::nullopt});
  }
  return r;
}

TEST(RefereeJerk, RampAboveTheLimitCounts) {
  const Referee r = ramp(12.0);
  EXPECT_EQ(count_of(r, IncidentType::max_jerk), 1);
  // The first group (to 1 s) compares with 0 and reads 4.9; the second (to 2 s) reads 11.94
  // (its first block compared with rest, so slightly under 12).
  EXPECT_NEAR(r.peaks().jerk_mps3, 11.94, 0.01);
  const std::vector<Incident> jerks = of_type(r, IncidentType::max_jerk);
  ASSERT_EQ(jerks.size(), 1u);
  EXPECT_NEAR(jerks.front().t_s, 2.0, 1e-9);
  EXPECT_NEAR(jerks.front().value, 11.94, 0.01);
  EXPECT_GT(r.peaks().strict_jerk_mps3, 11.0);
}

TEST(RefereeJerk, RampBelowTheLimitDoesNot) {
  const Referee r = ramp(8.0);
  EXPECT_EQ(count_of(r, IncidentType::max_jerk), 0);
  EXPECT_NEAR(r.peaks().jerk_mps3, 7.96, 0.01);
}

// --- collisions -------------------------------------------------------------------------

TEST(RefereeCollision, DrivingThroughAParkedCarCountsOncePerSecondOfOverlap) {
  constexpr int kCarId = 7;
  constexpr double kSpeed = 3.0;
  constexpr double kLength = 4.7;
  constexpr double kWidth = 1.9;
  const core::OrientedBox parked{{100.0, 0.0}, 0.0, kLength, kWidth};
  StraightDriver drv;
  long overlap_steps = 0;
  while (drv.x_m < 120.0) {
    const double next_x = drv.x_m + kSpeed * kDt;
    const core::OrientedBox ego{{next_x, 0.0}, 0.0, kLength, kWidth};
    const bool hit = core::boxes_overlap(ego, parked);
    if (hit) ++overlap_steps;
    drv.step(kSpeed, kLaneCentreD, hit ? std::optional<int>(kCarId) : std::nullopt);
  }
  // 9.4 m of overlap at 3 m/s: just over 3 s, so four incidents.
  ASSERT_GT(overlap_steps, 150);
  ASSERT_LE(overlap_steps, 200);
  const int expected = static_cast<int>((overlap_steps + 49) / 50);
  EXPECT_EQ(expected, 4);
  ASSERT_EQ(count_of(drv.referee, IncidentType::collision), expected);
  for (const Incident& i : drv.referee.incidents()) {
    EXPECT_EQ(i.type, IncidentType::collision);
    EXPECT_EQ(i.value, kCarId);
    EXPECT_EQ(i.lane, 1);
  }
  EXPECT_NEAR(drv.referee.incidents().front().s_m, 100.0 - kLength, kSpeed * kDt);
}

// --- incident-free distance -------------------------------------------------------------

TEST(RefereeDistance, AnIncidentResetsTheIncidentFreeDistance) {
  constexpr double kSpeed = 20.0;
  constexpr double kStep = kSpeed * kDt;
  StraightDriver drv;
  drv.step(kSpeed);       // the first frame has no distance of its own
  drv.hold(kSpeed, 5.0);  // 100 m
  drv.step(kSpeed, kLaneCentreD, 3);
  drv.hold(kSpeed, 2.5);  // 50 m
  ASSERT_EQ(drv.referee.incidents().size(), 1u);
  // The incident step's own 0.4 m still belongs to the stretch that it ends.
  EXPECT_NEAR(drv.referee.incident_free_m(), 50.0, 1e-6);
  EXPECT_NEAR(drv.referee.best_incident_free_m(), 100.0 + kStep, 1e-6);
  EXPECT_NEAR(drv.referee.distance_m(), 150.0 + kStep, 1e-6);
  drv.hold(kSpeed, 3.0);  // 60 m more: the current stretch becomes the best
  EXPECT_NEAR(drv.referee.best_incident_free_m(), 110.0, 1e-6);
}

TEST(RefereeDistance, CountsAreIndexedByEnumOrder) {
  StraightDriver drv;
  drv.step(30.0, 0.5, 2);  // collision, speeding and outside of lane in one step
  const Counts c = drv.referee.counts();
  EXPECT_EQ(c, (Counts{1, 1, 0, 0, 1}));
  ASSERT_EQ(drv.referee.incidents().size(), 3u);
  EXPECT_EQ(drv.referee.incidents()[0].type, IncidentType::collision);
  EXPECT_EQ(drv.referee.incidents()[1].type, IncidentType::speeding);
  EXPECT_EQ(drv.referee.incidents()[2].type, IncidentType::outside_lane);
}

TEST(RefereeStrictNow, PeaksAreTheMaximaOfTheCurrentFigures) {
  // Speeding up on a straight, then a circle at constant speed, then braking.
  StraightDriver drv;
  StrictFigures max_now;
  const auto watch = [&] {
    const StrictFigures f = drv.referee.current_strict();
    max_now.acceleration_mps2 = std::max(max_now.acceleration_mps2, f.acceleration_mps2);
    max_now.jerk_mps3 = std::max(max_now.jerk_mps3, f.jerk_mps3);
    EXPECT_NEAR(std::hypot(f.tangential_mps2, f.normal_mps2), f.acceleration_mps2, 1e-9);
  };
  EXPECT_EQ(drv.referee.current_strict(), StrictFigures{});
  for (int i = 0; i < 200; ++i) {
    drv.step(2.0 * kDt * i);  // 2 m/s^2
    watch();
  }
  // Constant acceleration along +x: all of it tangential, and positive.
  EXPECT_NEAR(drv.referee.current_strict().tangential_mps2, 2.0, kFigureTol);
  EXPECT_NEAR(drv.referee.current_strict().normal_mps2, 0.0, 1e-6);
  for (int i = 0; i < 100; ++i) {
    drv.step(std::max(0.0, 8.0 - 3.0 * kDt * i));  // slowing: negative tangential
    watch();
  }
  EXPECT_NEAR(drv.referee.current_strict().tangential_mps2, -3.0, kFigureTol);
  EXPECT_DOUBLE_EQ(max_now.acceleration_mps2, drv.referee.peaks().strict_acceleration_mps2);
  EXPECT_DOUBLE_EQ(max_now.jerk_mps3, drv.referee.peaks().strict_jerk_mps3);
}

TEST(RefereeStrictNow, OnACircleItIsNormal) {
  constexpr double kRadius = 100.0;
  constexpr double kSpeed = 20.0;
  Referee r{RefereeParams{}, kDt};
  for (int i = 0; i < 100; ++i) {
    const double a = kSpeed * kDt * i / kRadius;
    r.observe({i * kDt,
               {kRadius * std::cos(a), kRadius * std::sin(a)},
               kSpeed,
               0.0,
               kLaneCentreD,
               kLaneCentreD,
               {},
               {}});
  }
  const StrictFigures f = r.current_strict();
  EXPECT_NEAR(f.normal_mps2, kSpeed * kSpeed / kRadius, kCircleRelTol * kSpeed * kSpeed / kRadius);
  EXPECT_NEAR(f.tangential_mps2, 0.0, 1e-6);
}

// --- the original's ways of measuring ------------------------------------------------------

TEST(RefereeAcceleration, BlockCurvatureIsUnsignedLikeTheOriginals) {
  // A zigzag whose signed curvatures cancel within a block: the original adds each triple's
  // unsigned curvature, so the normal acceleration does not vanish.
  RefereeParams p;
  p.speed_limit_mps = 1000.0;
  Referee r{p, kDt};
  r.set_initial_speed(20.0);
  for (int i = 1; i <= 20; ++i) {
    const core::Vec2 at{0.4 * i, (i % 2 == 0) ? 0.0 : 0.01};
    r.observe({i * kDt, at, 20.0, at.x, kLaneCentreD, kLaneCentreD, std::nullopt, std::nullopt});
  }
  EXPECT_GT(r.peaks().acceleration_mps2, 20.0);
}

TEST(RefereeOutsideLane, TheBandTimerHoldsWhileOffTheRoad) {
  // Off the road counts at once and does not reset the timer of a line band.
  StraightDriver drv;
  drv.hold(20.0, 2.0, 7.5);  // 100 steps in the band
  drv.step(20.0, 11.5);      // off the road: one count
  drv.hold(20.0, 1.1, 7.5);  // 55 more steps in the band: past 150 in all
  EXPECT_EQ(count_of(drv.referee, IncidentType::outside_lane), 2);
}

TEST(RefereeOutsideLane, TheExactDIsCountedBesideTheRubric) {
  Referee r{RefereeParams{}, kDt};
  r.set_initial_speed(20.0);
  double x = 0.0;
  for (int i = 1; i <= 100; ++i) {
    x += 20.0 * kDt;
    // The original's d (on the chords) stays in the lane; the exact d crosses the edge.
    r.observe({i * kDt, {x, 0.0}, 20.0, x, 10.9, 11.4, std::nullopt, std::nullopt});
  }
  EXPECT_EQ(count_of(r, IncidentType::outside_lane), 0);
  EXPECT_EQ(r.exact_outside_lane_count(), 2);  // latched like the rubric: steps 1 and 51
  EXPECT_TRUE(r.incidents().empty());
}

}  // namespace
}  // namespace overtake::sim
