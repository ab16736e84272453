// The timing sketch: quantiles within its stated 1% of the exact order statistics, the
// maximum exact, and memory that does not grow with the number of values.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "overtake/core/quantile_sketch.hpp"

namespace overtake::core {
namespace {

double exact(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1;
  return v[std::min(i, v.size() - 1)];
}

TEST(QuantileSketch, QuantilesAreWithinTheStatedErrorOfTheExactOnes) {
  std::mt19937_64 rng(7);
  std::lognormal_distribution<double> cycle(std::log(70.0), 0.6);  // like planner cycles, us
  std::vector<double> values;
  QuantileSketch sketch;
  for (int i = 0; i < 200000; ++i) {
    const double v = cycle(rng);
    values.push_back(v);
    sketch.add(v);
  }
  for (const double q : {0.01, 0.5, 0.9, 0.99, 0.999}) {
    const double want = exact(values, q);
    EXPECT_NEAR(sketch.quantile(q), want, QuantileSketch::kRelativeError * want) << "q = " << q;
  }
  EXPECT_EQ(sketch.max(), *std::max_element(values.begin(), values.end()));
  EXPECT_EQ(sketch.count(), values.size());
}

TEST(QuantileSketch, SmallAndOddInputs) {
  QuantileSketch empty;
  EXPECT_EQ(empty.quantile(0.5), 0.0);
  EXPECT_EQ(empty.max(), 0.0);
  QuantileSketch one;
  one.add(250.0);
  EXPECT_NEAR(one.quantile(0.5), 250.0, 2.5);
  EXPECT_LE(one.quantile(0.99), 250.0);  // never above the maximum
  QuantileSketch odd;
  odd.add(std::nan(""));
  odd.add(0.0);
  odd.add(-3.0);
  odd.add(1e30);
  EXPECT_EQ(odd.count(), 3u);  // NaN ignored
  EXPECT_EQ(odd.max(), 1e30);
  EXPECT_LT(odd.quantile(0.5), 1e-2);
}

TEST(QuantileSketch, MemoryIsFixed) {
  // The whole state is the object: no heap, so a 7-day run's 15 million cycles cost nothing
  // more than ten do (the per-cycle vectors it replaces grew 16 bytes a cycle).
  static_assert(sizeof(QuantileSketch) < 16 * 1024);
  QuantileSketch s;
  for (int i = 0; i < 1000000; ++i) s.add(50.0 + (i % 100));
  EXPECT_EQ(s.count(), 1000000u);
  EXPECT_NEAR(s.quantile(0.5), 99.0, 1.0);
}

}  // namespace
}  // namespace overtake::core
