// Cubic splines and the reference line on an exact circle.

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "overtake/core/map.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/spline.hpp"
#include "overtake/core/units.hpp"

namespace overtake::core {
namespace {

constexpr double kTol = 1e-9;

TEST(NaturalSpline, InterpolatesItsKnotsWithZeroEndCurvature) {
  const std::vector<double> t{0.0, 1.0, 2.5, 4.0, 7.0};
  const std::vector<double> y{1.0, 3.0, -2.0, 0.5, 4.0};
  const auto s = PiecewiseCubic::natural(t, y);
  ASSERT_TRUE(s);
  for (std::size_t i = 0; i < t.size(); ++i) EXPECT_NEAR((*s)(t[i]), y[i], kTol);
  EXPECT_NEAR(s->eval(0.0).d2, 0.0, kTol);
  EXPECT_NEAR(s->eval(7.0).d2, 0.0, kTol);
  // Continuity of the first and second derivatives at an inner knot.
  const auto left = s->eval_piece(1, 2.5);
  const auto right = s->eval_piece(2, 2.5);
  EXPECT_NEAR(left.d1, right.d1, 1e-9);
  EXPECT_NEAR(left.d2, right.d2, 1e-9);
}

TEST(NaturalSpline, ReproducesAStraightLine) {
  const std::vector<double> t{0, 2, 3, 10};
  const std::vector<double> y{1, 5, 7, 21};
  const auto s = PiecewiseCubic::natural(t, y);
  ASSERT_TRUE(s);
  EXPECT_NEAR((*s)(6.0), 13.0, kTol);
  EXPECT_NEAR(s->eval(6.0).d1, 2.0, kTol);
}

TEST(NaturalSpline, TwoPointsMakeALine) {
  const std::vector<double> t{0, 4};
  const std::vector<double> y{0, 2};
  const auto s = PiecewiseCubic::natural(t, y);
  ASSERT_TRUE(s);
  EXPECT_NEAR((*s)(1.0), 0.5, kTol);
}

TEST(NaturalSpline, RejectsBadKnots) {
  const std::vector<double> one{0.0};
  EXPECT_FALSE(PiecewiseCubic::natural(one, one));
  const std::vector<double> t{0, 1, 1, 2};
  const std::vector<double> y{0, 1, 2, 3};
  EXPECT_FALSE(PiecewiseCubic::natural(t, y));
  const std::vector<double> dec{0, 2, 1};
  const std::vector<double> y3{0, 1, 2};
  EXPECT_FALSE(PiecewiseCubic::natural(dec, y3));
  const std::vector<double> nan_t{0, NAN, 2};
  EXPECT_FALSE(PiecewiseCubic::natural(nan_t, y3));
  const std::vector<double> short_y{0, 1};
  EXPECT_FALSE(PiecewiseCubic::natural(y3, short_y));
}

// A long spline finds its pieces through a bucket index: the same piece as a bisection of the
// knots, for knots spaced very unevenly, at the knots themselves, between them, and outside.
TEST(NaturalSpline, ALongSplineFindsThePieceABisectionFinds) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> gap(0.0, 1.0);
  std::vector<double> t{-50.0};
  for (int i = 0; i < 400; ++i) {
    const double g = gap(rng);
    t.push_back(t.back() + (i % 50 == 0 ? 300.0 * g : g * g * g + 1e-6));
  }
  const std::vector<double> y(t.size(), 1.0);
  const auto s = PiecewiseCubic::natural(t, y);
  ASSERT_TRUE(s);
  const auto bisection = [&](double x) -> std::size_t {
    const auto it = std::upper_bound(t.begin(), t.end(), x);
    if (it == t.begin()) return 0;
    return std::min<std::size_t>(static_cast<std::size_t>(it - t.begin()) - 1, t.size() - 2);
  };
  std::uniform_real_distribution<double> anywhere(t.front() - 10.0, t.back() + 10.0);
  std::vector<double> probes;
  for (int i = 0; i < 200000; ++i) probes.push_back(anywhere(rng));
  for (const double k : t) {
    probes.push_back(k);
    probes.push_back(std::nextafter(k, -1e9));
    probes.push_back(std::nextafter(k, 1e9));
  }
  probes.push_back(std::numeric_limits<double>::quiet_NaN());
  for (const double x : probes) ASSERT_EQ(s->piece(x), bisection(x)) << x;
}

TEST(PeriodicSpline, ClosesSmoothlyAcrossThePeriod) {
  const std::vector<double> t{0, 1, 2.5, 4};
  const std::vector<double> y{0, 2, -1, 1};
  const auto s = PiecewiseCubic::periodic(t, y, 5.0);
  ASSERT_TRUE(s);
  EXPECT_NEAR(s->back(), 5.0, kTol);
  const auto end = s->eval_piece(3, 5.0);
  const auto start = s->eval_piece(0, 0.0);
  EXPECT_NEAR(end.value, start.value, 1e-9);
  EXPECT_NEAR(end.d1, start.d1, 1e-9);
  EXPECT_NEAR(end.d2, start.d2, 1e-9);
}

TEST(PeriodicSpline, RejectsAPeriodShorterThanTheKnots) {
  const std::vector<double> t{0, 1, 2};
  const std::vector<double> y{0, 1, 0};
  EXPECT_FALSE(PiecewiseCubic::periodic(t, y, 2.0));
  EXPECT_TRUE(PiecewiseCubic::periodic(t, y, 3.0));
}

TEST(PeriodicSmoothingSpline, StiffnessZeroInterpolates) {
  const std::vector<double> t{0, 1, 2.5, 4};
  const std::vector<double> y{0, 2, -1, 1};
  const auto a = PiecewiseCubic::periodic(t, y, 5.0);
  const auto b = PiecewiseCubic::periodic_smoothing(t, y, 5.0, 0.0);
  ASSERT_TRUE(a && b);
  for (double x = 0.0; x < 5.0; x += 0.37) EXPECT_NEAR((*a)(x), (*b)(x), 1e-9);
}

TEST(PeriodicSmoothingSpline, DampsRoundingNoiseButKeepsTheShape) {
  // A sine of wavelength 600 sampled every 25, each sample off by +-0.05 (alternating):
  // interpolated, the noise puts wiggles into the second derivative nearly half the sine's
  // own; smoothed, they are gone and the curve stays within centimetres of the sine.
  constexpr double kWave = 600.0;
  constexpr double kAmp = 20.0;
  std::vector<double> t, y;
  for (int i = 0; i < 24; ++i) {
    t.push_back(25.0 * i);
    y.push_back(kAmp * std::sin(2.0 * kPi * t.back() / kWave) + (i % 2 ? 0.05 : -0.05));
  }
  const auto rough = PiecewiseCubic::periodic(t, y, kWave);
  const auto smooth = PiecewiseCubic::periodic_smoothing(t, y, kWave, 5000.0);
  ASSERT_TRUE(rough && smooth);
  const double k = 2.0 * kPi / kWave;
  double rough_err = 0.0, smooth_err = 0.0, smooth_pos = 0.0;
  for (double x = 0.0; x < kWave; x += 1.0) {
    const double want_d2 = -kAmp * k * k * std::sin(k * x);
    rough_err = std::max(rough_err, std::abs(rough->eval(x).d2 - want_d2));
    smooth_err = std::max(smooth_err, std::abs(smooth->eval(x).d2 - want_d2));
    smooth_pos = std::max(smooth_pos, std::abs((*smooth)(x)-kAmp * std::sin(k * x)));
  }
  EXPECT_GT(rough_err, 0.3 * kAmp * k * k);
  EXPECT_LT(smooth_err, 0.1 * rough_err);
  EXPECT_LT(smooth_pos, 0.15);
}

TEST(PeriodicSmoothingSpline, RejectsABadStiffness) {
  const std::vector<double> t{0, 1, 2};
  const std::vector<double> y{0, 1, 0};
  EXPECT_FALSE(PiecewiseCubic::periodic_smoothing(t, y, 3.0, -1.0));
  EXPECT_FALSE(PiecewiseCubic::periodic_smoothing(t, y, 3.0, std::nan("")));
  EXPECT_FALSE(PiecewiseCubic::periodic_smoothing(t, y, 2.0, 1.0));
  EXPECT_TRUE(PiecewiseCubic::periodic_smoothing(t, y, 3.0, 1.0));
}

// A counter-clockwise circle of radius r, waypoints every `n`-th of the loop, normals outward.
Map circle(double r, int n) {
  std::vector<Waypoint> w;
  const double chord = 2.0 * r * std::sin(kPi / n);
  for (int i = 0; i < n; ++i) {
    const double a = 2.0 * kPi * i / n - kPi / 2;
    w.push_back({r * std::cos(a), r * std::sin(a), chord * i, std::cos(a), std::sin(a)});
  }
  return parse_map(format_map(w), "circle");
}

TEST(ReferenceLine, CircleHasTheRightCurvatureAndHeading) {
  const Map m = circle(500.0, 120);
  const ReferenceLine line(m);
  EXPECT_NEAR(line.length_m(), 120 * 2 * 500 * std::sin(kPi / 120), 1e-3);
  for (double s = 0; s < line.length_m(); s += 97.0) {
    const RoadFrame f = line.frame(s);
    EXPECT_NEAR(norm(f.position), 500.0, 0.05);
    EXPECT_NEAR(f.curvature_1pm, 1.0 / 500.0, 2e-5);  // left turn: positive
    // The normal points away from the centre (outward = right of counter-clockwise travel).
    EXPECT_GT(dot(f.normal, f.position), 0.0);
    // Lanes farther out turn more gently.
    EXPECT_NEAR(line.curvature_at(s, 10.0), 1.0 / 510.0, 2e-5);
  }
}

TEST(ReferenceLine, SpeedAlongAnOuterLaneScalesWithItsRadius) {
  const ReferenceLine line(circle(500.0, 120));
  const FrenetPoint p{100.0, 10.0};
  const double s_dot = line.s_rate(p, 20.0);
  EXPECT_NEAR(norm(line.velocity(p, s_dot, 0.0)), 20.0, 1e-9);
  EXPECT_LT(s_dot, 20.0);  // 510 m radius vs 500 m: fewer metres of s per second
}

TEST(ReferenceLine, WrapAndSAheadAreCorrectAcrossTheLap) {
  const ReferenceLine line(circle(500.0, 120));
  const double len = line.length_m();
  EXPECT_NEAR(line.wrap_s(len + 5.0), 5.0, 1e-9);
  EXPECT_NEAR(line.wrap_s(-5.0), len - 5.0, 1e-9);
  EXPECT_NEAR(line.s_ahead(len - 10.0, 15.0), 25.0, 1e-9);
  EXPECT_NEAR(line.s_ahead(15.0, len - 10.0), -25.0, 1e-9);
}

// Wrapping gives exactly what fmod gives, within the loop (where it is skipped for a loop
// starting at 0) and outside it, and +0 for -0.
TEST(ReferenceLine, WrapGivesWhatFmodGivesBitForBit) {
  const ReferenceLine line(circle(500.0, 120));
  ASSERT_EQ(line.start_s_m(), 0.0);
  const double len = line.length_m();
  const auto by_fmod = [&](double s) {
    double r = std::fmod(s, len);
    if (r < 0.0) r += len;
    if (r >= len) r = 0.0;
    return 0.0 + r;
  };
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> any(-3.0 * len, 3.0 * len);
  std::vector<double> probes{0.0, -0.0, len, std::nextafter(len, 0.0), 1e-300, -1e-300};
  for (int i = 0; i < 100000; ++i) probes.push_back(any(rng));
  for (const double s : probes) {
    EXPECT_EQ(std::bit_cast<std::uint64_t>(line.wrap_s(s)),
              std::bit_cast<std::uint64_t>(by_fmod(s)))
        << s;
  }
}

TEST(ReferenceLine, FrenetRoundTripOnACircleAcrossTheWrap) {
  const ReferenceLine line(circle(300.0, 60));
  const double len = line.length_m();
  for (double s = -50.0; s <= 50.0; s += 2.5) {
    for (double d = -1.0; d <= 13.0; d += 1.0) {
      const Vec2 p = line.to_cartesian({s, d});
      const FrenetPoint f = line.to_frenet(p);
      EXPECT_NEAR(std::abs(line.s_ahead(s, f.s_m)), 0.0, 1e-6) << "s " << s << " d " << d;
      EXPECT_NEAR(f.d_m, d, 1e-6);
      const FrenetPoint hinted = line.to_frenet(p, line.wrap_s(s + 3.0));
      EXPECT_NEAR(std::abs(line.s_ahead(s, hinted.s_m)), 0.0, 1e-6);
      EXPECT_GE(f.s_m, 0.0);
      EXPECT_LT(f.s_m, len);
    }
  }
}

TEST(ReferenceLine, NormalsPointingInwardAreFollowed) {
  // The same circle with inward normals: d is measured toward the centre.
  std::vector<Waypoint> w = circle(500.0, 120).waypoints;
  for (auto& p : w) {
    p.dx = -p.dx;
    p.dy = -p.dy;
  }
  const ReferenceLine line(parse_map(format_map(w), "inward"));
  const Vec2 p = line.to_cartesian({50.0, 6.0});
  EXPECT_NEAR(norm(p), 494.0, 0.05);
}

TEST(ReferenceLine, ASmoothedLinePassesNearTheWaypointsAndKeepsTheMap) {
  const Map m = circle(500.0, 120);
  const ReferenceLine line(m, 5000.0);
  EXPECT_EQ(line.map().waypoints.size(), m.waypoints.size());
  EXPECT_EQ(line.map().waypoints[5].x_m, m.waypoints[5].x_m);
  for (const Waypoint& w : m.waypoints) {
    // A circle is smooth already: smoothing pulls it in by a little only.
    EXPECT_NEAR(norm(line.frame(w.s_m).position), 500.0, 0.05);
  }
  EXPECT_THROW(ReferenceLine(m, -1.0), MapError);
}

TEST(ReferenceLine, ANormalFarOffTheRoadIsAnError) {
  std::vector<Waypoint> w = circle(500.0, 120).waypoints;
  w[7].dx = -w[7].dx;
  w[7].dy = -w[7].dy;
  EXPECT_THROW(ReferenceLine(parse_map(format_map(w), "flipped")), MapError);
}

}  // namespace
}  // namespace overtake::core
