// Scenario suites and hunting: expectations judged as scenarios say, a folder run for every
// policy with a pass/fail table and exit status, and `hunt` finding the same failures
// whatever the number of jobs, each with a scenario that reproduces it.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/batch/hunt.hpp"
#include "overtake/batch/suite_run.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/scenarios/suite.hpp"
#include "process_support.hpp"
#include "temp_dir.hpp"

namespace overtake::batch {

using base::read_file;
using base::UsageError;
using base::write_file_atomic;
using run::drive;
using run::DriveOptions;
using run::read_json_file;
using scenarios::judge_scenario;
using scenarios::judged_distance_m;
using scenarios::ScenarioTrace;
using scenarios::ScenarioVerdict;
using scenarios::suite_table;
using scenarios::SuiteOutcome;
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using ::testing::HasSubstr;

class TempDir : public test::TempDir {
 public:
  TempDir() : test::TempDir("overtake-suite") {}
};

/// A contact with a car at `t` that the rubric counts `counts` times (once a second).
void add_collision(sim::RunReport& r, double t, sim::CollisionKind kind, bool at_fault,
                   int counts = 1) {
  const int contact = static_cast<int>(r.contacts.size());
  for (int k = 0; k < counts; ++k) {
    sim::Incident i;
    i.type = sim::IncidentType::collision;
    i.t_s = t + k;
    i.collision = sim::CollisionClass{kind, at_fault};
    i.contact = contact;
    r.incidents.push_back(i);
  }
  r.contacts.push_back({contact + 1, t, t + counts - 1, 0.0, 1, {kind, at_fault}, counts});
}

TEST(JudgeScenario, NoExpectationMeansNoAtFaultCollision) {
  sim::Scenario sc;
  sim::RunReport r;
  ScenarioTrace trace;
  EXPECT_TRUE(judge_scenario(sc, r, trace).empty());
  add_collision(r, 3.0, sim::CollisionKind::hit_from_behind, false);
  EXPECT_TRUE(judge_scenario(sc, r, trace).empty());  // not the ego's fault
  add_collision(r, 4.0, sim::CollisionKind::ego_lane_change, true);
  const auto fails = judge_scenario(sc, r, trace);
  ASSERT_EQ(fails.size(), 1U);
  EXPECT_THAT(fails[0], HasSubstr("1 at-fault collision (at most 0)"));
  EXPECT_THAT(fails[0], HasSubstr("ego_lane_change at t 4.00 s"));
}

TEST(JudgeScenario, EachLimitIsChecked) {
  sim::Scenario sc;
  sc.expect.max_collisions = 0;
  sc.expect.max_incidents = 1;
  sc.expect.reach_lane = 2;
  sc.expect.reach_lane_by_s = 10.0;
  sc.expect.min_distance_m = 100.0;
  sim::RunReport r;
  r.distance_m = 50.0;
  add_collision(r, 3.0, sim::CollisionKind::hit_from_behind, false);
  sim::Incident jerk;
  jerk.type = sim::IncidentType::max_jerk;
  jerk.t_s = 5.0;
  r.incidents.push_back(jerk);
  ScenarioTrace trace;
  trace.lane_reached_s = {0.0, 0.0, 12.5};
  const auto fails = judge_scenario(sc, r, trace);
  ASSERT_EQ(fails.size(), 4U);
  EXPECT_THAT(fails[0], HasSubstr("1 collision (at most 0)"));
  EXPECT_THAT(fails[1], HasSubstr("2 incidents (at most 1)"));
  EXPECT_THAT(fails[2], HasSubstr("did not reach lane 2 by t 10.0 s (reached it at t 12.50 s)"));
  EXPECT_THAT(fails[3], HasSubstr("drove 50.0 m, less than 100.0 m"));
  // Within the limits, it passes.
  r.distance_m = 150.0;
  r.incidents.pop_back();
  sc.expect.max_collisions = 1;
  trace.lane_reached_s[2] = 9.0;
  EXPECT_TRUE(judge_scenario(sc, r, trace).empty());
}

TEST(JudgeScenario, OneContactIsOneCollisionHoweverOftenTheRubricCountedIt) {
  // A contact the rubric counted three times (3 s of contact): one collision, three of the
  // rubric's incidents.
  sim::Scenario sc;
  sc.expect.max_collisions = 1;
  sim::RunReport r;
  add_collision(r, 3.0, sim::CollisionKind::ego_hit_car_ahead, true, 3);
  ScenarioTrace trace;
  EXPECT_TRUE(judge_scenario(sc, r, trace).empty());
  sc.expect.max_at_fault_collisions = 0;
  auto fails = judge_scenario(sc, r, trace);
  ASSERT_EQ(fails.size(), 1U);
  EXPECT_THAT(fails[0], HasSubstr("1 at-fault collision (at most 0)"));
  sc.expect.max_at_fault_collisions.reset();
  sc.expect.max_incidents = 2;
  fails = judge_scenario(sc, r, trace);
  ASSERT_EQ(fails.size(), 1U);
  EXPECT_THAT(fails[0], HasSubstr("3 incidents (at most 2)"));
}

TEST(JudgeScenario, TheLeadInIsNotJudgedAndAFailedPlannerFails) {
  sim::Scenario sc;
  sc.cut.emplace();
  sc.cut->lead_in_s = 10.0;
  sim::RunReport r;
  r.duration_s = 20.0;
  add_collision(r, 105.0, sim::CollisionKind::ego_lane_change, true);
  ScenarioTrace trace;
  trace.start_s = 100.0;
  EXPECT_TRUE(judge_scenario(sc, r, trace).empty());  // 5 s in: the lead-in
  add_collision(r, 111.0, sim::CollisionKind::ego_lane_change, true);
  EXPECT_EQ(judge_scenario(sc, r, trace).size(), 1U);
  r.incidents.clear();
  r.contacts.clear();
  r.outcome = {sim::RunEnd::planner_failed, 104.0, "stalled"};
  const auto fails = judge_scenario(sc, r, trace);
  ASSERT_EQ(fails.size(), 1U);
  EXPECT_THAT(fails[0], HasSubstr("the planner failed: stalled"));
}

// min_distance_m counted the lead-in: 600 m passed where the judged part drove 442 m.
TEST(JudgeScenario, TheDistanceIsCountedAfterTheLeadIn) {
  sim::Scenario sc;
  sc.cut.emplace();
  sc.cut->lead_in_s = 10.0;
  sc.expect.min_distance_m = 500.0;
  sim::RunReport r;
  r.distance_m = 600.0;
  r.duration_s = 20.0;
  ScenarioTrace trace;
  trace.start_s = 100.0;
  trace.lead_in_distance_m = 158.0;
  EXPECT_DOUBLE_EQ(judged_distance_m(r, trace), 442.0);
  const auto fails = judge_scenario(sc, r, trace);
  ASSERT_EQ(fails.size(), 1U);
  EXPECT_EQ(fails[0], "drove 442.0 m after the lead-in, less than 500.0 m");
  trace.lead_in_distance_m = 90.0;
  EXPECT_TRUE(judge_scenario(sc, r, trace).empty());
}

// A run over within its lead-in has nothing judged: it fails instead of passing.
TEST(JudgeScenario, ARunOverWithinItsLeadInFails) {
  sim::Scenario sc;
  sc.cut.emplace();
  sc.cut->lead_in_s = 10.0;
  sim::RunReport r;
  r.duration_s = 4.0;
  add_collision(r, 103.0, sim::CollisionKind::ego_lane_change, true);
  ScenarioTrace trace;
  trace.start_s = 100.0;
  const auto fails = judge_scenario(sc, r, trace);
  ASSERT_EQ(fails.size(), 1U);
  EXPECT_EQ(fails[0], "the run lasted 4.00 s, within the lead-in (10.00 s): nothing was judged");
  r.duration_s = 10.0;  // it reached the judged part, which holds no collision
  EXPECT_TRUE(judge_scenario(sc, r, trace).empty());
}

// A failure of several lines, or a '|', broke suite.md's table.
TEST(SuiteTable, EveryVerdictStaysOneRowOfSevenCells) {
  SuiteOutcome o;
  ScenarioVerdict v;
  v.file = "a|b.json";
  v.policy = "reference";
  v.failures = {
      "could not run: x.json: invalid scenario\n  - scenario.cars: expected a list\r\n"
      "  - scenario.speed: unknown key",
      "one | two"};
  o.verdicts = {v, v};
  o.failed = 2;
  const std::string table = suite_table(o);
  EXPECT_THAT(table, HasSubstr("| a\\|b.json | reference | **FAIL** |"));
  EXPECT_THAT(table, HasSubstr("invalid scenario<br>  - scenario.cars: expected a list<br>  - "
                               "scenario.speed: unknown key; one \\| two |"));
  std::istringstream lines(table);
  std::string line;
  int rows = 0;
  while (std::getline(lines, line) && !line.empty()) {
    ++rows;
    int cells = 0;  // the '|' not escaped, less the one ending the row
    for (std::size_t i = 0; i < line.size(); ++i) {
      if (line[i] == '|' && (i == 0 || line[i - 1] != '\\')) ++cells;
    }
    EXPECT_EQ(cells - 1, 7) << line;
  }
  EXPECT_EQ(rows, 4);  // the header, its rule and the two verdicts
}

fs::path library() {
  return fs::path(OVERTAKE_SOURCE_DIR) / "data/scenarios";
}

/// A scripted scenario of 2 s that every policy passes.
void write_short_scenario(const fs::path& file) {
  std::ofstream(file) << R"({"duration_s": 2, "ego": {"s_m": 300, "lane": 1, "speed_mps": 0}})";
}

// One symlink loop named *.json stopped the whole suite with no table: a file that cannot be
// read is one failed row, the others still run, and suite.md and suite.json are written.
TEST(ScenarioSuite, AFileThatCannotBeReadIsOneFailedRow) {
  TempDir dir;
  const fs::path scenarios = dir.path() / "s";
  fs::create_directories(scenarios / "folder.json");
  write_short_scenario(scenarios / "good.json");
  fs::create_symlink("loop.json", scenarios / "loop.json");
  fs::create_symlink("nowhere", scenarios / "dangling.json");
  std::ofstream(scenarios / "bad|name.json") << R"({"speed": 3, "cars": 5})";
  SuiteSpec spec;
  spec.dir = scenarios;
  spec.policies = {"reference"};
  spec.out = dir.path() / "out";
  const SuiteOutcome o = run_suite(spec, nullptr, {});
  ASSERT_EQ(o.verdicts.size(), 5U);  // in name order
  EXPECT_EQ(o.verdicts[0].file, "bad|name.json");
  EXPECT_THAT(o.verdicts[0].failures.front(), HasSubstr("invalid scenario\n"));
  EXPECT_EQ(o.verdicts[1].file, "dangling.json");
  EXPECT_EQ(o.verdicts[1].failures,
            std::vector<std::string>{"cannot read: No such file or directory"});
  EXPECT_EQ(o.verdicts[2].file, "folder.json");
  EXPECT_EQ(o.verdicts[2].failures, std::vector<std::string>{"cannot read: a folder, not a file"});
  EXPECT_EQ(o.verdicts[3].file, "good.json");
  EXPECT_TRUE(o.verdicts[3].pass);
  EXPECT_EQ(o.verdicts[4].file, "loop.json");
  EXPECT_EQ(o.verdicts[4].failures,
            std::vector<std::string>{"cannot read: Too many levels of symbolic links"});
  EXPECT_EQ(o.passed, 1U);
  EXPECT_EQ(o.failed, 4U);
  EXPECT_EQ(read_json_file(*spec.out / "suite.json")["verdicts"].size(), 5U);
  const std::string table = read_file(*spec.out / "suite.md");
  EXPECT_THAT(table, HasSubstr("| loop.json | reference | **FAIL** | 0 | 0 (0) | 0.0 | cannot "
                               "read: Too many levels of symbolic links |\n"));
  EXPECT_THAT(table, HasSubstr("| bad\\|name.json |"));
  EXPECT_THAT(table, HasSubstr("invalid scenario<br>  - "));
  EXPECT_THAT(table, HasSubstr("\n\n1 passed, 4 failed\n"));
}

// Driven: the distance judged is the run's less what the ego drove in the lead-in, read
// from the frames.
TEST(ScenarioSuite, TheJudgedDistanceStartsAfterTheLeadIn) {
  TempDir dir;
  json j = read_json_file(library() / "seed001-default-faithful-ego-lane-change.json");
  const fs::path whole = dir.path() / "whole.json";
  std::ofstream(whole) << j.dump();
  DriveOptions d;
  d.scenario = whole;
  d.minutes_from_scenario = true;
  d.policy = "reference";
  const double whole_m = drive(d).report.distance_m;
  const fs::path scenarios = dir.path() / "s";
  fs::create_directories(scenarios);
  j["cut"]["lead_in_s"] = 10.0;
  j["expect"] = {{"min_distance_m", 300.0}};
  std::ofstream(scenarios / "lead.json") << j.dump();
  SuiteSpec spec;
  spec.dir = scenarios;
  spec.policies = {"reference"};
  const SuiteOutcome o = run_suite(spec, nullptr, {});
  ASSERT_EQ(o.verdicts.size(), 1U);
  const ScenarioVerdict& v = o.verdicts[0];
  // 20 s at about 22 m/s (the first step's 0.45 m included: the referee goes on from the run's,
  // which knows where the ego was a step before); the last 10 s are judged.
  EXPECT_NEAR(whole_m, 444.09, 0.01);
  EXPECT_NEAR(v.distance_m, 222.31, 0.01);
  ASSERT_EQ(v.failures.size(), 1U);
  EXPECT_EQ(v.failures[0], "drove 222.3 m after the lead-in, less than 300.0 m");
}

// A suite with its scenarios folder as --out read its own suite.json as a scenario the next
// time; and it replaced whatever suite.md or suite.json --out held.
TEST(ScenarioSuite, WritesOnlyWhereItMay) {
  TempDir dir;
  const fs::path scenarios = dir.path() / "s";
  fs::create_directories(scenarios);
  write_short_scenario(scenarios / "a.json");
  SuiteSpec spec;
  spec.dir = scenarios;
  spec.policies = {"reference"};
  const auto error_of = [&](const fs::path& out) {
    spec.out = out;
    try {
      (void)run_suite(spec, nullptr, {});
    } catch (const UsageError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_THAT(error_of(scenarios), HasSubstr("--out: " + scenarios.string() +
                                             " is the scenarios folder; the suite's suite.json "
                                             "would be read as a scenario"));
  EXPECT_THAT(error_of(dir.path() / "s" / "." / ""), HasSubstr("is the scenarios folder"));
  EXPECT_FALSE(fs::exists(scenarios / "suite.json"));
  // A subfolder is fine (the suite does not look into subfolders), and so is running again
  // into a folder that holds a suite's outputs.
  EXPECT_EQ(error_of(scenarios / "out"), "");
  EXPECT_EQ(error_of(scenarios / "out"), "");
  EXPECT_EQ(read_json_file(scenarios / "out" / "suite.json")["verdicts"].size(), 1U);
  // Files of the same names that no suite wrote are not replaced.
  for (const char* name : {"suite.md", "suite.json"}) {
    const fs::path other = dir.path() / (std::string("other-") + name);
    fs::create_directories(other);
    std::ofstream(other / name) << "{\"mine\": true}\n";
    EXPECT_THAT(error_of(other), HasSubstr("--out: " + (other / name).string() +
                                           " was not written by an overtake suite and would be "
                                           "replaced; move it away, or give another --out"));
    EXPECT_EQ(read_file(other / name), "{\"mine\": true}\n");
    EXPECT_EQ(fs::exists(other / "suite.json"), std::string(name) == "suite.json");
  }
  // Nor are the files of a replays/ or logs/ folder beside no suite's verdicts.
  const fs::path theirs = dir.path() / "theirs";
  fs::create_directories(theirs / "replays");
  std::ofstream(theirs / "replays" / "a-reference.otr") << "my own replay\n";
  EXPECT_THAT(error_of(theirs), HasSubstr("--out: " + (theirs / "replays").string() +
                                          " holds files no overtake suite wrote there"));
  EXPECT_EQ(read_file(theirs / "replays" / "a-reference.otr"), "my own replay\n");
  // A suite's verdicts in the scenarios folder (left by an older overtake) are not a scenario.
  fs::copy_file(scenarios / "out" / "suite.json", scenarios / "suite.json");
  spec.out.reset();
  const SuiteOutcome o = run_suite(spec, nullptr, {});
  ASSERT_EQ(o.verdicts.size(), 1U);
  EXPECT_EQ(o.verdicts[0].file, "a.json");
  EXPECT_EQ(o.skipped, std::vector<std::string>{"suite.json"});
  // ... but a scenario that happens to be named suite.json is one.
  write_short_scenario(scenarios / "suite.json");
  EXPECT_EQ(run_suite(spec, nullptr, {}).verdicts.size(), 2U);
}

TEST(ScenarioSuite, RunsAFolderForEveryPolicyAndSaysWhatFailed) {
  TempDir dir;
  const fs::path scenarios = dir.path() / "s";
  fs::create_directories(scenarios);
  for (const char* f :
       {"seed001-default-faithful-ego-lane-change.json", "scripted-all-lanes-blocked.json"}) {
    fs::copy_file(library() / f, scenarios / f);
  }
  // Reach the left lane within 5 s of a scripted cut-in: the reference planner keeps its lane.
  std::ofstream(scenarios / "reach.json") << R"({"name": "reach", "duration_s": 8,
      "ego": {"s_m": 300, "lane": 1, "speed_mps": 20},
      "expect": {"reach_lane": {"lane": 0, "by_s": 5}}})";
  std::ofstream(scenarios / "broken.json") << "{";
  SuiteSpec spec;
  spec.dir = scenarios;
  spec.policies = {"reference", "seed001"};
  spec.jobs = 2;
  spec.out = dir.path() / "out";
  const SuiteOutcome o = run_suite(spec, nullptr, {});
  ASSERT_EQ(o.verdicts.size(), 8U);
  const auto verdict = [&](const std::string& file, const std::string& policy) {
    for (const auto& v : o.verdicts) {
      if (v.file == file && v.policy == policy) return v;
    }
    ADD_FAILURE() << "no verdict for " << file << " / " << policy;
    return ScenarioVerdict{};
  };
  EXPECT_TRUE(verdict("seed001-default-faithful-ego-lane-change.json", "reference").pass);
  const ScenarioVerdict failed =
      verdict("seed001-default-faithful-ego-lane-change.json", "seed001");
  EXPECT_FALSE(failed.pass);
  EXPECT_GE(failed.at_fault_collisions, 1);
  EXPECT_THAT(failed.failures.front(), HasSubstr("ego_lane_change at t 79.36 s"));
  EXPECT_TRUE(fs::exists(dir.path() / "out" / failed.replay));  // the failed run's replay
  EXPECT_TRUE(verdict("scripted-all-lanes-blocked.json", "reference").pass);
  EXPECT_FALSE(verdict("reach.json", "reference").pass);
  EXPECT_THAT(verdict("broken.json", "reference").failures.front(), HasSubstr("could not run"));
  EXPECT_EQ(o.passed + o.failed, 8U);
  const json written = read_json_file(dir.path() / "out" / "suite.json");
  EXPECT_EQ(written["verdicts"].size(), 8U);
  EXPECT_THAT(read_file(dir.path() / "out" / "suite.md"), HasSubstr("| **FAIL** |"));
}

int run_binary(const std::string& args) {
  const std::string cmd = std::string(OVERTAKE_BINARY_DIR) + "/overtake " + args + " > /dev/null";
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST(ScenarioSuite, TheExitStatusSaysWhetherAnyFailed) {
  TempDir dir;
  fs::copy_file(library() / "seed001-default-faithful-ego-lane-change.json", dir.path() / "a.json");
  EXPECT_EQ(run_binary("bench -q --scenarios " + dir.path().string() + " --policies reference"), 0);
  EXPECT_EQ(run_binary("bench -q --scenarios " + dir.path().string() + " --policies seed001"), 1);
  EXPECT_EQ(run_binary("bench -q --scenarios " + dir.path().string() + " --seeds 1-3"), 2);
  EXPECT_EQ(run_binary("bench -q --scenarios " + (dir.path() / "none").string()), 2);
}

TEST(Hunt, FindsTheSameFailuresWhateverTheJobsAndEachScenarioReproducesIt) {
  std::string first;
  TempDir dir;
  for (const int jobs : {1, 2}) {
    fs::remove_all(dir.path() / "hunt");
    HuntSpec spec;
    spec.policy = "seed001";
    spec.traffic = {"faithful"};
    spec.minutes = 2.0;
    spec.failures = 2;
    spec.budget_hours = 1.0;
    spec.jobs = jobs;
    spec.out = dir.path() / "hunt";
    const HuntOutcome o = run_hunt(spec, nullptr, {});
    ASSERT_EQ(o.failures.size(), 2U);
    EXPECT_FALSE(o.groups.empty());
    json j = read_json_file(spec.out / "hunt.json");
    j.erase("timing");
    if (first.empty()) {
      first = j.dump();
    } else {
      EXPECT_EQ(j.dump(), first);
    }
    EXPECT_TRUE(fs::is_empty(spec.out / "runs"));  // only the failing runs' replays are kept
    for (const HuntGroup& g : o.groups) {
      const HuntFailure& f = o.failures[g.failures.front()];
      EXPECT_TRUE(fs::exists(spec.out / f.replay));
      for (const std::string& scenario : {g.reactive, g.replayed}) {
        DriveOptions d;
        d.scenario = spec.out / scenario;
        d.minutes_from_scenario = true;
        d.policy = "seed001";
        bool again = false;
        for (const sim::Incident& i : drive(d).report.incidents) {
          again =
              again || (i.type == sim::IncidentType::collision && std::abs(i.t_s - f.t_s) < 1e-6);
        }
        EXPECT_TRUE(again) << scenario << " does not repeat " << f.what << " at " << f.t_s;
      }
    }
  }
}

HuntSpec small_hunt(const fs::path& out) {
  HuntSpec spec;
  spec.policy = "seed001";
  spec.traffic = {"faithful"};
  spec.minutes = 2.0;
  spec.failures = 3;
  spec.budget_hours = 1.0;
  spec.jobs = 2;
  spec.out = out;
  return spec;
}

// A file of a hunt's folder with the folder named OUT.
std::string comparable(const fs::path& dir, const std::string& file) {
  std::string text = read_file(dir / file);
  for (std::size_t at = text.find(dir.string()); at != std::string::npos;
       at = text.find(dir.string())) {
    text.replace(at, dir.string().size(), "OUT");
  }
  return text;
}

// hunt.json with its timing left out and the folder it was written in named OUT.
std::string comparable(const fs::path& dir) {
  json j = json::parse(comparable(dir, "hunt.json"));
  j.erase("timing");
  return j.dump(1);
}

// Each shard hunts its slice until it has found --failures of its own; the first failures of
// all slices in run order are those one hunt finds, and the runs one hunt would have driven
// are counted from each shard's runs.
TEST(Hunt, ShardsMergeIntoWhatOneHuntFinds) {
  TempDir dir;
  const HuntSpec whole = small_hunt(dir.path() / "whole");
  const HuntOutcome local = run_hunt(whole, nullptr, {});
  ASSERT_EQ(local.failures.size(), 3U);
  std::vector<fs::path> shards;
  for (int i = 1; i <= 3; ++i) {
    HuntSpec s = small_hunt(dir.path() / ("shard" + std::to_string(i)));
    s.shard_index = i;
    s.shard_count = 3;
    s.jobs = 1;
    const HuntOutcome o = run_hunt(s, nullptr, {});
    ASSERT_TRUE(o.shard);
    EXPECT_TRUE(o.shard->finished);
    for (const HuntFailure& f : o.failures) EXPECT_EQ(f.run % 3, static_cast<std::size_t>(i - 1));
    shards.push_back(s.out);
  }
  const fs::path merged = dir.path() / "merged";
  const HuntOutcome m = merge_hunt({shards[2], shards[0], shards[1]}, merged);
  EXPECT_EQ(m.runs, local.runs);
  EXPECT_DOUBLE_EQ(m.simulated_s, local.simulated_s);
  EXPECT_EQ(comparable(merged), comparable(whole.out));
  for (const HuntFailure& f : m.failures) {
    EXPECT_EQ(read_file(merged / f.replay), read_file(whole.out / f.replay)) << f.replay;
  }
  for (const HuntGroup& g : m.groups) {
    EXPECT_EQ(comparable(merged, g.reactive), comparable(whole.out, g.reactive));
    EXPECT_EQ(comparable(merged, g.replayed), comparable(whole.out, g.replayed));
  }

  const auto refused = [&](const std::vector<fs::path>& dirs, const std::string& what) {
    try {
      (void)merge_hunt(dirs, dir.path() / "refused");
      ADD_FAILURE() << "merged: " << what;
    } catch (const UsageError& e) {
      EXPECT_THAT(e.what(), HasSubstr(what));
    }
  };
  refused({shards[0], shards[1]}, "2 of the hunt's 3 shards; a shard is missing");
  refused({shards[0], shards[0], shards[1]}, "shard 1 of 3 appears twice");
  refused({shards[0], shards[1], shards[2], whole.out}, "is not the report of a hunt shard");
  const fs::path cut_short = dir.path() / "cut-short";
  fs::copy(shards[1], cut_short, fs::copy_options::recursive);
  json report = read_json_file(cut_short / "hunt.json");
  report["shard"]["finished"] = false;
  write_file_atomic(cut_short / "hunt.json", report.dump());
  refused({shards[0], cut_short, shards[2]}, "holds an unfinished shard (shard 2 was interrupted)");
  HuntSpec other = small_hunt(dir.path() / "other");
  other.minutes = 1.0;
  other.shard_index = 3;
  other.shard_count = 3;
  (void)run_hunt(other, nullptr, {});
  refused({shards[0], shards[1], other.out}, "is a shard of another hunt");
  try {
    (void)merge_hunt(shards, merged);
    ADD_FAILURE() << "merged into a folder that holds a hunt";
  } catch (const UsageError& e) {
    EXPECT_THAT(e.what(), HasSubstr("already holds a hunt"));
  }
}

}  // namespace
}  // namespace overtake::batch

