// The evaluation's methods measured on benches shaped like real ones (calibration.hpp): every
// interval covers the true figure at least 93% of the time at 8 and 20 seeds, over 1,000
// synthetic benches per shape (the rubric's latched incidents: 90%, and none where they come
// in bursts of dozens); `compare --fail-if-worse` fails benches equal in distribution
// at most 5% of the time (its verdicts corrected for the family of figures and profiles it
// judges); a real +1 mph change is found. docs/evaluation.md ("Calibration") gives the
// figures these tests measure; `overtake_stats_calibration` prints them in full.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "calibration.hpp"

namespace overtake::eval::calibration {
namespace {

constexpr int kDraws = 1000;
constexpr double kMinCoverage = 0.93;
const std::vector<std::string> kPolicies = {"reference", "walkthrough", "seed000", "seed001",
                                            "seed002",   "seed003",     "seed004"};
const std::vector<std::string> kTraffic = {"faithful", "calm"};
/// A rate whose events come in bursts of dozens within a seed (the per-seed counts' variance
/// over their mean above 20; 1 for Poisson counts) is out of any interval's reach at 8 or 20
/// seeds: a sample without the few bursting seeds cannot tell how rare they are. In these
/// rows, only seed003's rubric incidents (83-150: collisions latched for minutes in a few
/// faithful seeds, speeding for minutes in 4 calm seeds of 100); every other shape is below 5.
constexpr double kBurstDispersion = 20.0;

bool bursts(const Population& p, Rate r) {
  return dispersion(p, r) > kBurstDispersion;
}

TEST(Calibration, TheRowsAreWhatTheDocsDescribe) {
  for (const char* set : {"a30", "b30", "a10"}) {
    for (const auto& p : kPolicies) {
      for (const auto& t : kTraffic) {
        const Population& pop = population(set, p, t);
        EXPECT_EQ(pop.size(), 100U) << pop.name();
        EXPECT_EQ(pop.seed.front(), 1U);
        EXPECT_EQ(pop.seed.back(), 100U);
      }
    }
  }
  // The rates out of reach are exactly seed003's rubric incidents.
  std::vector<std::string> handful;
  for (const auto& [key, pop] : rows()) {
    if (pop.set == "b30") continue;
    for (const Rate r : kRates) {
      if (bursts(pop, r)) handful.push_back(pop.name() + " " + name(r));
    }
  }
  EXPECT_EQ(handful, (std::vector<std::string>{
                         "a10 seed003 / calm incidents", "a10 seed003 / faithful incidents",
                         "a30 seed003 / calm incidents", "a30 seed003 / faithful incidents"}));
}

TEST(Calibration, MeanSpeedIntervalsCover) {
  for (const char* set : {"a30", "a10"}) {
    for (const auto& p : kPolicies) {
      for (const auto& t : kTraffic) {
        const Population& pop = population(set, p, t);
        for (const std::size_t n : {8U, 20U}) {
          const double c = speed_coverage(pop, n, kDraws, 101 + n, 2000);
          EXPECT_GE(c, kMinCoverage) << pop.name() << ", " << n << " seeds";
        }
      }
    }
  }
}

/// The rubric's incidents are counted again every second a condition lasts, so they cluster
/// in seeds even without bursts; when a planner has them in only a few seeds of a hundred, a
/// sample of 8 or 20 seeds with none at all is likely, and the exact bound after no event
/// (which takes events one at a time) falls short: seed001 and seed002 in calm traffic cover
/// 90-91% at one of the two seed counts. Every other rate (collisions as contacts, near
/// misses) takes events one at a time and holds 93%.
constexpr double kMinIncidentCoverage = 0.90;

TEST(Calibration, RateIntervalsCover) {
  for (const char* set : {"a30", "a10"}) {
    for (const auto& p : kPolicies) {
      for (const auto& t : kTraffic) {
        const Population& pop = population(set, p, t);
        for (const Rate r : kRates) {
          if (true_rate(pop, r) == 0.0 || bursts(pop, r)) continue;
          const double least = r == Rate::incidents ? kMinIncidentCoverage : kMinCoverage;
          for (const std::size_t n : {8U, 20U}) {
            const double c = rate_coverage(pop, r, n, kDraws, 201 + n);
            EXPECT_GE(c, least) << pop.name() << " " << name(r) << ", " << n << " seeds";
          }
        }
      }
    }
  }
}

TEST(Calibration, PairedSpeedDifferenceIntervalsCover) {
  // Real pairs: the reference planner against every other policy on the same seeds (30- and
  // 10-minute runs), and the twins (the reference planner and seed004 against themselves
  // nudged, whose runs part within minutes).
  std::vector<std::pair<const Population*, const Population*>> pairs;
  for (const char* set : {"a30", "a10"}) {
    for (const auto& t : kTraffic) {
      for (std::size_t k = 1; k < kPolicies.size(); ++k) {
        pairs.emplace_back(&population(set, "reference", t), &population(set, kPolicies[k], t));
      }
    }
  }
  for (const char* p : {"reference", "seed004"}) {
    for (const auto& t : kTraffic) {
      pairs.emplace_back(&population("a30", p, t), &population("b30", p, t));
    }
  }
  for (const auto& [a, b] : pairs) {
    for (const std::size_t n : {8U, 20U}) {
      const double c = speed_difference_coverage(*a, *b, n, kDraws, 301 + n, 1000);
      EXPECT_GE(c, kMinCoverage) << a->name() << " - " << b->name() << ", " << n << " seeds";
    }
  }
}

TEST(Calibration, PairedRateDifferenceIntervalsCover) {
  for (const auto& t : kTraffic) {
    for (std::size_t i = 0; i < kPolicies.size(); ++i) {
      for (std::size_t j = i + 1; j < kPolicies.size(); ++j) {
        const Population& a = population("a30", kPolicies[i], t);
        const Population& b = population("a30", kPolicies[j], t);
        for (const Rate r : kRates) {
          if (bursts(a, r) || bursts(b, r)) continue;
          if (true_rate(a, r) == 0.0 && true_rate(b, r) == 0.0) continue;
          const double least = r == Rate::incidents ? kMinIncidentCoverage : kMinCoverage;
          for (const std::size_t n : {8U, 20U}) {
            const double c = rate_difference_coverage(a, b, r, n, kDraws, 401 + n);
            EXPECT_GE(c, least) << a.name() << " - " << b.name() << " " << name(r) << ", " << n
                                << " seeds";
          }
        }
      }
    }
  }
}

TEST(Calibration, TheGateRarelyFailsBenchesEqualInDistribution) {
  // One policy, both profiles, every default figure: 10 tests per comparison. Benches drawn
  // on independent seeds from the same 100 (equal in distribution, not paired): 150 draws of
  // each policy at 20 seeds.
  int draws = 0, failed = 0;
  for (const auto& p : kPolicies) {
    const GateOutcome g = gate(150, 501, policy_benches("a30", "a30", p, 20, false));
    draws += g.draws;
    failed += g.failed;
    EXPECT_EQ(g.withheld, 0);
  }
  EXPECT_LE(static_cast<double>(failed) / draws, 0.05) << failed << " of " << draws;
  // The twins, paired by seed (a planner against itself nudged, each seed's two runs to the
  // arms in a random order): 500 draws each.
  for (const char* p : {"reference", "seed004"}) {
    const GateOutcome g = gate(500, 502, policy_benches("a30", "b30", p, 20, true));
    EXPECT_LE(g.failure_rate(), 0.05) << p << ": " << g.failed << " of " << g.draws;
  }
}

TEST(Calibration, AnAACompareOfEveryPolicyPassesTheGateAtLeast95PercentOfTheTime) {
  // The construction that once failed 23% of the time: a real 7-policy, 20-seed bench, each
  // row's distance scaled by independent 4% noise, twice; all 70 figures judged at once.
  const GateOutcome g = gate(kDraws, 601, noisy_benches(20, 0.04));
  EXPECT_GE(1.0 - g.failure_rate(), 0.95) << g.failed << " of " << g.draws;
  EXPECT_EQ(g.withheld, 0);
}

TEST(Calibration, ARealChangeOfOneMphIsFound) {
  // The reference planner against its twin made 1 mph faster (every run's distance raised by
  // its hours x 1 mph), over both profiles as the gate judges them. In calm traffic (runs
  // spread 0.5 mph) 20 seeds find it nearly always; in faithful traffic (1.5 mph, and
  // paired runs part within minutes) it takes 50 seeds to find it 80% of the time.
  const GateOutcome calm = gate(300, 701, policy_benches("a30", "b30", "reference", 20, true, 1.0),
                                "reference / calm: mean_speed_mph");
  EXPECT_GE(calm.better_rate(), 0.8);
  const GateOutcome faithful =
      gate(300, 702, policy_benches("a30", "b30", "reference", 50, true, 1.0),
           "reference / faithful: mean_speed_mph");
  EXPECT_GE(faithful.better_rate(), 0.8);
  EXPECT_LE(faithful.failure_rate(), 0.05);  // and nothing is called worse
}

}  // namespace
}  // namespace overtake::eval::calibration
