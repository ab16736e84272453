// `overtake bench`: deterministic, job-count independent, shardable, resumable, and strict
// about bad input before any run starts.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>

#include "overtake/base/build_info.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/batch/bench.hpp"
#include "overtake/eval/summary.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "process_support.hpp"

namespace overtake::batch {

using base::build_revision;
using base::read_file;
using base::UsageError;
using base::write_file_atomic;
using run::config_to_json;
using run::default_config;
using run::drive_on;
using run::DriveOptions;
using run::DriveResult;
using run::load_config;
using run::load_track;
using run::report_to_json;
namespace {

using nlohmann::json;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

class BenchTest : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("overtake_bench_test_" +
             std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }

  BenchSpec spec(const std::string& out) const {
    BenchSpec s;
    s.policies = {"walkthrough", "seed001"};
    s.traffic = {"faithful"};
    s.seeds = {1, 2};
    s.minutes = 1.0;
    s.jobs = 2;
    s.out = root_ / out;
    return s;
  }
  // The same, slice `index` of `count`.
  BenchSpec shard(const std::string& out, int index, int count) const {
    BenchSpec s = spec(out);
    s.shard_index = index;
    s.shard_count = count;
    return s;
  }
  // runs.jsonl without the fields that measure time or place.
  static std::string stable_runs(const fs::path& dir) {
    std::ifstream in(dir / "runs.jsonl");
    std::string line, out;
    while (std::getline(in, line)) {
      json j = json::parse(line);
      j.erase("timing");
      j.erase("provenance");
      out += j.dump() + "\n";
    }
    return out;
  }
  static json stable_summary(const fs::path& dir) {
    std::vector<json> runs;
    std::ifstream in(dir / "runs.jsonl");
    std::string line;
    while (std::getline(in, line)) runs.push_back(json::parse(line));
    json rows = summarize_bench(runs, {"walkthrough", "seed001"}, {"faithful"}, "runs").rows;
    for (auto& r : rows) r.erase("timing");
    return rows;
  }

  fs::path root_;
};

TEST_F(BenchTest, SameRunsTwiceAndWithOneOrTwoJobs) {
  BenchSpec a = spec("a");
  BenchSpec b = spec("b");
  b.jobs = 1;
  BenchSpec c = spec("c");
  const auto oa = run_bench(a, nullptr, {});
  (void)run_bench(b, nullptr, {});
  (void)run_bench(c, nullptr, {});
  EXPECT_EQ(oa.runs_done, 4u);
  const std::string ra = stable_runs(a.out);
  EXPECT_EQ(std::count(ra.begin(), ra.end(), '\n'), 4);
  EXPECT_EQ(ra, stable_runs(b.out));
  EXPECT_EQ(ra, stable_runs(c.out));
  EXPECT_TRUE(fs::exists(a.out / "summary.csv"));
  EXPECT_TRUE(fs::exists(a.out / "summary.md"));
  EXPECT_THAT(read_file(a.out / "summary.md"), HasSubstr("| seed001 | faithful | 2 |"));
  // The evaluation, intervals and pairs included, is the same whatever the order in which the
  // runs finished (apart from the planners' timing).
  EXPECT_EQ(read_file(a.out / "pairs.csv"), read_file(b.out / "pairs.csv"));
  EXPECT_EQ(read_file(a.out / "pairs.csv"), read_file(c.out / "pairs.csv"));
  const auto untimed = [](const fs::path& dir) {
    json s = json::parse(read_file(dir / "summary.json"));
    for (auto& r : s["rows"]) r.erase("timing");
    return s.dump();
  };
  EXPECT_EQ(untimed(a.out), untimed(b.out));
  EXPECT_EQ(untimed(a.out), untimed(c.out));
  const json pairs = json::parse(read_file(a.out / "summary.json"))["pairs"];
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0]["policy"], "walkthrough");
  EXPECT_EQ(pairs[0]["versus"], "seed001");
  EXPECT_EQ(pairs[0]["seeds"], 2);
}