namespace overtake::batch {
namespace {

TEST(Hunt, CtrlCKeepsWhatWasFound) {
  TempDir dir;
  const fs::path out = dir.path() / "hunt";
  // SIGINT to a hunt that would go on for hours, once it has kept a failure (hunt.json is
  // written after each one): waiting for that, not for a fixed time, holds on a loaded machine.
  const pid_t pid = test::start_overtake(
      {"hunt", "--policy", "seed001", "--traffic", "faithful", "--minutes", "2", "--failures",
       "1000", "--budget-hours", "1000", "--jobs", "2", "--quiet", "--out", out.string()},
      dir.path() / "stdout", dir.path() / "stderr");
  const auto until = std::chrono::steady_clock::now() + std::chrono::minutes(2);
  while (!fs::exists(out / "hunt.json") && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(pid, SIGINT);
  const auto status = test::exit_status(pid, std::chrono::minutes(1));
  ASSERT_TRUE(status.has_value()) << "the hunt did not end within a minute of Ctrl-C";
  EXPECT_EQ(*status, 130);
  const json j = read_json_file(out / "hunt.json");
  EXPECT_TRUE(j["interrupted"].get<bool>());
  EXPECT_GE(j["runs"].get<int>(), 1);
  EXPECT_GE(j["failures"].size(), 1U);
  for (const json& f : j["failures"]) EXPECT_TRUE(fs::exists(out / f["replay"].get<std::string>()));
  EXPECT_TRUE(fs::is_empty(out / "runs"));  // no run's replay left half-kept
}

}  // namespace
}  // namespace overtake::batch
