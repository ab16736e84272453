// Multilevel splitting (eval/splitting.hpp) on a chain whose rate is known exactly: the
// estimate is unbiased, its interval covers, it costs less than plain runs for the same
// variance, and a tree of paths is the same for the same seeds. The coverage on the
// simulator itself: tests/calibration/risk_calibration_test.cpp.

#include "overtake/eval/splitting.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "eval/birth_death.hpp"

namespace overtake::eval {
namespace {

using testing::BirthDeath;
using testing::BirthDeathSystem;
using testing::chain_levels;
using testing::estimate_chain;

TEST(SplitLevels, RefusesWhatCannotBeLevels) {
  EXPECT_THROW((SplitLevels{{1.0, 2.0}, {2}}).validate(), std::invalid_argument);
  EXPECT_THROW((SplitLevels{{2.0, 1.0}, {2, 2}}).validate(), std::invalid_argument);
  EXPECT_THROW((SplitLevels{{1.0}, {0}}).validate(), std::invalid_argument);
  EXPECT_NO_THROW((SplitLevels{{1.0, 2.0}, {3, 1}}).validate());
  const SplitLevels l{{1.0, 2.0}, {3, 3}};
  EXPECT_EQ(l.level_of(0.5), 0);
  EXPECT_EQ(l.level_of(1.0), 1);
  EXPECT_EQ(l.level_of(7.0), 2);
}

TEST(SplitEstimate, ExactRateOfTheChain) {
  // A chain short enough to count by brute force: its exact rate against a long plain run.
  const BirthDeath chain{.top = 6, .up = 0.3, .down = 0.5, .steps = 2'000'000};
  BirthDeathSystem sys(chain, 7);
  long events = 0;
  for (long t = 0; t < chain.steps; ++t) events += sys.advance().events;
  const double plain = static_cast<double>(events) / static_cast<double>(chain.steps);
  EXPECT_NEAR(plain / chain.exact_rate(), 1.0, 0.03) << plain << " vs " << chain.exact_rate();
}

TEST(Splitting, WithoutSplitsIsThePlainRun) {
  const BirthDeath chain{.top = 6, .steps = 5000};
  SplitLevels none{{2.0, 4.0}, {1, 1}};
  BirthDeathSystem a(chain, 3);
  BirthDeathSystem b(chain, 3);
  const SplitTally t = run_split(a, none, {});
  long plain = 0;
  for (long s = 0; s < chain.steps; ++s) plain += b.advance().events;
  EXPECT_EQ(t.weighted_events, static_cast<double>(plain));
  EXPECT_EQ(t.base_events, plain);
  EXPECT_EQ(t.paths, 1U);
  EXPECT_EQ(t.cost, static_cast<double>(chain.steps));
}

TEST(Splitting, SameSeedsSameTree) {
  const BirthDeath chain{.top = 14, .steps = 4000};
  const SplitLevels levels = chain_levels(chain, 3, 4);
  BirthDeathSystem a(chain, 11);
  BirthDeathSystem b(chain, 11);
  const SplitTally ta = run_split(a, levels, {.seed = 5});
  const SplitTally tb = run_split(b, levels, {.seed = 5});
  EXPECT_EQ(ta.weighted_events, tb.weighted_events);
  EXPECT_EQ(ta.paths, tb.paths);
  EXPECT_EQ(ta.cost, tb.cost);
  EXPECT_GT(ta.paths, 1U);
  // The base path is the plain run: its events and exposure are those of the run unsplit.
  BirthDeathSystem c(chain, 11);
  const SplitTally plain = run_split(c, chain_levels(chain, 2, 1), {});
  EXPECT_EQ(ta.base_events, plain.base_events);
  EXPECT_EQ(ta.exposure, plain.exposure);
}

TEST(Splitting, TooManyPathsIsAnError) {
  const BirthDeath chain{.top = 14, .steps = 20000};
  BirthDeathSystem sys(chain, 1);
  EXPECT_THROW((void)run_split(sys, chain_levels(chain, 1, 20), {.max_paths = 1000}),
               SplitExplosion);
}

TEST(Splitting, UnbiasedAndCoveredAtARareRate) {
  // Rate about 1e-5 per step: a plain run of 2,000 steps sees an event once in ~50 runs.
  const BirthDeath chain{.top = 20, .up = 0.3, .down = 0.5, .steps = 2000};
  const double exact = chain.exact_rate();
  ASSERT_GT(exact, 1e-6);
  ASSERT_LT(exact, 1e-4);
  const SplitLevels levels = chain_levels(chain, 3, 4);
  int covered = 0;
  double sum = 0.0, cost = 0.0, var = 0.0;
  constexpr int kEstimates = 200;
  for (int k = 0; k < kEstimates; ++k) {
    const auto e = estimate_chain(chain, levels, 40, 1000 + k);
    if (e.estimate.ci.lo <= exact && exact <= e.estimate.ci.hi) ++covered;
    sum += e.estimate.rate;
    var += (e.estimate.rate - exact) * (e.estimate.rate - exact);
    cost += e.cost;
  }
  const double mean = sum / kEstimates;
  const double sd_mean = std::sqrt(var / kEstimates / kEstimates);
  EXPECT_NEAR(mean, exact, 3.0 * sd_mean) << "mean " << mean << " exact " << exact;
  EXPECT_GE(covered, 180) << covered << " of " << kEstimates;
  // Work-normalised gain: plain runs need rate / variance steps for the same variance.
  const double per_estimate_var = var / kEstimates;
  const double plain_cost = exact / per_estimate_var;
  const double gain = plain_cost / (cost / kEstimates);
  EXPECT_GT(gain, 10.0) << "gain " << gain;
}

TEST(RateRatio, EndsAndOneSidedBounds) {
  const RateEstimate a{2.0, {1.0, 4.0}, false};
  const RateEstimate b{4.0, {2.0, 8.0}, false};
  const RateRatio r = rate_ratio(a, b);
  EXPECT_DOUBLE_EQ(r.ratio, 2.0);
  // log 2 -+ hypot(log 2, log 2).
  EXPECT_NEAR(r.ci.lo, std::exp(std::log(2.0) - std::hypot(std::log(2.0), std::log(2.0))), 1e-12);
  EXPECT_NEAR(r.ci.hi, std::exp(std::log(2.0) + std::hypot(std::log(2.0), std::log(2.0))), 1e-12);
  EXPECT_EQ(r.verdict, "no difference");
  const RateEstimate none{0.0, {0.0, 0.5}, true};
  const RateRatio lower = rate_ratio(a, none);
  EXPECT_EQ(lower.ci.hi, 0.5);
  EXPECT_EQ(lower.verdict, "lower");
  const RateRatio higher = rate_ratio(none, a);
  EXPECT_FALSE(higher.defined);
  EXPECT_EQ(higher.ci.lo, 2.0);
  EXPECT_EQ(higher.verdict, "higher");
  EXPECT_EQ(rate_ratio(none, none).verdict, "no verdict");
}

TEST(RateRatio, FalseAlarmsAtOneRateAndPowerAtTwo) {
  // Split estimates of the chain's rate (40 base runs each): two of the same rate are judged
  // different at most about 5% of the time; rates four times apart nearly always.
  const BirthDeath same{.top = 17, .up = 0.3, .down = 0.5, .steps = 2000};
  const BirthDeath rarer{.top = 20, .up = 0.3, .down = 0.5, .steps = 2000};
  ASSERT_GT(same.exact_rate() / rarer.exact_rate(), 4.0);
  const auto est = [](const BirthDeath& chain, std::uint64_t seed) {
    const SplitEstimate e = estimate_chain(chain, chain_levels(chain, 3, 4), 40, seed).estimate;
    return RateEstimate{e.rate, e.ci, e.upper_bound_only};
  };
  int alarms = 0, found = 0;
  constexpr int kPairs = 150;
  for (int k = 0; k < kPairs; ++k) {
    const RateEstimate a = est(same, 5000 + 2 * k);
    if (rate_ratio(a, est(same, 5001 + 2 * k)).verdict != "no difference") ++alarms;
    if (rate_ratio(a, est(rarer, 9000 + k)).verdict == "lower") ++found;
  }
  EXPECT_LE(alarms, 12) << alarms << " of " << kPairs;  // 5% is 7.5
  EXPECT_GE(found, 120) << found << " of " << kPairs;
}

}  // namespace
}  // namespace overtake::eval
