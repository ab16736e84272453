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
#include "overtake/batch/bench.hpp"
#include "overtake/batch/bench_page.hpp"
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

TEST(Risk, ShardsMergeIntoTheEstimateOfOneRunHere) {
  const test::TempDir dir;
  write(dir.path() / "blocks.json", R"({"batch_runs": 3, "min_runs_with_events": 2})");
  RiskSpec local = short_spec(dir.path() / "local");
  local.params = dir.path() / "blocks.json";
  local.policy = "seed003";  // a near miss in most runs of 3 min
  local.minutes = 3.0;
  local.max_runs = 14;
  local.rel_error = 0.9;  // stops at a block before max-runs
  local.jobs = 2;
  const RiskOutcome ol = run_risk(local, nullptr, {});
  ASSERT_EQ(ol.stopped_by, "rel-error");
  ASSERT_LT(ol.runs.size(), 14U);
  ASSERT_EQ(ol.runs.size() % 3, 0U);
  // Three shards: each runs all of its planned runs (the stopping rules are the merge's).
  EXPECT_EQ(risk_runs_planned(local), 14U);
  std::vector<std::filesystem::path> shards;
  for (int i = 1; i <= 3; ++i) {
    RiskSpec s = local;
    s.shard = {i, 3};
    s.jobs = 1;
    s.out = dir.path() / ("shard-" + std::to_string(i));
    const RiskOutcome o = run_risk(s, nullptr, {});
    EXPECT_EQ(o.stopped_by, "shard");
    EXPECT_EQ(o.runs.size(), s.shard.size_of(14));
    for (const RiskRun& r : o.runs) EXPECT_TRUE(s.shard.holds(r.index));
    shards.push_back(s.out);
  }
  RiskSpec merged = local;
  merged.out = dir.path() / "merged";
  const RiskOutcome om = merge_risk(merged, shards, nullptr);
  EXPECT_EQ(om.stopped_by, ol.stopped_by);
  ASSERT_EQ(om.runs.size(), ol.runs.size());
  EXPECT_EQ(om.estimate.rate, ol.estimate.rate);
  EXPECT_EQ(om.estimate.ci, ol.estimate.ci);
  EXPECT_EQ(om.simulated_h, ol.simulated_h);
  EXPECT_THAT(om.merged_note, HasSubstr("3 of 3 shards, 14 runs"));
  // The merged folder is an estimate as a local run writes it: a resume goes on with it.
  RiskSpec more = merged;
  more.resume = true;
  more.rel_error = 0.0;
  const RiskOutcome resumed = run_risk(more, nullptr, {});
  EXPECT_EQ(resumed.resumed_runs, ol.runs.size());
  EXPECT_EQ(resumed.runs.size(), 14U);
  // Without shard 2 the runs from 0 end at run 1: the estimate is of run 0 alone, and says so.
  RiskSpec gap = local;
  gap.out = dir.path() / "gap";
  const RiskOutcome og = merge_risk(gap, {shards[0], shards[2]}, nullptr);
  EXPECT_EQ(og.runs.size(), 1U);
  EXPECT_EQ(og.stopped_by, "shards");
  // What cannot be merged is refused, naming it.
  RiskSpec again = local;
  again.out = dir.path() / "again";
  EXPECT_THAT(usage_error([&] {
                (void)merge_risk(again, {shards[0], shards[0]}, nullptr);
              }),
              HasSubstr("given twice"));
  RiskSpec other = again;
  other.event = parse_risk_event("contact");
  EXPECT_THAT(usage_error([&] { (void)merge_risk(other, shards, nullptr); }),
              HasSubstr("is a shard of another event"));
  EXPECT_THAT(usage_error([&] { (void)merge_risk(merged, shards, nullptr); }),
              HasSubstr("already holds an estimate"));
  // A shard's folder goes on only as that shard.
  RiskSpec whole = local;
  whole.out = shards[0];
  whole.resume = true;
  EXPECT_THAT(usage_error([&] { (void)run_risk(whole, nullptr, {}); }), HasSubstr("--shard"));
  RiskSpec bad = local;
  bad.shard = {4, 3};
  EXPECT_THAT(usage_error([&] { check_risk_spec(bad); }), HasSubstr("--shard"));
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

// The tests' course planner as a --planner-cmd: `wrapper` around it (sh), named "course".
RiskSpec program_spec(const std::filesystem::path& out, const std::string& command) {
  planners::PlannerFlags flags;
  flags.commands = {command};
  flags.names = {"course"};
  RiskSpec s = short_spec(out);
  s.planners = planners::catalog_from_flags(flags);
  s.policy = "course";
  s.event = parse_risk_event("outside_lane");
  return s;
}

std::string course_planner() {
  return (std::filesystem::path(OVERTAKE_BINARY_DIR) / "tests" / "overtake_course_planner")
      .string();
}

TEST(Risk, APlannersFailureEndsItsRunThereAndIsNeverTheEvent) {
  const test::TempDir dir;
  // The second run's planner crashes after 600 answers (about 24 s); the others drive on. One
  // job: the runs start in order, so the counter tells them apart.
  const std::string counter = (dir.path() / "count").string();
  const std::string cmd = "n=$(cat " + counter + " 2>/dev/null || echo 0); echo $((n+1)) > " +
                          counter + "; if [ \"$n\" = 1 ]; then exec " + course_planner() +
                          " --crash-after 600; else exec " + course_planner() + "; fi";
  RiskSpec s = program_spec(dir.path() / "o", cmd);
  s.max_runs = 8;
  s.jobs = 1;
  const RiskOutcome o = run_risk(s, nullptr, {});
  ASSERT_EQ(o.runs.size(), 8U);
  for (std::size_t k = 0; k < o.runs.size(); ++k) EXPECT_EQ(o.runs[k].base_failed(), k == 1) << k;
  ASSERT_TRUE(o.runs[1].base_failed());
  ASSERT_EQ(o.runs[1].failures.size(), 1U);
  const RiskFailure& f = o.runs[1].failures[0];
  EXPECT_GT(f.t_s, 5.0);
  EXPECT_LT(f.t_s, 50.0);
  EXPECT_FALSE(f.reason.empty());
  // What it drove until then counts, and no more.
  EXPECT_GT(o.runs[1].tally.exposure, 0.0);
  EXPECT_LT(o.runs[1].tally.exposure, 0.9 * o.runs[0].tally.exposure);
  EXPECT_NEAR(o.runs[1].tally.base_cost, f.t_s, 0.1);
  double metres = 0.0;
  for (const RiskRun& r : o.runs) metres += r.tally.exposure;
  EXPECT_NEAR(o.miles, metres / 1609.344, 1e-9);
  // Said in risk.json and the summary, with its seed and time.
  const nlohmann::json j = run::read_json_file(s.out / "risk.json");
  EXPECT_EQ(j["runs_ended_by_planner"], 1);
  ASSERT_EQ(j["planner_failures"].size(), 1U);
  EXPECT_EQ(j["planner_failures"][0]["seed"], s.first_seed + 1);
  EXPECT_EQ(j["planner_failures"][0]["path"], 0);
  const std::string md = base::read_file(s.out / "summary.md");
  EXPECT_THAT(md, HasSubstr("ended by the planner's failure | 1 of 8 runs"));
  EXPECT_THAT(md, HasSubstr("run 1 (seed " + std::to_string(s.first_seed + 1) + ")"));
  // A comparison says so, and still compares the speeds (a failed run counts what it drove).
  const nlohmann::json c = compare_risk_folders(s.out, s.out);
  ASSERT_FALSE(c["notes"].empty());
  EXPECT_THAT(c["notes"][0].get<std::string>(), HasSubstr("1 of 8 runs ended by the planner"));
  ASSERT_TRUE(c["speed_on_common_seeds"].is_object()) << c.dump(2);
  EXPECT_EQ(c["speed_on_common_seeds"]["seeds"], 8);
  // Kept through a resume.
  s.resume = true;
  s.max_runs = 9;
  const RiskOutcome again = run_risk(s, nullptr, {});
  ASSERT_EQ(again.runs.size(), 9U);
  EXPECT_EQ(again.runs[1].failures, o.runs[1].failures);
}

TEST(Risk, APlannerThatFailsInEveryRunStopsTheEstimateNamingTheFailure) {
  const test::TempDir dir;
  RiskSpec s = program_spec(dir.path() / "o", course_planner() + " --crash-after 100");
  s.max_runs = 40;
  std::string what;
  try {
    (void)run_risk(s, nullptr, {});
  } catch (const std::runtime_error& e) {
    what = e.what();
  }
  EXPECT_THAT(what, HasSubstr("failed in every one of the 16 runs"));
  EXPECT_THAT(what, HasSubstr("seed " + std::to_string(s.first_seed)));
  EXPECT_THAT(what, HasSubstr("runs.jsonl"));
  // Its runs are kept.
  std::ifstream runs(s.out / "runs.jsonl");
  int lines = 0;
  for (std::string line; std::getline(runs, line);) ++lines;
  EXPECT_EQ(lines, 16);
}

TEST(Risk, TheBaseRunsEventsAreCutIntoScenariosThatRepeatThem) {
  const test::TempDir dir;
  RiskSpec s = short_spec(dir.path() / "o");
  s.policy = "seed003";  // about 20 contacts per 100 mi: several in 16 runs of 3 min
  s.event = parse_risk_event("contact");
  s.minutes = 3.0;
  s.max_runs = 16;
  s.scenarios = 3;
  const RiskOutcome o = run_risk(s, nullptr, {});
  ASSERT_TRUE(o.cut.has_value()) << o.cut_note;
  EXPECT_EQ(o.cut_note, "");
  // The hunt found the estimate's own first three events: the same seeds, the same times.
  std::vector<std::pair<std::uint64_t, double>> events;
  for (const RiskRun& r : o.runs) {
    for (const eval::SplitEvent& e : r.tally.events) events.emplace_back(r.seed, e.at);
  }
  ASSERT_GE(events.size(), 3U);
  ASSERT_EQ(o.cut->failures.size(), 3U);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(o.cut->failures[i].seed, events[i].first) << i;
    EXPECT_NEAR(o.cut->failures[i].t_s, events[i].second, 0.05) << i;
  }
  // Each group's scenarios were cut and repeat the contact.
  ASSERT_FALSE(o.cut->groups.empty());
  for (const HuntGroup& g : o.cut->groups) {
    EXPECT_EQ(g.cut_error, "") << g.situation;
    EXPECT_TRUE(g.reproduced) << g.situation << ": " << g.reproduces_reactive;
    EXPECT_TRUE(std::filesystem::exists(s.out / "events" / g.reactive)) << g.reactive;
  }
  const nlohmann::json j = run::read_json_file(s.out / "risk.json");
  EXPECT_EQ(j["scenarios"]["folder"], "events");
  EXPECT_EQ(j["scenarios"]["events"], 3);
  EXPECT_EQ(j["scenarios"]["groups"].size(), o.cut->groups.size());
  EXPECT_THAT(base::read_file(s.out / "summary.md"), HasSubstr("The events cut into scenarios"));
  // None asked: none cut. A near miss has no time to cut at: said.
  s.scenarios = 0;
  s.out = dir.path() / "none";
  EXPECT_FALSE(run_risk(s, nullptr, {}).cut.has_value());
  EXPECT_FALSE(std::filesystem::exists(s.out / "events"));
  RiskSpec near = short_spec(dir.path() / "near");
  near.max_runs = 2;
  EXPECT_THAT(run_risk(near, nullptr, {}).cut_note, HasSubstr("near misses"));
  s.scenarios = -1;
  EXPECT_THAT(usage_error([&] { check_risk_spec(s); }), HasSubstr("--scenarios"));
}

