// The intervals and tests against published values and values worked out independently
// (scipy): Garwood's exact Poisson intervals, the overdispersed rate interval, the order
// statistics of a median, MOVER, the paired t-test, the exact sign-flip test, Holm's
// adjustment, rliable's probability of improvement, and the seeds that halve an interval. How
// well they cover on benches shaped like real ones: stats_calibration_test.cpp.

#include "overtake/eval/stats.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "overtake/core/random.hpp"

namespace overtake::eval {
namespace {

TEST(PoissonInterval, GarwoodsPublishedValues) {
  // Garwood (1936); e.g. the table of exact 95% limits in Ulm (1990), Am. J. Epidemiol.
  const Interval zero = poisson_interval(0);
  EXPECT_EQ(zero.lo, 0.0);
  EXPECT_NEAR(zero.hi, 3.6889, 1e-4);
  const Interval one = poisson_interval(1);
  EXPECT_NEAR(one.lo, 0.0253, 1e-4);
  EXPECT_NEAR(one.hi, 5.5716, 1e-4);
  const Interval ten = poisson_interval(10);
  EXPECT_NEAR(ten.lo, 4.7954, 1e-4);
  EXPECT_NEAR(ten.hi, 18.3904, 1e-4);
  // The two-sided 95% upper end after zero events is the one-sided 97.5% bound; the one-sided
  // 95% bound is -ln 0.05 = 3.00.
  EXPECT_NEAR(poisson_zero_upper_bound(), 2.9957, 1e-4);
  EXPECT_NEAR(poisson_zero_upper_bound(0.975), zero.hi, 1e-9);
}

TEST(PoissonInterval, BadInputIsRefused) {
  EXPECT_THROW((void)poisson_interval(-1), std::invalid_argument);
  EXPECT_THROW((void)poisson_interval(std::nan("")), std::invalid_argument);
  EXPECT_THROW((void)poisson_interval(1, 1.0), std::invalid_argument);
  EXPECT_THROW((void)poisson_interval(1, 0.0), std::invalid_argument);
  const std::vector<double> one = {1.0}, two = {1.0, 2.0}, negative = {-1.0};
  EXPECT_THROW((void)rate_interval(one, two, 100.0), std::invalid_argument);
  EXPECT_THROW((void)rate_interval(negative, one, 100.0), std::invalid_argument);
}

TEST(RateInterval, ZeroEventsGiveTheOneSidedUpperBound) {
  // Zero incidents in 440 miles over 20 seeds: 0 per 100 miles, at most 0.68 (one-sided 95%;
  // the two-sided interval's 0.84 is the one-sided 97.5% bound).
  const std::vector<double> none(20, 0.0), miles(20, 22.0);
  const RateInterval r = rate_interval(none, miles, 100.0);
  EXPECT_TRUE(r.upper_bound_only);
  EXPECT_EQ(r.ci.lo, 0.0);
  EXPECT_NEAR(r.ci.hi, 100.0 * 2.9957 / 440.0, 1e-3);
  const std::vector<double> no_miles(20, 0.0), some(20, 1.0);
  EXPECT_EQ(rate_interval(some, no_miles, 100.0).ci, (Interval{0.0, 0.0}));
}

TEST(RateInterval, EventsClusteredInSeedsWidenTheExactInterval) {
  // 7 events in 8 seeds of 22 miles, 1 0 2 0 3 0 0 1: Pearson X^2 = 10.14 over 7 degrees of
  // freedom, times (t(7) / z)^2 = 1.456: phi = 2.109; Garwood on 7 / phi events (scipy).
  const std::vector<double> y = {1, 0, 2, 0, 3, 0, 0, 1}, miles(8, 22.0);
  const RateInterval r = rate_interval(y, miles, 100.0);
  EXPECT_FALSE(r.upper_bound_only);
  EXPECT_NEAR(r.dispersion, 2.10907, 1e-4);
  EXPECT_NEAR(r.ci.lo, 0.91153, 1e-4);
  EXPECT_NEAR(r.ci.hi, 11.0771, 1e-3);
  EXPECT_NEAR(r.top_seed_share, 3.0 / 7.0, 1e-12);
  // The same 7 events spread as evenly as they can be: no extra dispersion, only t's.
  const std::vector<double> even = {1, 1, 1, 1, 1, 1, 1, 0};
  const RateInterval e = rate_interval(even, miles, 100.0);
  EXPECT_LT(e.ci.width(), r.ci.width());
  EXPECT_GT(e.ci.width(), 100.0 * poisson_interval(7).width() / 176.0);
}

TEST(MedianInterval, OrderStatisticsWithBinomialCoverage) {
  std::vector<double> v(20);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = static_cast<double>(20 - i);
  // n = 20: the 6th and 15th smallest (coverage 95.9%; the 7th and 14th would be 88.5%).
  EXPECT_EQ(median_interval(v), (Interval{6.0, 15.0}));
  // n = 8: the smallest and largest (99.2%; the 2nd and 7th would be 93.0%).
  const std::vector<double> eight = {5, 1, 8, 2, 7, 3, 6, 4};
  EXPECT_EQ(median_interval(eight), (Interval{1.0, 8.0}));
  const std::vector<double> same(9, 21.9);
  EXPECT_EQ(median_interval(same), (Interval{21.9, 21.9}));
  EXPECT_EQ(median({4, 1, 3, 2}), 2.5);
  EXPECT_EQ(median({}), 0.0);
}

TEST(MeanInterval, NearStudentsTForNormalData) {
  core::Rng rng(3);
  std::vector<double> miles(40), hours(40, 0.5);
  for (double& m : miles) {
    const double u1 = 1.0 - rng.uniform01(), u2 = rng.uniform01();
    m = 0.5 * (44.0 + 1.5 * std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2));
  }
  BootstrapOptions o;
  o.seed = bootstrap_seed("speed|x");
  const Interval ci = mean_interval(miles, hours, o);
  double sum = 0.0;
  for (const double m : miles) sum += m;
  const double mean = sum / 20.0;  // miles over hours
  double ss = 0.0;
  for (const double m : miles) ss += (2.0 * m - mean) * (2.0 * m - mean);
  const double se = std::sqrt(ss / 39.0 / 40.0);
  // With 40 normal seeds both bootstrap-t intervals are near Student's t(39) = 2.02.
  EXPECT_NEAR((mean - ci.lo) / se, 2.02, 0.3);
  EXPECT_NEAR((ci.hi - mean) / se, 2.02, 0.3);
  // The same data and key give the same interval; no spread, no width.
  EXPECT_EQ(mean_interval(miles, hours, o), ci);
  const std::vector<double> flat(10, 22.0), half(10, 0.5);
  EXPECT_EQ(mean_interval(flat, half, o), (Interval{44.0, 44.0}));
}

TEST(MeanInterval, OneSeedFarFromTheRestReachesFartherBelowAndNoFurtherThanTwiceStudents) {
  // Nine seeds near 48.5 mph and one stuck at 41 (a short run behind a slow car): the
  // interval reaches farther below the mean than above it, and at most 2 t(9) standard
  // errors either way (the bootstrap-t's quantiles explode: resamples without the slow seed
  // have almost no spread).
  const std::vector<double> speeds = {48.56, 48.56, 48.56, 48.59, 48.57,
                                      48.02, 41.12, 48.56, 48.5,  49.04};
  const std::vector<double> hours(10, 1.0);
  BootstrapOptions o;
  const Interval ci = mean_interval(speeds, hours, o);
  double mean = 0.0;
  for (const double v : speeds) mean += v / 10.0;
  double ss = 0.0;
  for (const double v : speeds) ss += (v - mean) * (v - mean);
  const double se = std::sqrt(ss / 9.0 / 10.0);
  EXPECT_LT(ci.lo, mean);
  EXPECT_GT(ci.hi, mean);
  EXPECT_GE(ci.lo, mean - 2.0 * 2.2622 * se - 1e-9);
  EXPECT_LE(ci.hi, mean + 2.0 * 2.2622 * se + 1e-9);
  EXPECT_GT(mean - ci.lo, 2.2622 * se);  // wider below than Student's
}

TEST(PairedDifferences, TheTTestsPValueIsStudents) {
  // scipy.stats.ttest_rel on these speeds: t = 2.424, p = 0.0458 (7 degrees of freedom).
  const std::vector<double> a = {44.1, 43.2, 45.0, 42.8, 44.9, 43.7, 44.4, 43.9};
  const std::vector<double> b = {43.5, 43.6, 44.1, 42.0, 44.2, 43.0, 44.8, 43.1};
  const std::vector<double> ones(8, 1.0);
  const PairedRatios p{a, ones, b, ones};
  EXPECT_NEAR(mean_difference_p_value(p), 0.045826, 1e-5);
  const PairedRatios same{a, ones, a, ones};
  EXPECT_EQ(mean_difference_p_value(same), 1.0);
  BootstrapOptions o;
  EXPECT_EQ(mean_difference_interval(same, o), (Interval{0.0, 0.0}));
  const Interval ci = mean_difference_interval(p, o);
  EXPECT_LT(ci.lo, 0.4625);  // around the difference, 0.4625
  EXPECT_GT(ci.hi, 0.4625);
  // Student's 95% interval (0.011 to 0.914, p = 0.046) barely excludes 0; the bootstrap-t's
  // span, built for skewed spreads, is wider with 8 seeds and reaches below it.
  EXPECT_LT(ci.lo, 0.011);
}

TEST(PairedDifferences, RatesByMoverFromBothIntervals) {
  // A: 4 events in 8 seeds of 20 miles (1 0 0 2 0 1 0 0), B: none. MOVER from A's interval
  // and B's two-sided upper end after no event (3.689 / 160 miles): scipy's values.
  const std::vector<double> ya = {1, 0, 0, 2, 0, 1, 0, 0}, yb(8, 0.0), miles(8, 20.0);
  const Interval ci = rate_difference_interval({ya, miles, yb, miles}, 100.0);
  EXPECT_NEAR(ci.lo, -0.62191, 1e-4);
  EXPECT_NEAR(ci.hi, 8.17082, 1e-3);
  // Nothing in either: from minus B's bound to A's.
  const Interval none = rate_difference_interval({yb, miles, yb, miles}, 100.0);
  EXPECT_NEAR(none.lo, -100.0 * 3.6889 / 160.0, 1e-3);
  EXPECT_NEAR(none.hi, 100.0 * 3.6889 / 160.0, 1e-3);
}

TEST(SignFlipTest, IsExactOverEveryAssignment) {
  // One event in each of 4 seeds for A, none for B, on equal miles: only the two assignments
  // that put all four on one side are as extreme: p = 2 / 16 (one-sided 1 / 16 = 0.0625).
  std::vector<double> ya(20, 0.0), yb(20, 0.0), miles(20, 22.0);
  for (int i = 0; i < 4; ++i) ya[static_cast<std::size_t>(i)] = 1.0;
  EXPECT_DOUBLE_EQ(rate_difference_p_value({ya, miles, yb, miles}, 1), 0.125);
  // Identical runs: nothing differs.
  EXPECT_EQ(rate_difference_p_value({ya, miles, ya, miles}, 1), 1.0);
  // Every one of 20 seeds the same way: the exact p would be 2^-19; a Monte Carlo of 20,000
  // draws gives 1 / 20001 (it never draws the observed assignment or its mirror, but counts
  // the observed one).
  std::vector<double> all(20, 1.0);
  EXPECT_NEAR(rate_difference_p_value({all, miles, yb, miles}, 1), 1.0 / 20001.0, 1e-12);
  // 20 seeds that differ every way (half up, half down): a Monte Carlo that stops at its 20th
  // draw as extreme as the data, p = 20 / 20 (Besag and Clifford).
  std::vector<double> up_down(20, 0.0);
  for (std::size_t i = 0; i < 20; ++i) up_down[i] = i % 2 ? 1.0 : 0.0;
  std::vector<double> down_up(20, 0.0);
  for (std::size_t i = 0; i < 20; ++i) down_up[i] = i % 2 ? 0.0 : 1.0;
  EXPECT_EQ(rate_difference_p_value({up_down, miles, down_up, miles}, 1), 1.0);
  // 12 seeds the same way (exact: 2 / 4096).
  std::vector<double> twelve(20, 0.0);
  for (int i = 0; i < 12; ++i) twelve[static_cast<std::size_t>(i)] = 2.0;
  EXPECT_DOUBLE_EQ(rate_difference_p_value({twelve, miles, yb, miles}, 1), 2.0 / 4096.0);
}

TEST(Holm, StepDownAdjustedPValues) {
  const std::vector<double> p = {0.01, 0.04, 0.03, 0.005};
  const std::vector<double> adjusted = holm_adjust(p);
  ASSERT_EQ(adjusted.size(), 4U);
  EXPECT_DOUBLE_EQ(adjusted[3], 0.02);  // 4 x 0.005
  EXPECT_DOUBLE_EQ(adjusted[0], 0.03);  // 3 x 0.01
  EXPECT_DOUBLE_EQ(adjusted[2], 0.06);  // 2 x 0.03
  EXPECT_DOUBLE_EQ(adjusted[1], 0.06);  // 1 x 0.04, raised to keep the order
  EXPECT_TRUE(holm_adjust({}).empty());
  const std::vector<double> big = {0.5, 0.9};
  EXPECT_EQ(holm_adjust(big), (std::vector<double>{1.0, 1.0}));
}

TEST(ProbabilityOfImprovement, OverAllPairsOfRunsTiesCountingHalf) {
  BootstrapOptions o;
  const std::vector<double> x = {2, 2, 1, 5}, y = {1, 2, 3, 4};
  // Every run of x against every run of y: 2 beats 1 and ties 2 (1.5, twice), 1 ties 1
  // (0.5), 5 beats all (4): 7.5 / 16.
  const Improvement higher = probability_of_improvement(x, y, true, o);
  EXPECT_DOUBLE_EQ(higher.p, 7.5 / 16.0);
  EXPECT_LE(higher.ci.lo, higher.p);
  EXPECT_GE(higher.ci.hi, higher.p);
  EXPECT_DOUBLE_EQ(probability_of_improvement(x, y, false, o).p, 1.0 - 7.5 / 16.0);
  // A shift of 0.1 on every seed is not "better with probability 1" when the runs spread.
  const std::vector<double> a = {43.1, 44.9, 42.0, 45.5, 43.8, 44.2},
                            b = {43.0, 44.8, 41.9, 45.4, 43.7, 44.1};
  const Improvement shift = probability_of_improvement(a, b, true, o);
  EXPECT_LT(shift.p, 0.6);
  EXPECT_GT(shift.p, 0.5);
  EXPECT_EQ(probability_of_improvement({}, {}, true, o).p, 0.5);
}

TEST(SeedsToHalve, FromTheSameMethods) {
  // t(n - 1) / sqrt(n) halves from 20 seeds at 73 (scipy), from 8 at 25.
  EXPECT_EQ(seeds_to_halve_mean(20), 73U);
  EXPECT_EQ(seeds_to_halve_mean(8), 25U);
  // No event: the bound goes as 1 / exposure, twice the seeds.
  const std::vector<double> none(20, 0.0), miles(20, 22.0);
  EXPECT_EQ(seeds_to_halve_rate(none, miles), 40U);
  // Many events spread as Poisson: about four times (a little less: t's degrees of freedom).
  const std::vector<double> many(20, 50.0);
  const std::size_t m = seeds_to_halve_rate(many, miles);
  EXPECT_GE(m, 70U);
  EXPECT_LE(m, 80U);
  // Few events: the exact interval's width shrinks slower than 1 / sqrt(exposure) at first.
  std::vector<double> few(20, 0.0);
  few[3] = 1.0;
  few[9] = 2.0;
  EXPECT_GT(seeds_to_halve_rate(few, miles), 40U);
}

}  // namespace
}  // namespace overtake::eval
