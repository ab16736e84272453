// `overtake risk` (batch/risk.hpp) on short runs: events and parameters refused with their
// names, the same estimate whatever --jobs, a resumed estimate equal to one never stopped, a
// resume of another estimate refused, Ctrl-C keeping the finished runs. Its calibration
// against brute force: tests/calibration/risk_calibration_test.cpp.

#include "overtake/batch/risk.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <string>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/planners/catalog.hpp"
#include "overtake/run/config.hpp"
#include "temp_dir.hpp"

namespace overtake::batch {
namespace {

using ::testing::HasSubstr;

std::string usage_error(const std::function<void()>& f) {
  try {
    f();
  } catch (const base::UsageError& e) {
    return e.what();
  }
  return "";
}

RiskSpec short_spec(const std::filesystem::path& out) {
  RiskSpec s;
  s.minutes = 1.0;
  s.max_runs = 6;
  s.rel_error = 0.0;
  s.budget_hours = 1000.0;
  s.event = parse_risk_event("near-miss");  // common enough to count in minutes
  s.out = out;
  return s;
}

void write(const std::filesystem::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

TEST(RiskEvent, NamesAndRefusals) {
  EXPECT_EQ(parse_risk_event("at-fault").kind, RiskEventKind::at_fault);
  EXPECT_EQ(parse_risk_event("contact").kind, RiskEventKind::contact);
  EXPECT_EQ(parse_risk_event("near-miss").name(), "near-miss");
  const RiskEvent speeding = parse_risk_event("speeding");
  EXPECT_EQ(speeding.kind, RiskEventKind::incident);
  EXPECT_EQ(speeding.name(), "speeding");
  const std::string e = usage_error([] { (void)parse_risk_event("crash"); });
  EXPECT_THAT(e, HasSubstr("--event: 'crash'"));
  EXPECT_THAT(e, HasSubstr("outside_lane"));
}

TEST(RiskParams, ShippedOnesLoadAndBadKeysAreNamed) {
  const RiskParams p = load_risk_params(std::nullopt);
  EXPECT_EQ(p.margins_m.size(), p.splits.size());
  EXPECT_NO_THROW(p.levels().validate());
  const test::TempDir dir;
  const auto f = dir.path() / "p.json";
  const auto error = [&](const std::string& text) {
    write(f, text);
    try {
      (void)load_risk_params(f);
    } catch (const run::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_THAT(error(R"({"splits": [2, 2]})"), HasSubstr("splits: one per margin"));
  EXPECT_THAT(error(R"({"margins_m": [1, 2, 3, 4]})"), HasSubstr("margins_m: must decrease"));
  EXPECT_THAT(error(R"({"score": {"horizon": 3}})"), HasSubstr("score.horizon: is not a key"));
  EXPECT_THAT(error(R"({"splits": [1, 1, 1.5, 1]})"), HasSubstr("splits: must be whole"));
  EXPECT_THAT(error(R"({"levels": 3})"), HasSubstr("levels: is not a key"));
  EXPECT_THAT(error(R"({"splits": [1, 1, 1, 99]})"), HasSubstr("each from 1 to 50"));
}

TEST(RiskSpec, BadFlagsAreNamed) {
  const test::TempDir dir;
  RiskSpec s = short_spec(dir.path() / "o");
  s.minutes = 0.1;
  EXPECT_THAT(usage_error([&] { check_risk_spec(s); }), HasSubstr("--minutes"));
  s = short_spec(dir.path() / "o");
  s.traffic = "dense";
  EXPECT_THAT(usage_error([&] { check_risk_spec(s); }), HasSubstr("--traffic: 'dense'"));
  s = short_spec(dir.path() / "o");
  s.policy = "nobody";
  EXPECT_THAT(usage_error([&] { check_risk_spec(s); }), HasSubstr("--policy: 'nobody'"));
  s = short_spec(dir.path() / "o");
  s.budget_hours = 0;
  EXPECT_THAT(usage_error([&] { check_risk_spec(s); }), HasSubstr("--budget-hours"));
}

TEST(Risk, TheSameEstimateWhateverTheJobsAndSplitsThatSplit) {
  const test::TempDir dir;
  write(dir.path() / "split.json", R"({"margins_m": [6, 4, 2, 1], "splits": [2, 2, 1, 1]})");
  RiskSpec a = short_spec(dir.path() / "a");
  a.params = dir.path() / "split.json";
  a.jobs = 1;
  RiskSpec b = a;
  b.out = dir.path() / "b";
  b.jobs = 2;
  const RiskOutcome oa = run_risk(a, nullptr, {});
  const RiskOutcome ob = run_risk(b, nullptr, {});
  ASSERT_EQ(oa.runs.size(), 6U);
  EXPECT_EQ(oa.stopped_by, "max-runs");
  EXPECT_EQ(oa.estimate.rate, ob.estimate.rate);
  EXPECT_EQ(oa.estimate.ci, ob.estimate.ci);
  EXPECT_EQ(oa.simulated_h, ob.simulated_h);
  std::size_t paths = 0;
  for (const RiskRun& r : oa.runs) paths += r.tally.paths;
  EXPECT_GT(paths, oa.runs.size());  // copies were made
  EXPECT_GT(oa.simulated_h, oa.base_h);
  // The base runs are the plain runs: their exposure is the same with splitting or without.
  RiskSpec plain = short_spec(dir.path() / "plain");
  const RiskOutcome op = run_risk(plain, nullptr, {});
  EXPECT_EQ(op.miles, oa.miles);
  EXPECT_EQ(op.base_h, op.simulated_h);
  // What it wrote.
  const nlohmann::json j = run::read_json_file(a.out / "risk.json");
  for (const char* key :
       {"event", "rate_per_100mi", "ci95_per_100mi", "simulated_hours", "plain_mc_hours", "gain"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["event"], "near-miss");
  EXPECT_TRUE(std::filesystem::exists(a.out / "summary.md"));
}

TEST(Risk, AResumedEstimateIsTheOneNeverStoppedAndAnotherIsRefused) {
  const test::TempDir dir;
  RiskSpec whole = short_spec(dir.path() / "whole");
  const RiskOutcome ow = run_risk(whole, nullptr, {});
  RiskSpec part = short_spec(dir.path() / "part");
  part.max_runs = 3;
  (void)run_risk(part, nullptr, {});
  // Without --resume an --out holding an estimate is refused.
  part.max_runs = 6;
  EXPECT_THAT(usage_error([&] { (void)run_risk(part, nullptr, {}); }), HasSubstr("--resume"));
  // A resume of another event is refused, naming it.
  RiskSpec other = part;
  other.resume = true;
  other.event = parse_risk_event("contact");
  EXPECT_THAT(usage_error([&] { (void)run_risk(other, nullptr, {}); }), HasSubstr("event"));
  part.resume = true;
  const RiskOutcome resumed = run_risk(part, nullptr, {});
  EXPECT_EQ(resumed.resumed_runs, 3U);
  ASSERT_EQ(resumed.runs.size(), ow.runs.size());
  EXPECT_EQ(resumed.estimate.rate, ow.estimate.rate);
  EXPECT_EQ(resumed.estimate.ci, ow.estimate.ci);
  EXPECT_EQ(resumed.miles, ow.miles);
}

TEST(Risk, AStopKeepsTheFinishedRuns) {
  const test::TempDir dir;
  RiskSpec s = short_spec(dir.path() / "o");
  s.max_runs = 40;
  std::atomic<bool> stop{false};
  const RiskOutcome o = run_risk(s, &stop, [&](const RiskProgress& p) {
    if (p.runs >= 2) stop = true;
  });
  EXPECT_TRUE(o.interrupted);
  EXPECT_EQ(o.stopped_by, "interrupted");
  EXPECT_GE(o.runs.size(), 2U);
  EXPECT_LT(o.runs.size(), 40U);
  // They are in --out, and a resume goes on from them.
  s.resume = true;
  s.max_runs = o.runs.size() + 1;
  const RiskOutcome r = run_risk(s, nullptr, {});
  EXPECT_EQ(r.resumed_runs, o.runs.size());
  EXPECT_EQ(r.runs.size(), o.runs.size() + 1);
}

TEST(Risk, APlannerProgramIsEstimatedFromPlainRunsAndRefusedWhereTheLevelsSplit) {
  const test::TempDir dir;
  planners::PlannerFlags flags;
  flags.commands = {
      (std::filesystem::path(OVERTAKE_BINARY_DIR) / "tests" / "overtake_course_planner").string()};
  flags.names = {"course"};
  RiskSpec s = short_spec(dir.path() / "o");
  s.planners = planners::catalog_from_flags(flags);
  s.policy = "course";
  s.max_runs = 2;
  s.event = parse_risk_event("outside_lane");
  const RiskOutcome o = run_risk(s, nullptr, {});
  ASSERT_EQ(o.runs.size(), 2U);
  EXPECT_GT(o.miles, 0.5);
  EXPECT_EQ(o.simulated_h, o.base_h);
  for (const RiskRun& r : o.runs) EXPECT_EQ(r.tally.paths, 1U);
  // Copies would need the planner's state: refused, naming it.
  write(dir.path() / "split.json", R"({"splits": [2, 1, 1, 1]})");
  s.params = dir.path() / "split.json";
  s.out = dir.path() / "o2";
  const std::string e = usage_error([&] { check_risk_spec(s); });
  EXPECT_THAT(e, HasSubstr("planner from outside"));
  EXPECT_THAT(e, HasSubstr("plain runs"));
}

}  // namespace
}  // namespace overtake::batch