TEST(Risk, TwoEstimatesOnTheSameSeedsCompareTheirSpeedsPairedBySeed) {
  const test::TempDir dir;
  // The reference against seed000 (a lane keeper) on the same eight seeds of 2 minutes.
  RiskSpec a = short_spec(dir.path() / "reference");
  a.event = parse_risk_event("at-fault");
  a.minutes = 2.0;
  a.max_runs = 8;
  a.jobs = 2;
  RiskSpec b = a;
  b.policy = "seed000";
  b.out = dir.path() / "seed000";
  const RiskOutcome oa = run_risk(a, nullptr, {});
  const RiskOutcome ob = run_risk(b, nullptr, {});
  const nlohmann::json c = compare_risk_folders(a.out, b.out);
  const nlohmann::json& speed = c["speed_on_common_seeds"];
  ASSERT_TRUE(speed.is_object()) << c.dump(2);
  EXPECT_EQ(speed["seeds"], 8);
  // The speeds are the estimates' own (miles over hours of the same runs).
  EXPECT_NEAR(speed["base_mph"].get<double>(), oa.miles / oa.base_h, 1e-9);
  EXPECT_NEAR(speed["candidate_mph"].get<double>(), ob.miles / ob.base_h, 1e-9);
  const double d = speed["difference_mph"].get<double>();
  EXPECT_NEAR(d, ob.miles / ob.base_h - oa.miles / oa.base_h, 1e-9);
  const double lo = speed["ci95_mph"][0].get<double>();
  const double hi = speed["ci95_mph"][1].get<double>();
  EXPECT_LT(lo, d);
  EXPECT_GT(hi, d);
  EXPECT_EQ(speed["verdict"], lo > 0.0 ? "faster" : (hi < 0.0 ? "slower" : "no difference"));
  EXPECT_THAT(compare_risk_text(c), HasSubstr("seeds both drove"));
  // The same planner against itself: no difference, exactly 0.
  const nlohmann::json self = compare_risk_folders(a.out, a.out);
  EXPECT_EQ(self["speed_on_common_seeds"]["difference_mph"], 0.0);
  EXPECT_EQ(self["speed_on_common_seeds"]["verdict"], "no difference");
  // Estimates of other seeds share none: no speeds, and the note says why.
  RiskSpec other = a;
  other.first_seed = 1001;
  other.max_runs = 2;
  other.out = dir.path() / "other";
  (void)run_risk(other, nullptr, {});
  const nlohmann::json none = compare_risk_folders(a.out, other.out);
  EXPECT_TRUE(none["speed_on_common_seeds"].is_null());
  ASSERT_FALSE(none["notes"].empty());
  EXPECT_THAT(none["notes"][0].get<std::string>(), HasSubstr("share 0 seeds"));
}

