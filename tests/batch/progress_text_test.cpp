// The batch commands' progress lines as text: what a terminal's status line shows.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "overtake/batch/progress.hpp"

namespace overtake::batch {
namespace {

using ::testing::HasSubstr;

TEST(ProgressText, DurationsReadAsSecondsMinutesOrHours) {
  EXPECT_EQ(duration_text(0.0), "0s");
  EXPECT_EQ(duration_text(59.9), "59s");
  EXPECT_EQ(duration_text(187.0), "3m07s");
  EXPECT_EQ(duration_text(7500.0), "2h05m");
}

TEST(ProgressText, ABenchShowsItsBarRunsMilesAndTimeToGo) {
  BenchProgress p;
  p.done = 3;
  p.total = 12;
  p.simulated_m = 1609.344 * 20.0;
  p.simulated_s = 1800.0;
  p.wall_s = 10.0;
  const std::string text = progress_text(p, 7200.0);
  EXPECT_THAT(text, HasSubstr("[######..................]"));  // a quarter of 24
  EXPECT_THAT(text, HasSubstr("3/12 runs"));
  EXPECT_THAT(text, HasSubstr("20.0 mi simulated"));
  EXPECT_THAT(text, HasSubstr("elapsed 10s"));
  EXPECT_THAT(text, HasSubstr("ETA 30s"));  // 3 times the simulated time left, at that pace
  p.done = 12;
  p.simulated_s = 7200.0;
  EXPECT_THAT(progress_text(p, 7200.0), HasSubstr("ETA 0s"));
  EXPECT_THAT(progress_text(BenchProgress{}, 0.0), HasSubstr("ETA 0s"));
}

TEST(ProgressText, HuntRiskAndTuneSayWhereTheyAre) {
  HuntProgress h;
  h.runs = 4;
  h.simulated_s = 3600.0;
  h.budget_s = 4 * 3600.0;
  h.failures = 2;
  h.groups = 1;
  h.wall_s = 60.0;
  EXPECT_THAT(progress_text(h), HasSubstr("hunt: 4 runs, 1.0 of 4.0 simulated h, 2 failures in 1 "
                                          "situations, 1.0 sim-h/min, at most 180 s to go"));
  RiskProgress r;
  r.runs = 7;
  r.simulated_h = 1.5;
  r.budget_h = 2.0;
  r.weighted_events = 3.0;
  r.rate_per_100mi = 0.125;
  r.rel_half_width = 0.5;
  r.wall_s = 9.0;
  EXPECT_THAT(progress_text(r), HasSubstr("risk: 7 runs, 1.5 of 2.0 simulated h, 3.00 weighted "
                                          "events, 0.1250 per 100 mi (+-50%), 9 s"));
  TuneProgress t;
  t.trial = 2;
  t.trials = 10;
  t.runs_done = 5;
  t.runs_total = 8;
  EXPECT_THAT(progress_text(t), HasSubstr("tune: trial 2 of 10, run 5/8   "));
  t.best = 45.1234;
  EXPECT_THAT(progress_text(t), HasSubstr("run 5/8, best 45.123"));
}

}  // namespace
}  // namespace overtake::batch