// `overtake compare`: a second identical bench is no difference (exit 0 even with
// --fail-if-worse); a slower planner fails --fail-if-worse; too few seeds give no verdict
// (exit 2 with --fail-if-worse, and the reason); folders that are not benches, or benches
// that cannot be paired, fail with a message; bad flags are usage errors.
TEST_F(BenchTest, CompareTellsNoDifferenceFromWorse) {
  BenchSpec a = spec("a");
  a.policies = {"reference"};
  a.seeds = {1, 2, 3, 4, 5, 6, 7, 8};
  BenchSpec b = a;
  b.out = root_ / "b";
  BenchSpec slow = a;
  slow.out = root_ / "slow";
  json config = config_to_json(default_config());
  config["planner"]["reference"]["behaviour"]["cruise_speed_mps"] = 17.0;
  write_file_atomic(root_ / "slow.json", config.dump());
  slow.config = root_ / "slow.json";
  BenchSpec other_map = a;
  other_map.out = root_ / "other";
  other_map.minutes = 0.5;
  BenchSpec few = slow;
  few.out = root_ / "few";
  few.seeds = {1, 2, 3};
  for (const BenchSpec* s : {&a, &b, &slow, &other_map, &few}) (void)run_bench(*s, nullptr, {});

  const auto compare = [&](std::vector<std::string> args) {
    args.insert(args.begin(), "compare");
    const pid_t pid = test::start_overtake(args, root_ / "out.txt", root_ / "err.txt");
    const auto status = test::exit_status(pid, std::chrono::minutes(2));
    return std::make_pair(status.value_or(-1),
                          read_file(root_ / "out.txt") + read_file(root_ / "err.txt"));
  };
  auto [same, same_text] = compare({a.out, b.out, "--fail-if-worse"});
  EXPECT_EQ(same, 0) << same_text;
  EXPECT_THAT(same_text, HasSubstr("No figure got significantly worse."));
  EXPECT_THAT(same_text, HasSubstr("no difference"));
  EXPECT_THAT(same_text, ::testing::Not(HasSubstr(" worse\n")));

  auto [worse, worse_text] =
      compare({a.out, slow.out, "--fail-if-worse", "--json", root_ / "cmp.json"});
  EXPECT_EQ(worse, 1) << worse_text;
  EXPECT_THAT(worse_text, HasSubstr("reference / faithful: mean_speed_mph"));
  const json cmp = json::parse(read_file(root_ / "cmp.json"));
  EXPECT_EQ(cmp["comparisons"][0]["figures"]["mean_speed_mph"]["verdict"], "worse");
  EXPECT_EQ(compare({a.out, slow.out}).first, 0);  // reported, not failed, without the flag
  // Three seeds, however much slower: no verdict, and --fail-if-worse says why (exit 2).
  auto [few_status, few_text] = compare({a.out, few.out, "--fail-if-worse"});
  EXPECT_EQ(few_status, 2) << few_text;
  EXPECT_THAT(few_text, HasSubstr("no verdict, reference / faithful: too few seeds: 3, need at "
                                  "least 8"));
  EXPECT_THAT(few_text, HasSubstr("too few seeds"));
  EXPECT_THAT(few_text, ::testing::Not(HasSubstr(" worse\n")));

  auto [unpaired, unpaired_text] = compare({a.out, other_map.out});
  EXPECT_EQ(unpaired, 1);
  EXPECT_THAT(unpaired_text, HasSubstr("different durations (minutes)"));
  auto [missing, missing_text] = compare({a.out, root_ / "nothing"});
  EXPECT_EQ(missing, 1);
  EXPECT_THAT(missing_text, HasSubstr("no such folder"));
  EXPECT_EQ(compare({a.out, b.out, "--pair", "reference"}).first, 2);
  const std::string runs_before = read_file(a.out / "runs.jsonl");
  auto [over, over_text] = compare({a.out, b.out, "--json", a.out / "runs.jsonl"});
  EXPECT_EQ(over, 2);
  EXPECT_THAT(over_text, HasSubstr("a file of a bench being compared"));
  EXPECT_EQ(read_file(a.out / "runs.jsonl"), runs_before);
  EXPECT_EQ(compare({a.out, b.out, "--pair", "reference=other"}).first, 2);
  auto [figures, figures_text] = compare({a.out, b.out, "--figures", "speed"});
  EXPECT_EQ(figures, 2);
  EXPECT_THAT(figures_text, HasSubstr("unknown figure 'speed' (known: mean_speed_mph"));
}

