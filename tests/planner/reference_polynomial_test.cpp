// Jerk-minimising polynomials and the braking profile: boundary conditions, extension, costs.

#include <gtest/gtest.h>

#include <cmath>

#include "overtake/planner/reference/polynomial.hpp"
#include "overtake/planner/reference/prediction.hpp"

namespace overtake::planner::reference {
namespace {

constexpr double kTol = 1e-9;

struct Ends {
  double x0, v0, a0, x1, v1, a1, t;
};

TEST(Quintic, MeetsBothEndsInPositionVelocityAndAcceleration) {
  for (const Ends e : {Ends{0, 0, 0, 100, 20, 0, 6}, Ends{5, 21, -1.5, 60, 17, 0, 3},
                       Ends{6, 0.4, 0.3, 2, 0, 0, 3.7}, Ends{-3, -2, 4, 3, 2, -4, 0.5}}) {
    const Polynomial1d p = quintic(e.x0, e.v0, e.a0, e.x1, e.v1, e.a1, e.t);
    const Motion1d s = p.raw(0.0);
    const Motion1d f = p.raw(e.t);
    EXPECT_NEAR(s.x, e.x0, kTol);
    EXPECT_NEAR(s.v, e.v0, kTol);
    EXPECT_NEAR(s.a, e.a0, kTol);
    EXPECT_NEAR(f.x, e.x1, 1e-7);
    EXPECT_NEAR(f.v, e.v1, 1e-7);
    EXPECT_NEAR(f.a, e.a1, 1e-7);
  }
}

TEST(Quartic, MeetsTheStartAndTheEndVelocity) {
  const Polynomial1d p = quartic(10.0, 22.0, -0.5, 15.0, 0.0, 4.0);
  EXPECT_NEAR(p.raw(0.0).x, 10.0, kTol);
  EXPECT_NEAR(p.raw(0.0).v, 22.0, kTol);
  EXPECT_NEAR(p.raw(0.0).a, -0.5, kTol);
  EXPECT_NEAR(p.raw(4.0).v, 15.0, 1e-9);
  EXPECT_NEAR(p.raw(4.0).a, 0.0, 1e-9);
  EXPECT_EQ(p.c[5], 0.0);
}

TEST(Quartic, FromRestIsTheMinimumJerkSpeedProfile) {
  // v(t) = v1 (3 tau^2 - 2 tau^3): monotone, peak acceleration 1.5 v1 / T at mid-time.
  const Polynomial1d p = quartic(0.0, 0.0, 0.0, 20.0, 0.0, 5.0);
  double last = -1.0;
  for (double t = 0.0; t <= 5.0; t += 0.05) {
    EXPECT_GE(p.raw(t).v, last - kTol);
    last = p.raw(t).v;
  }
  EXPECT_NEAR(p.raw(2.5).a, 1.5 * 20.0 / 5.0, 1e-9);
}

TEST(Polynomial, ContinuesAtItsEndVelocityAfterItsEnd) {
  const Polynomial1d p = quartic(0.0, 10.0, 0.0, 20.0, 0.0, 3.0);
  const Motion1d end = p.raw(3.0);
  const Motion1d later = p.at(5.0);
  EXPECT_NEAR(later.x, end.x + 2.0 * end.v, 1e-9);
  EXPECT_NEAR(later.v, end.v, kTol);
  EXPECT_EQ(later.a, 0.0);
  EXPECT_EQ(later.j, 0.0);
  // Before its start it is the polynomial itself (a smooth continuation of the start state).
  EXPECT_EQ(p.at(-0.1).x, p.raw(-0.1).x);
}

TEST(Polynomial, JerkCostIsTheIntegralOfTheSquaredJerk) {
  const Polynomial1d p = quintic(0.0, 3.0, 1.0, 40.0, 12.0, 0.0, 4.0);
  double numeric = 0.0;
  const int n = 40000;
  for (int i = 0; i < n; ++i) {
    const double t = (i + 0.5) * 4.0 / n;
    numeric += p.raw(t).j * p.raw(t).j * 4.0 / n;
  }
  EXPECT_NEAR(p.jerk_cost(), numeric, 1e-6 * numeric);
}

TEST(BrakingProfile, StopsWithinItsJerkAndBrakingLimitsWithoutReversing) {
  for (const double a0 : {0.0, 1.5, -3.0, -8.0}) {
    const BrakingProfile b(50.0, 22.0, a0, 6.0, 7.0);
    EXPECT_NEAR(b.at(0.0).x, 50.0, kTol);
    EXPECT_NEAR(b.at(0.0).v, 22.0, kTol);
    EXPECT_NEAR(b.at(0.0).a, a0, kTol);
    Motion1d prev = b.at(0.0);
    for (double t = 0.01; t < b.stop_time_s() + 2.0; t += 0.01) {
      const Motion1d m = b.at(t);
      EXPECT_GE(m.v, 0.0);
      EXPECT_GE(m.x, prev.x - kTol);
      EXPECT_GE(m.a, -std::max(6.0, -a0) - 1e-9);
      EXPECT_LE(std::abs(m.a - prev.a), std::max(7.0, a0 * a0 / 44.0) * 0.01 + 1e-9) << "t " << t;
      prev = m;
    }
    EXPECT_EQ(b.at(b.stop_time_s() + 1.0).v, 0.0);
    EXPECT_NEAR(b.at(b.stop_time_s() - 1e-6).a, 0.0, 1e-4);  // no jolt at the stop
  }
}

TEST(BrakingProfile, AtRestStaysAtRest) {
  const BrakingProfile b(3.0, 0.0, 0.0, 6.0, 7.0);
  EXPECT_EQ(b.at(2.0).x, 3.0);
  EXPECT_EQ(b.at(2.0).v, 0.0);
}

TEST(MinimumJerk, ProgressInvertsTheFraction) {
  for (double tau = 0.0; tau <= 1.0; tau += 0.05) {
    EXPECT_NEAR(min_jerk_progress(min_jerk_fraction(tau)), tau, 1e-9);
  }
  EXPECT_EQ(min_jerk_fraction(-1.0), 0.0);
  EXPECT_EQ(min_jerk_fraction(2.0), 1.0);
}

}  // namespace
}  // namespace overtake::planner::reference
