// `overtake risk` against brute force on the world (label `calibration`): with levels that
// split, the estimate of a weakened reference planner's at-fault rate agrees with the plain
// count of the same base runs, and the copies it makes are real branches. The estimator's
// coverage and gain on a process of exactly known rate: tests/eval/splitting_test.cpp.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "overtake/batch/risk.hpp"
#include "overtake/eval/stats.hpp"
#include "temp_dir.hpp"

namespace overtake::batch {
namespace {

TEST(RiskCalibration, SplittingAgreesWithThePlainCountOfItsBaseRuns) {
  const test::TempDir dir("overtake-risk-cal");
  const auto params = dir.path() / "split.json";
  std::ofstream(params) << R"({"margins_m": [4, 2, 0.25, 0.0], "splits": [2, 3, 2, 2]})";
  RiskSpec s;
  s.config = std::filesystem::path(OVERTAKE_SOURCE_DIR) / "tests/data/risk/weak2.json";
  s.params = params;
  s.minutes = 10.0;
  s.max_runs = 32;
  s.rel_error = 0.0;
  s.budget_hours = 1000.0;
  s.jobs = 2;
  s.out = dir.path() / "out";
  const RiskOutcome o = run_risk(s, nullptr, {});
  ASSERT_EQ(o.runs.size(), 32U);
  std::vector<double> plain, miles;
  std::size_t paths = 0;
  for (const RiskRun& r : o.runs) {
    plain.push_back(r.tally.base_events);
    miles.push_back(r.tally.exposure);
    paths += r.tally.paths;
  }
  const eval::RateInterval brute = eval::rate_interval(plain, miles, 1.0);
  double events = 0.0;
  for (double x : plain) events += x;
  ASSERT_GE(events, 3.0);  // the weakened planner's rate is about 2 per 100 mi
  const double brute_rate = events / o.miles / 1609.344;
  EXPECT_GT(paths, 10 * o.runs.size());  // the levels split
  EXPECT_GT(o.simulated_h, o.base_h);
  // Each estimate's interval holds the other's rate.
  EXPECT_LE(o.estimate.ci.lo, brute_rate);
  EXPECT_GE(o.estimate.ci.hi, brute_rate);
  EXPECT_LE(brute.ci.lo, o.estimate.rate);
  EXPECT_GE(brute.ci.hi, o.estimate.rate);
}

}  // namespace
}  // namespace overtake::batch