TEST_F(BenchTest, EachLineCarriesProvenance) {
  const BenchSpec s = spec("p");
  (void)run_bench(s, nullptr, {});
  std::ifstream in(s.out / "runs.jsonl");
  std::string line;
  std::getline(in, line);
  const json j = json::parse(line);
  EXPECT_EQ(j["index"], 0);
  EXPECT_EQ(j["config"]["policy"], "walkthrough");
  EXPECT_EQ(j["config"]["seed"], 1);
  EXPECT_EQ(j["config"]["traffic"], "faithful");
  EXPECT_EQ(j["config"]["map"]["hash"].get<std::string>().size(), 16u);
  EXPECT_EQ(j["config"]["params_hash"].get<std::string>().size(), 16u);
  EXPECT_TRUE(j["provenance"].contains("git_revision"));
  EXPECT_TRUE(j["provenance"].contains("host"));
  EXPECT_TRUE(j["timing"].contains("finished_at"));
}

TEST_F(BenchTest, ShardsMergeIntoTheUnshardedResult) {
  const BenchSpec whole = spec("whole");
  (void)run_bench(whole, nullptr, {});
  BenchSpec s1 = shard("s1", 1, 2);
  BenchSpec s2 = shard("s2", 2, 2);
  EXPECT_EQ(run_bench(s1, nullptr, {}).runs_done, 2u);
  EXPECT_EQ(run_bench(s2, nullptr, {}).runs_done, 2u);
  const auto merged = merge_bench({s2.out, s1.out}, root_ / "merged");
  EXPECT_EQ(merged.runs_done, 4u);
  EXPECT_EQ(stable_runs(root_ / "merged"), stable_runs(whole.out));
  EXPECT_EQ(stable_summary(root_ / "merged"), stable_summary(whole.out));
}

TEST_F(BenchTest, MergeRefusesDifferentConfigurationsAndMissingShards) {
  BenchSpec s1 = shard("s1", 1, 2);
  BenchSpec other = shard("other", 2, 2);
  other.minutes = 0.5;
  (void)run_bench(s1, nullptr, {});
  (void)run_bench(other, nullptr, {});
  try {
    (void)merge_bench({s1.out, other.out}, root_ / "m");
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("different bench configuration"));
  }
  try {
    (void)merge_bench({s1.out}, root_ / "m");
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("a shard is missing"));
  }
  try {
    (void)merge_bench({s1.out, s1.out}, root_ / "m");
    FAIL();
  } catch (const UsageError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("appears twice"));
  }
}

// Shards run by two builds (another node's binary, a rebuild between arrays) may drive
// differently: their rows do not make one sweep.
TEST_F(BenchTest, MergeRefusesRowsOfTwoRevisions) {
  BenchSpec s1 = shard("s1", 1, 2);
  BenchSpec s2 = shard("s2", 2, 2);
  (void)run_bench(s1, nullptr, {});
  (void)run_bench(s2, nullptr, {});
  std::string rows;
  {
    std::ifstream in(s2.out / "runs.jsonl");
    std::string line;
    while (std::getline(in, line)) {
      json j = json::parse(line);
      j["provenance"]["git_revision"] = "0123abc";
      rows += j.dump() + "\n";
    }
  }
  write_file_atomic(s2.out / "runs.jsonl", rows);
  try {
    (void)merge_bench({s1.out, s2.out}, root_ / "m");
    FAIL() << "merged rows of two builds";
  } catch (const UsageError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("different builds of overtake"));
    EXPECT_THAT(std::string(e.what()),
                HasSubstr("0123abc (in " + (s2.out / "runs.jsonl").string() + ":1, run 1)"));
  }
  EXPECT_FALSE(fs::exists(root_ / "m" / "runs.jsonl"));
}

TEST_F(BenchTest, ResumeSkipsFinishedRunsAndDropsACutOffLine) {
  BenchSpec s = spec("r");
  s.policies = {"walkthrough"};
  (void)run_bench(s, nullptr, {});
  const std::string full = stable_runs(s.out);
  // Keep the first run, and a line cut off mid-way as a kill would leave it.
  std::ifstream in(s.out / "runs.jsonl");
  std::string first;
  std::getline(in, first);
  in.close();
  write_file_atomic(s.out / "runs.jsonl", first + "\n" + first.substr(0, first.size() / 2));
  EXPECT_THROW((void)run_bench(s, nullptr, {}), UsageError);  // without --resume: refused
  s.resume = true;
  const auto o = run_bench(s, nullptr, {});
  EXPECT_EQ(o.runs_new, 1u);
  EXPECT_EQ(o.runs_done, 2u);
  EXPECT_EQ(stable_runs(s.out), full);
}

