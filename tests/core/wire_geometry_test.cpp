// The wire rounding of numbers, and footprint overlap.

#include <gtest/gtest.h>

#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <limits>
#include <random>

#include "overtake/core/geometry.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/core/units.hpp"
#include "overtake/core/wire_number.hpp"

namespace overtake::core {
namespace {

TEST(WireRound, KeepsSevenSignificantDigitsOfTheFloat) {
  EXPECT_EQ(wire_round(909.48250105225), 909.4825);
  EXPECT_EQ(wire_round(124.83364), 124.8336);
  EXPECT_EQ(wire_round(6.1648331), 6.164833);
  EXPECT_EQ(wire_round(0.0), 0.0);
  EXPECT_EQ(wire_round(49.0), 49.0);
  EXPECT_EQ(wire_round(-0.3651), -0.3651);
  EXPECT_EQ(wire_round(1e-5), 1e-5);
  EXPECT_EQ(wire_round(-3.5e-6), -3.5e-6);
}

TEST(WireRound, IsIdempotent) {
  for (double v = -2500.0; v < 2500.0; v += 13.3713371337) {
    const double once = wire_round(v);
    EXPECT_EQ(wire_round(once), once) << v;
  }
}

// The definition: the float printed with 7 significant digits and read back.
double through_text(double value) {
  const auto f = static_cast<float>(value);
  char buf[32];
  const auto printed = std::to_chars(buf, buf + sizeof buf, f, std::chars_format::general, 7);
  double out = 0.0;
  std::from_chars(buf, printed.ptr, out);
  return out;
}

// wire_round computes without text; it must give the text's double, bit for bit, for every
// magnitude, sign and tie (a float exactly halfway between two 7-digit decimals rounds to the
// even one).
TEST(WireRound, GivesWhatTheTextGivesBitForBit) {
  const auto same = [](double v) {
    const double a = wire_round(v);
    const double b = through_text(v);
    EXPECT_EQ(std::bit_cast<std::uint64_t>(a), std::bit_cast<std::uint64_t>(b))
        << std::setprecision(17) << v << ": " << a << " vs " << b;
  };
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(1.0, 10.0);
  std::uniform_int_distribution<int> exponent(-40, 40);
  for (int i = 0; i < 2000000; ++i) {
    const double v = unit(rng) * std::pow(10.0, exponent(rng));
    same(i % 2 == 0 ? v : -v);
  }
  // Every float in decades where figures live, stepping through their bits.
  for (const float start : {0.001F, 1.0F, 99.0F, 6900.0F, 524287.0F}) {
    std::uint32_t bits = std::bit_cast<std::uint32_t>(start);
    for (int i = 0; i < 300000; ++i) same(static_cast<double>(std::bit_cast<float>(bits++)));
  }
  // Exact ties: floats with 8 significant digits ending in 5.
  for (double base = 1000000.5; base < 1000100.0; base += 1.0) same(base / 10.0);
  for (double v = 1048576.5; v < 1048676.0; v += 1.0) same(v);
  for (const double v : {0.0, -0.0, 1e-16, 9.9999999e-17, 999999.94, 999999.96, 1e6, 3.4e38, 1e-45,
                         1e-38, 123456.75, 0.5, 0.25, 0.125, 9999999.5}) {
    same(v);
    same(-v);
  }
}

TEST(WireRound, PassesNonFiniteValuesThrough) {
  EXPECT_TRUE(std::isnan(wire_round(std::numeric_limits<double>::quiet_NaN())));
  EXPECT_EQ(wire_round(std::numeric_limits<double>::infinity()),
            std::numeric_limits<double>::infinity());
}

TEST(WireRound, RoundsYawInDegreesAndSpeedInMph) {
  Telemetry t;
  t.ego.yaw_rad = deg_to_rad(12.3456789);
  t.ego.speed_mps = mph_to_mps(49.123456789);
  const Telemetry r = round_like_wire(t);
  EXPECT_DOUBLE_EQ(rad_to_deg(r.ego.yaw_rad), 12.34568);
  EXPECT_DOUBLE_EQ(mps_to_mph(r.ego.speed_mps), 49.12346);
}

TEST(BoxesOverlap, AlignedBoxes) {
  const OrientedBox a{{0, 0}, 0.0, 4.7, 1.9};
  EXPECT_TRUE(boxes_overlap(a, {{4.6, 0}, 0.0, 4.7, 1.9}));
  EXPECT_FALSE(boxes_overlap(a, {{4.8, 0}, 0.0, 4.7, 1.9}));
  EXPECT_TRUE(boxes_overlap(a, {{0, 1.8}, 0.0, 4.7, 1.9}));
  EXPECT_FALSE(boxes_overlap(a, {{0, 2.0}, 0.0, 4.7, 1.9}));
}

TEST(BoxesOverlap, RotationMatters) {
  const OrientedBox a{{0, 0}, 0.0, 4.7, 1.9};
  // A car 3 m to the side does not touch when parallel, but does when turned across.
  EXPECT_FALSE(boxes_overlap(a, {{0, 3.0}, 0.0, 4.7, 1.9}));
  EXPECT_TRUE(boxes_overlap(a, {{0, 3.0}, kPi / 2, 4.7, 1.9}));
  // Along the diagonal: the turned box's end reaches the first box, a bit farther it does not
  // (separated on the turned box's own long axis).
  EXPECT_TRUE(boxes_overlap(a, {{3.6, 2.4}, kPi / 4, 4.7, 1.9}));
  EXPECT_FALSE(boxes_overlap(a, {{4.5, 3.0}, kPi / 4, 4.7, 1.9}));
}

TEST(MengerCurvature, CircleThroughThreePoints) {
  const double r = 150.0;
  const Vec2 a{r, 0}, b{r * std::cos(0.1), r * std::sin(0.1)},
      c{r * std::cos(0.2), r * std::sin(0.2)};
  EXPECT_NEAR(menger_curvature(a, b, c), 1.0 / r, 1e-9);   // counter-clockwise: positive
  EXPECT_NEAR(menger_curvature(c, b, a), -1.0 / r, 1e-9);  // clockwise: negative
  EXPECT_EQ(menger_curvature(a, a, c), 0.0);
}

}  // namespace
}  // namespace overtake::core