TEST(Risk, AnAtFaultEstimateIsAPointOfTheBenchPagesChart) {
  const test::TempDir dir;
  RiskSpec s = short_spec(dir.path() / "fault");
  s.event = parse_risk_event("at-fault");
  s.max_runs = 2;
  const RiskOutcome o = run_risk(s, nullptr, {});
  const nlohmann::json p = risk_chart_point(s.out);
  EXPECT_EQ(p["label"], "reference (risk)");
  EXPECT_EQ(p["traffic"], "faithful");
  EXPECT_NEAR(p["mean_speed_mph"].get<double>(), o.miles / o.base_h, 1e-9);
  EXPECT_GT(p["mean_speed_mph"].get<double>(), 20.0);
  EXPECT_EQ(p["ci95_per_100mi"].size(), 2U);
  // The bench page's object carries it.
  BenchSpec bench;
  bench.policies = {"reference"};
  bench.traffic = {"faithful"};
  bench.seeds = {1};
  bench.minutes = 1.0;
  bench.out = dir.path() / "bench";
  (void)run_bench(bench, nullptr, {});
  const nlohmann::json page = bench_report_object(bench.out, dir.path(), {s.out});
  ASSERT_EQ(page["risk"].size(), 1U);
  EXPECT_EQ(page["risk"][0], p);
  EXPECT_EQ(bench_report_object(bench.out, dir.path())["risk"].size(), 0U);
  // An estimate of another event is not on the chart's axis: refused, naming the file.
  RiskSpec near = short_spec(dir.path() / "near");
  near.max_runs = 1;
  (void)run_risk(near, nullptr, {});
  try {
    (void)risk_chart_point(near.out);
    ADD_FAILURE() << "a near-miss estimate was taken";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("risk.json"));
    EXPECT_THAT(e.what(), HasSubstr("at-fault"));
  }
}