TEST_F(BenchTest, ResumeRefusesDuplicatedAndForeignRows) {
  BenchSpec s = spec("dup");
  s.policies = {"walkthrough"};
  (void)run_bench(s, nullptr, {});
  std::ifstream in(s.out / "runs.jsonl");
  std::string first, second;
  std::getline(in, first);
  std::getline(in, second);
  in.close();
  s.resume = true;
  // A row twice (the summary once said 25 runs for 20 seeds).
  write_file_atomic(s.out / "runs.jsonl", first + "\n" + first + "\n");
  try {
    (void)run_bench(s, nullptr, {});
    FAIL() << "a duplicated row was resumed";
  } catch (const UsageError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("run 0 appears twice"));
  }
  // A row of another run under this index.
  json other = json::parse(second);
  other["index"] = 0;
  write_file_atomic(s.out / "runs.jsonl", other.dump() + "\n");
  try {
    (void)run_bench(s, nullptr, {});
    FAIL() << "a foreign row was resumed";
  } catch (const UsageError& e) {
    EXPECT_THAT(std::string(e.what()),
                HasSubstr("the row of run 0 is not walkthrough / faithful / seed 1"));
  }
  // An index beyond the bench.
  other["index"] = 7;
  write_file_atomic(s.out / "runs.jsonl", other.dump() + "\n");
  EXPECT_THROW((void)run_bench(s, nullptr, {}), UsageError);
}

TEST_F(BenchTest, MergeNeverOverwritesResults) {
  BenchSpec s1 = shard("s1", 1, 2);
  BenchSpec s2 = shard("s2", 2, 2);
  (void)run_bench(s1, nullptr, {});
  (void)run_bench(s2, nullptr, {});
  const std::string before = stable_runs(s1.out);
  try {
    (void)merge_bench({s1.out, s2.out}, s1.out);
    FAIL() << "merged into an input shard";
  } catch (const UsageError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("is one of the folders being joined"));
  }
  EXPECT_EQ(stable_runs(s1.out), before);
  // A folder with files of a bench's names that no bench wrote.
  fs::create_directories(root_ / "notes");
  write_file_atomic(root_ / "notes" / "pairs.csv", "mine\n");
  try {
    (void)merge_bench({s1.out, s2.out}, root_ / "notes");
    FAIL() << "merged over a pairs.csv of someone's";
  } catch (const UsageError& e) {
    EXPECT_THAT(std::string(e.what()),
                HasSubstr((root_ / "notes" / "pairs.csv").string() + " is not a bench's"));
  }
  EXPECT_EQ(read_file(root_ / "notes" / "pairs.csv"), "mine\n");
  (void)merge_bench({s1.out, s2.out}, root_ / "m");
  try {
    (void)merge_bench({s1.out, s2.out}, root_ / "m");
    FAIL() << "merged into a folder that holds results";
  } catch (const UsageError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("already holds bench results"));
  }
}

