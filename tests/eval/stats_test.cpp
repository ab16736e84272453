// The intervals against published values and known truths: Garwood's exact Poisson intervals,
// a bootstrap's coverage on synthetic data with a known mean (about 95% over many draws), the
// probability of improvement, and the seeds that halve an interval.

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
  // 90%: 0 events -> 2.9957 (= -ln 0.05).
  EXPECT_NEAR(poisson_interval(0, 0.90).hi, -std::log(0.05), 1e-9);
}

TEST(PoissonInterval, ARateOfZeroIsNotAnIntervalOfZero) {
  // Zero incidents in 440 miles: 0 per 100 miles, up to 0.84.
  const Interval r = rate_interval(0, 440.0, 100.0);
  EXPECT_EQ(r.lo, 0.0);
  EXPECT_NEAR(r.hi, 0.838, 5e-4);
  EXPECT_EQ(rate_interval(3, 0.0, 100.0), (Interval{0.0, 0.0}));  // no exposure
}

TEST(PoissonInterval, BadInputIsRefused) {
  EXPECT_THROW((void)poisson_interval(-1), std::invalid_argument);
  EXPECT_THROW((void)poisson_interval(std::nan("")), std::invalid_argument);
  EXPECT_THROW((void)poisson_interval(1, 1.0), std::invalid_argument);
  EXPECT_THROW((void)poisson_interval(1, 0.0), std::invalid_argument);
}

/// A normal draw (Box-Muller) from the project's portable generator.
double normal(core::Rng& rng, double mean, double sd) {
  const double u1 = 1.0 - rng.uniform01();
  const double u2 = rng.uniform01();
  return mean + sd * std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * 3.141592653589793 * u2);
}

TEST(Bootstrap, AMeansIntervalCoversTheTrueMeanAbout95PercentOfTheTime) {
  constexpr int kTrials = 1000;
  constexpr int kRuns = 30;
  constexpr double kMean = 43.0;
  core::Rng data(7);
  int covered = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    std::vector<double> x(kRuns), ones(kRuns, 1.0);
    for (double& v : x) v = normal(data, kMean, 2.0);
    BootstrapOptions o;
    o.resamples = 2000;
    o.seed = static_cast<std::uint64_t>(trial);
    const Interval ci = bootstrap_ratio(x, ones, o);
    if (ci.lo <= kMean && kMean <= ci.hi) ++covered;
  }
  const double coverage = static_cast<double>(covered) / kTrials;
  // The percentile bootstrap of a mean of 30 runs covers a little under 95%.
  EXPECT_GT(coverage, 0.92);
  EXPECT_LT(coverage, 0.97);
}

TEST(Bootstrap, APairedDifferencesIntervalCoversTheTrueDifference) {
  // Two planners on the same seeds: the seed moves both (shared noise), the candidate is
  // 0.5 faster on average with its own noise.
  constexpr int kTrials = 600;
  constexpr int kSeeds = 25;
  core::Rng data(11);
  int covered = 0, beyond_noise = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    std::vector<double> a(kSeeds), b(kSeeds), ones(kSeeds, 1.0);
    for (int i = 0; i < kSeeds; ++i) {
      const double seed_effect = normal(data, 43.0, 3.0);
      b[static_cast<std::size_t>(i)] = seed_effect + normal(data, 0.0, 0.5);
      a[static_cast<std::size_t>(i)] = seed_effect + 0.5 + normal(data, 0.0, 0.5);
    }
    BootstrapOptions o;
    o.resamples = 2000;
    o.seed = static_cast<std::uint64_t>(trial);
    const Interval ci = bootstrap_ratio_difference(a, ones, b, ones, o);
    if (ci.lo <= 0.5 && 0.5 <= ci.hi) ++covered;
    if (ci.excludes_zero()) ++beyond_noise;
  }
  EXPECT_GT(static_cast<double>(covered) / kTrials, 0.92);
  EXPECT_LT(static_cast<double>(covered) / kTrials, 0.97);
  // Pairing takes the seeds' spread (sd 3) out: 0.5 over 25 seeds with sd 0.7 per pair is
  // found beyond noise most of the time (unpaired, with the seeds' sd 3, hardly ever).
  EXPECT_GT(static_cast<double>(beyond_noise) / kTrials, 0.8);
}

TEST(Bootstrap, TheSameDataAndKeyGiveTheSameInterval) {
  const std::vector<double> miles = {7.1, 7.3, 6.9, 7.4, 7.0},
                            hours = {0.17, 0.17, 0.17, 0.17, 0.17};
  BootstrapOptions o;
  o.seed = bootstrap_seed("speed|reference|faithful");
  EXPECT_EQ(bootstrap_ratio(miles, hours, o), bootstrap_ratio(miles, hours, o));
  BootstrapOptions other = o;
  other.seed = bootstrap_seed("speed|reference|calm");
  EXPECT_NE(o.seed, other.seed);
  // Identical pairs: a difference of exactly 0.
  EXPECT_EQ(bootstrap_ratio_difference(miles, hours, miles, hours, o), (Interval{0.0, 0.0}));
  EXPECT_FALSE((Interval{0.0, 0.0}).excludes_zero());
  EXPECT_TRUE((Interval{0.1, 0.2}).excludes_zero());
  EXPECT_TRUE((Interval{-0.2, -0.1}).excludes_zero());
}

TEST(Bootstrap, MedianOfConstantsAndOfASample) {
  BootstrapOptions o;
  const std::vector<double> same(9, 21.9);
  EXPECT_EQ(bootstrap_median(same, o), (Interval{21.9, 21.9}));
  const std::vector<double> v = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
  const Interval ci = bootstrap_median(v, o);
  EXPECT_LE(ci.lo, 6.0);
  EXPECT_GE(ci.hi, 6.0);
  EXPECT_GE(ci.lo, 1.0);
  EXPECT_LE(ci.hi, 11.0);
  EXPECT_EQ(median({4, 1, 3, 2}), 2.5);
  EXPECT_EQ(median({}), 0.0);
}

TEST(ProbabilityOfImprovement, SharesOfSeedsTiesCountingHalf) {
  EXPECT_DOUBLE_EQ(probability_of_improvement(std::vector<double>{2, 2, 1, 5},
                                              std::vector<double>{1, 2, 3, 4}, true),
                   (1 + 0.5 + 0 + 1) / 4.0);
  EXPECT_DOUBLE_EQ(probability_of_improvement(std::vector<double>{2, 2, 1, 5},
                                              std::vector<double>{1, 2, 3, 4}, false),
                   (0 + 0.5 + 1 + 0) / 4.0);
  EXPECT_DOUBLE_EQ(probability_of_improvement({}, {}, true), 0.5);
}

TEST(SeedsToHalve, FourTimesTheSeedsForABootstrapTwiceToFourTimesForARate) {
  EXPECT_EQ(seeds_to_halve_bootstrap(20), 80u);
  // With no event the exact interval's width is 3.69 / exposure: twice the exposure halves it.
  EXPECT_EQ(seeds_to_halve_rate(0, 20), 40u);
  // With many, the width goes as sqrt(k) / exposure: about four times.
  const std::size_t many = seeds_to_halve_rate(1000, 20);
  EXPECT_GE(many, 78u);
  EXPECT_LE(many, 82u);
  const std::size_t few = seeds_to_halve_rate(3, 20);
  EXPECT_GT(few, 40u);
  EXPECT_LT(few, many);
  EXPECT_EQ(seeds_to_halve_rate(3, 0), 0u);
}

}  // namespace
}  // namespace overtake::eval