// The knob from cautious to assertive (planner.reference.assertiveness) on fixed seeds: at
// 0.75 the reference drives faster than at 0 (seeds 1-16 x 5 min: 46.74 against 45.82 mph),
// which is the point of turning it (docs/figures.md, "The speed-risk frontier").
TEST(Frontier, TheKnobsAssertiveEndDrivesFasterOnFixedSeeds) {
  const test::TempDir dir;
  write(dir.path() / "a0.75.json", R"({"planner": {"reference": {"assertiveness": 0.75}}})");
  const auto mean_mph = [&](const std::string& name, std::optional<std::filesystem::path> config) {
    BenchSpec bench;
    bench.policies = {"reference"};
    bench.traffic = {"faithful"};
    for (std::uint64_t seed = 1; seed <= 16; ++seed) bench.seeds.push_back(seed);
    bench.minutes = 5.0;
    bench.jobs = 2;
    bench.config = std::move(config);
    bench.out = dir.path() / name;
    (void)run_bench(bench, nullptr, {});
    return run::read_json_file(bench.out / "summary.json")["rows"][0]["mean_speed_mph"]
        .get<double>();
  };
  const double cautious = mean_mph("a0", std::nullopt);
  const double assertive = mean_mph("a0.75", dir.path() / "a0.75.json");
  EXPECT_NEAR(cautious, 45.82, 0.01);
  EXPECT_NEAR(assertive, 46.74, 0.01);
  EXPECT_GT(assertive, cautious + 0.5);
}

}  // namespace
}  // namespace overtake::batch