// bench.json records the build that ran the bench, and --resume refuses rows of another build,
// map, length or parameters (the check `bench merge` and `compare` make), naming the line and
// the run, and leaves the folder as it was.
TEST_F(BenchTest, ResumeRefusesRowsOfAnotherBuildMapOrLength) {
  BenchSpec s = spec("r");
  s.policies = {"walkthrough"};
  (void)run_bench(s, nullptr, {});
  const fs::path runs = s.out / "runs.jsonl";
  const fs::path manifest_path = s.out / "bench.json";
  const json manifest = json::parse(read_file(manifest_path));
  EXPECT_EQ(manifest["git_revision"], std::string(build_revision()));
  std::string first, second;
  {
    std::ifstream in(runs);
    std::getline(in, first);
    std::getline(in, second);
  }
  const auto second_edited = [&](const std::function<void(json&)>& edit) {
    json j = json::parse(second);
    edit(j);
    return first + "\n" + j.dump() + "\n";
  };
  s.resume = true;
  const auto refusal = [&](const std::string& rows) -> std::string {
    write_file_atomic(runs, rows);
    try {
      (void)run_bench(s, nullptr, {});
    } catch (const UsageError& e) {
      EXPECT_EQ(read_file(runs), rows);  // refused before anything was rewritten
      return e.what();
    }
    return "";
  };
  const std::string at = runs.string() + ":2: ";
  const std::string rev =
      refusal(second_edited([](json& j) { j["provenance"]["git_revision"] = "0123abc"; }));
  EXPECT_THAT(rev, HasSubstr("--resume: the runs come from different builds of overtake: " +
                             std::string(build_revision()) + " (this overtake) and 0123abc (in " +
                             runs.string() + ":2, run 1)"));
  EXPECT_THAT(rev, HasSubstr("cannot be resumed"));
  EXPECT_THAT(
      refusal(second_edited([](json& j) { j["config"]["map"]["hash"] = "00000000deadbeef"; })),
      HasSubstr(at + "run 1 was driven on another map"));
  EXPECT_THAT(refusal(second_edited([](json& j) { j["config"]["minutes"] = 2.0; })),
              HasSubstr(at + "run 1 lasted another length (2.0 minutes; this bench's runs last "
                             "1.0)"));
  EXPECT_THAT(refusal(second_edited([](json& j) { j["config"]["params_hash"] = "feed"; })),
              HasSubstr(at + "run 1 ran with other parameters"));
  // A bench.json of another build.
  json other = manifest;
  other["git_revision"] = "0123abc";
  write_file_atomic(manifest_path, other.dump(2));
  EXPECT_THAT(refusal(first + "\n" + second + "\n"),
              HasSubstr("and 0123abc (in " + manifest_path.string() + ")"));
  // As it was: resumed, nothing to run.
  write_file_atomic(manifest_path, manifest.dump(2));
  EXPECT_EQ(run_bench(s, nullptr, {}).runs_new, 0U);
}

// `compare` counted a row written five times as five seeds (and turned figures "worse"), and a
// line with 1e999 aborted it naming no file while other bad lines were dropped. Now every
// row it cannot vouch for is refused, naming the file, the line and the run.
TEST_F(BenchTest, CompareRefusesRowsItCannotVouchFor) {
  BenchSpec a = spec("a");
  a.policies = {"walkthrough"};
  a.seeds = {1, 2, 3};
  BenchSpec b = a;
  b.out = root_ / "b";
  (void)run_bench(a, nullptr, {});
  (void)run_bench(b, nullptr, {});
  const fs::path runs = b.out / "runs.jsonl";
  std::vector<std::string> lines;
  {
    std::ifstream in(runs);
    std::string line;
    while (std::getline(in, line)) lines.push_back(line);
  }
  ASSERT_EQ(lines.size(), 3U);
  const auto error_of = [&](const std::string& rows) -> std::string {
    write_file_atomic(runs, rows);
    try {
      (void)compare_bench_folders(a.out, b.out, {});
    } catch (const std::runtime_error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(error_of(lines[0] + "\n" + lines[1] + "\n" + lines[2] + "\n"), "");
  std::string five_times;
  for (const auto& l : lines) {
    for (int k = 0; k < 5; ++k) five_times += l + "\n";
  }
  EXPECT_THAT(
      error_of(five_times),
      HasSubstr(runs.string() +
                ":2: run 0 appears twice (walkthrough / faithful / seed 1, lines 1 and 2)"));
  // Every bad line is named, and none is left out: a number out of range, a line not JSON.
  const std::string bad =
      error_of(lines[0] + "\n{\"index\": 1, \"duration_s\": 1e999}\n" + lines[2] + "\nnot a row\n");
  EXPECT_THAT(bad, HasSubstr(runs.string() + ":2: not a run (number overflow parsing '1e999')"));
  EXPECT_THAT(bad,
              HasSubstr(runs.string() + ":4: not a run (parse error at column 2: syntax error"));
  // A last line cut off (a killed bench) is refused too, saying what finishes it.
  const std::string cut =
      error_of(lines[0] + "\n" + lines[1] + "\n" + lines[2].substr(0, lines[2].size() / 2));
  EXPECT_THAT(cut, HasSubstr(runs.string() + ":3: not a run"));
  EXPECT_THAT(cut, HasSubstr("--resume"));
  // A row of another build in one bench.
  json foreign = json::parse(lines[2]);
  foreign["provenance"]["git_revision"] = "0123abc";
  EXPECT_THAT(error_of(lines[0] + "\n" + lines[1] + "\n" + foreign.dump() + "\n"),
              HasSubstr("different builds of overtake"));
  // At the command line: exit status 1, the file and line named.
  write_file_atomic(runs, five_times);
  const pid_t pid =
      test::start_overtake({"compare", a.out, b.out}, root_ / "out.txt", root_ / "err.txt");
  EXPECT_EQ(test::exit_status(pid, std::chrono::minutes(1)), 1);
  EXPECT_THAT(read_file(root_ / "err.txt"), HasSubstr(runs.string() + ":2: run 0 appears twice"));
}

// `bench --out` replaced a summary.md, pairs.csv or summary.json of someone's own; now a folder
// that holds no bench is written only when it holds no file of a bench's names (or --force).
TEST_F(BenchTest, OutNeverReplacesFilesNoBenchWrote) {
  BenchSpec s = spec("mine");
  s.policies = {"walkthrough"};
  s.seeds = {1};
  for (const char* name : {"summary.md", "summary.csv", "summary.json", "pairs.csv"}) {
    fs::remove_all(s.out);
    fs::create_directories(s.out);
    write_file_atomic(s.out / name, "mine\n");
    try {
      (void)run_bench(s, nullptr, {});
      ADD_FAILURE() << "replaced " << name;
    } catch (const UsageError& e) {
      EXPECT_THAT(std::string(e.what()),
                  HasSubstr("--out: " + (s.out / name).string() + " is not a bench's"));
      EXPECT_THAT(std::string(e.what()), HasSubstr("--force"));
    }
    EXPECT_EQ(read_file(s.out / name), "mine\n");
    EXPECT_FALSE(fs::exists(s.out / "bench.json"));
    EXPECT_FALSE(fs::exists(s.out / "runs.jsonl"));
  }
  fs::remove_all(s.out);
  fs::create_directories(s.out / "replays");
  write_file_atomic(s.out / "replays" / "a.otr", "mine\n");
  EXPECT_THROW((void)run_bench(s, nullptr, {}), UsageError);
  fs::remove_all(s.out / "replays");
  write_file_atomic(s.out / "summary.md", "mine\n");
  s.force = true;
  EXPECT_EQ(run_bench(s, nullptr, {}).runs_done, 1U);
  EXPECT_THAT(read_file(s.out / "summary.md"), HasSubstr("| walkthrough | faithful | 1 |"));
  // The folder is now a bench's: --resume rewrites its summaries, without --force.
  s.force = false;
  s.resume = true;
  EXPECT_EQ(run_bench(s, nullptr, {}).runs_new, 0U);
}

// `--traffic faithful,faithful` drove every run twice and counted each failure twice.
TEST_F(BenchTest, ListFlagsNameEachThingOnce) {
  auto error_of = [&](const BenchSpec& s) {
    try {
      check_bench_spec(s);
    } catch (const UsageError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  BenchSpec s = spec("twice");
  s.policies = {"walkthrough", "seed001", "walkthrough"};
  EXPECT_THAT(error_of(s), HasSubstr("--policies: 'walkthrough' is named twice (items 1 and 3)"));
  s = spec("twice");
  s.traffic = {"faithful", "faithful"};
  EXPECT_THAT(error_of(s), HasSubstr("--traffic: 'faithful' is named twice (items 1 and 2)"));
  s = spec("twice");
  s.seeds = {1, 2, 1};
  EXPECT_THAT(error_of(s), HasSubstr("--seeds: a seed is named twice"));
  const pid_t pid =
      test::start_overtake({"bench", "--policies", "walkthrough", "--traffic", "faithful,faithful",
                            "--seeds", "1", "--quiet", "--out", (root_ / "twice").string()},
                           root_ / "out.txt", root_ / "err.txt");
  EXPECT_EQ(test::exit_status(pid, std::chrono::minutes(1)), 2);
  EXPECT_THAT(read_file(root_ / "err.txt"), HasSubstr("--traffic: 'faithful' is named twice"));
  EXPECT_FALSE(fs::exists(root_ / "twice"));
}

TEST_F(BenchTest, AStopKeepsFinishedRunsOnly) {
  BenchSpec s = spec("stop");
  std::atomic<bool> stop{true};
  const auto o = run_bench(s, &stop, {});
  EXPECT_TRUE(o.interrupted);
  EXPECT_EQ(o.runs_done, 0u);
  EXPECT_TRUE(fs::exists(s.out / "bench.json"));
  s.resume = true;
  EXPECT_EQ(run_bench(s, nullptr, {}).runs_done, 4u);
}

TEST_F(BenchTest, BadInputIsRefusedBeforeAnyRun) {
  auto error_of = [&](BenchSpec s) {
    try {
      (void)run_bench(s, nullptr, {});
    } catch (const UsageError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  BenchSpec s = spec("bad");
  s.policies = {"walkthrough", "nope"};
  EXPECT_THAT(error_of(s), HasSubstr("unknown policy 'nope'"));
  s = spec("bad");
  s.traffic = {"rush"};
  EXPECT_THAT(error_of(s), HasSubstr("unknown profile 'rush'"));
  s = spec("bad");
  s.shard_index = 3;
  s.shard_count = 2;
  EXPECT_THAT(error_of(s), HasSubstr("--shard"));
  s = spec("bad");
  s.jobs = 0;
  EXPECT_THAT(error_of(s), HasSubstr("--jobs"));
  EXPECT_FALSE(fs::exists(root_ / "bad" / "runs.jsonl"));
}

TEST(BenchParse, SeedLists) {
  EXPECT_EQ(parse_seed_list("1-3"), (std::vector<std::uint64_t>{1, 2, 3}));
  EXPECT_EQ(parse_seed_list("7"), (std::vector<std::uint64_t>{7}));
  EXPECT_EQ(parse_seed_list("1,4-5,9"), (std::vector<std::uint64_t>{1, 4, 5, 9}));
  EXPECT_THROW((void)parse_seed_list("5-1"), UsageError);
  EXPECT_THROW((void)parse_seed_list(""), UsageError);
  EXPECT_THROW((void)parse_seed_list("a-b"), UsageError);
  EXPECT_THROW((void)parse_seed_list("1,1"), UsageError);
  try {
    (void)parse_seed_list("5-1");
  } catch (const UsageError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr("empty"));
  }
}

TEST(BenchParse, Shards) {
  EXPECT_EQ(parse_shard("2/8"), (batch::Shard{2, 8}));
  EXPECT_THROW((void)parse_shard("0/8"), UsageError);
  EXPECT_THROW((void)parse_shard("9/8"), UsageError);
  EXPECT_THROW((void)parse_shard("2-8"), UsageError);
  EXPECT_THROW((void)parse_shard("2/8x"), UsageError);
}

// A policy that falls back on a fifth of its cycles must not look like a clean one: the
// summary gives the share of cycles by plan status, and how many runs ended early. Rows from
// before statuses were kept count as normal planning.
TEST(BenchSummary, PlanStatusesAndEarlyEndsAreSummed) {
  const DriveResult a = drive_on(*load_track(std::nullopt), load_config(std::nullopt), [] {
    DriveOptions o;
    o.minutes = 0.1;
    o.policy = "walkthrough";
    return o;
  }());
  json with = report_to_json(a.report, a.provenance);
  with["planner_cycles"] = 1000;
  with["plan_status"]["cycles"] = {{"normal", 800}, {"least_bad", 0}, {"fallback", 200}};
  json old = with;
  old.erase("plan_status");
  old["ended_early"] = "planner failed at t = 1.000000 s: gone";
  // The old row also predates collision classes and near misses.
  old.erase("collisions");
  old.erase("safety");
  const json rows = summarize_bench({with, old}, {"walkthrough"}, {"faithful"}, "runs").rows;
  ASSERT_EQ(rows.size(), 1u);
  const json& share = rows[0]["plan_status_share"];
  EXPECT_DOUBLE_EQ(share["fallback"].get<double>(), 0.1);  // 200 of 2000 cycles
  EXPECT_EQ(share["least_bad"].get<double>(), 0.0);
  EXPECT_NEAR(share["normal"].get<double>(), 1.0 - share["fallback"].get<double>(), 1e-12);
  EXPECT_EQ(rows[0]["runs_ended_early"], 1);
  EXPECT_THAT(eval::summary_markdown(rows, json::array()), HasSubstr("| 0.0% / 10.0% | 1 |"));
  EXPECT_THAT(eval::summary_csv(rows),
              HasSubstr("least_bad_cycle_share,fallback_cycle_share,runs_ended_early"));
  // Without contacts in every row there are no collision figures, nor near misses.
  EXPECT_TRUE(rows[0]["collisions"].is_null());
  EXPECT_TRUE(rows[0]["near_misses"].is_null());
}

}  // namespace
}  // namespace overtake::batch
