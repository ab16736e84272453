// `overtake hunt` with bad input: flags bounded where they enter (the cut window as `cut`
// bounds it, the budget, the first seed), list flags that name a thing twice, an output folder
// holding what the hunt would replace, replay names that two maps would share, and a report
// that cannot be written (the hunt stops cleanly, keeping what it found).

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <set>

#include "overtake/app/cli.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/batch/hunt.hpp"
#include "overtake/replay/replay.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/scenarios/cut.hpp"
#include "process_support.hpp"
#include "temp_dir.hpp"

namespace overtake::app {

using base::kExitFailure;
using base::kExitUsage;
using base::read_file;
using base::UsageError;
using base::write_file_atomic;
using batch::check_hunt_out;
using batch::check_hunt_spec;
using batch::hunt_max_runs;
using batch::hunt_run_name;
using batch::HuntFailure;
using batch::HuntOutcome;
using batch::HuntSpec;
using batch::run_hunt;
using scenarios::cut_replay;
using scenarios::CutOptions;
using scenarios::kMaxCutWindowS;
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::Not;

class HuntRobustness : public ::testing::Test {
 protected:
  test::TempDir dir_{"overtake-hunt"};

  [[nodiscard]] fs::path path(const std::string& name) const { return dir_.path() / name; }

  // A hunt that finds its first failure in its first runs (seed001 collides early).
  [[nodiscard]] HuntSpec quick(const std::string& out) const {
    HuntSpec spec;
    spec.policy = "seed001";
    spec.traffic = {"faithful"};
    spec.minutes = 2.0;
    spec.failures = 1;
    spec.budget_hours = 1.0;
    spec.jobs = 2;
    spec.out = path(out);
    return spec;
  }

  // `overtake ARGS`: its exit status (1000 + a signal that killed it) and what it printed.
  [[nodiscard]] std::pair<int, std::string> overtake(std::vector<std::string> args) const {
    const pid_t pid = test::start_overtake(args, path("out.txt"), path("err.txt"));
    const auto status = test::exit_status(pid, std::chrono::minutes(3));
    return {status.value_or(-1), read_file(path("out.txt")) + read_file(path("err.txt"))};
  }

  // The error a spec is refused with before any run ("" when it is not).
  static std::string refusal(const HuntSpec& spec) {
    try {
      check_hunt_spec(spec);
    } catch (const UsageError& e) {
      return e.what();
    }
    return "";
  }
};

// `cut` takes --before and --after up to 3600 s; a hunt that would cut with more used to run
// until its first failure and abort there (exit 134, nothing kept). Now it is refused before
// any run, with the same bounds and words as `cut`.
TEST_F(HuntRobustness, TheCutWindowIsBoundedAsCutBoundsIt) {
  const auto [status, text] = overtake(
      {"hunt", "--policy", "seed001", "--before", "4000", "--quiet", "--out", path("h").string()});
  EXPECT_EQ(status, kExitUsage) << text;
  EXPECT_THAT(text, HasSubstr("--before must be between 0 and 3600 s (got 4000)"));
  EXPECT_FALSE(fs::exists(path("h")));
  HuntSpec spec = quick("h");
  spec.after_s = -1.0;
  EXPECT_THAT(refusal(spec), HasSubstr("--after must be between 0 and 3600 s (got -1)"));
  spec.after_s = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THAT(refusal(spec), HasSubstr("--after must be between 0 and 3600 s"));
  spec.after_s = kMaxCutWindowS;
  EXPECT_EQ(refusal(spec), "");
  try {
    CutOptions cut;
    cut.before_s = 4000.0;
    (void)cut_replay(cut);
    ADD_FAILURE() << "cut took --before 4000";
  } catch (const UsageError& e) {
    EXPECT_THAT(e.what(), HasSubstr("--before must be between 0 and 3600 s (got 4000)"));
  }
}

// A budget of 1e300 hours used to wrap the run count to 0 ("hunt of 0 runs").
TEST_F(HuntRobustness, TheBudgetAndTheSeedsAreBounded) {
  const auto [status, text] = overtake({"hunt", "--policy", "seed001", "--budget-hours", "1e300",
                                        "--quiet", "--out", path("h").string()});
  EXPECT_EQ(status, kExitUsage) << text;
  EXPECT_THAT(text,
              HasSubstr("--budget-hours must be more than 0 and at most 100000 (got 1e+300)"));
  EXPECT_FALSE(fs::exists(path("h")));
  HuntSpec spec = quick("h");
  for (const double bad : {0.0, -1.0, std::numeric_limits<double>::infinity(),
                           std::numeric_limits<double>::quiet_NaN(), 100001.0}) {
    spec.budget_hours = bad;
    EXPECT_THAT(refusal(spec), HasSubstr("--budget-hours must be more than 0")) << bad;
  }
  spec.budget_hours = 1e300;
  EXPECT_EQ(hunt_max_runs(spec), 100000000U);  // saturated, never wrapped
  spec.budget_hours = 100000.0;
  spec.minutes = 0.001;  // 6e9 runs
  EXPECT_THAT(refusal(spec), HasSubstr("gives more than 99999999 runs"));
  spec = quick("h");
  spec.budget_hours = 1.0;  // 30 runs of 2 minutes: seeds first_seed to first_seed + 29
  spec.first_seed = std::numeric_limits<std::uint64_t>::max() - 28;
  EXPECT_THAT(refusal(spec), HasSubstr("--first-seed: the hunt's seeds go from"));
  spec.first_seed = std::numeric_limits<std::uint64_t>::max() - 29;
  EXPECT_EQ(refusal(spec), "");
}

// `--maps default,default` drove every run twice and counted each failure twice.
TEST_F(HuntRobustness, ListFlagsNameEachThingOnce) {
  const auto [status, text] = overtake({"hunt", "--policy", "seed001", "--maps", "default,default",
                                        "--quiet", "--out", path("h").string()});
  EXPECT_EQ(status, kExitUsage) << text;
  EXPECT_THAT(text, HasSubstr("--maps: default is named twice (items 1 and 2)"));
  HuntSpec spec = quick("h");
  spec.traffic = {"faithful", "calm", "faithful"};
  EXPECT_THAT(refusal(spec), HasSubstr("--traffic: 'faithful' is named twice (items 1 and 3)"));
  // One file by two names, and two files with the same map.
  const fs::path source = fs::path(OVERTAKE_SOURCE_DIR) / "data" / "tracks" / "default.csv";
  fs::create_directories(path("maps"));
  fs::copy_file(source, path("maps") / "a.csv");
  fs::copy_file(source, path("maps") / "b.csv");
  spec = quick("h");
  spec.maps = {path("maps") / "a.csv", path("maps") / "." / "a.csv"};
  EXPECT_THAT(refusal(spec), HasSubstr("is named twice"));
  spec.maps = {path("maps") / "a.csv", path("maps") / "b.csv"};
  EXPECT_THAT(refusal(spec),
              HasSubstr("b.csv is the same map as " + (path("maps") / "a.csv").string()));
}

// A hunt's folder holds what a hunt wrote; another hunt there, or a hunt into a folder whose
// hunt.md or replays are someone's own, replaced them. Now it says which and stops (--force
// replaces them).
TEST_F(HuntRobustness, TheOutputFolderIsNotReplacedUnlessAsked) {
  const auto refused_with = [&](const HuntSpec& spec) -> std::string {
    try {
      (void)run_hunt(spec, nullptr, {});
    } catch (const UsageError& e) {
      return e.what();
    }
    return "";
  };
  HuntSpec spec = quick("mine");
  fs::create_directories(spec.out);
  write_file_atomic(spec.out / "hunt.md", "my notes\n");
  EXPECT_THAT(refused_with(spec), HasSubstr((spec.out / "hunt.md").string() + " exists"));
  EXPECT_EQ(read_file(spec.out / "hunt.md"), "my notes\n");
  EXPECT_FALSE(fs::exists(spec.out / "runs"));  // refused before anything was made
  fs::remove(spec.out / "hunt.md");
  write_file_atomic(spec.out / "hunt.json", "{}\n");
  EXPECT_THAT(refused_with(spec), HasSubstr("hunt.json exists (a hunt's results)"));
  fs::remove(spec.out / "hunt.json");
  fs::create_directories(spec.out / "replays");
  write_file_atomic(spec.out / "replays" / "drive.otr", "x");
  EXPECT_THAT(refused_with(spec), HasSubstr((spec.out / "replays").string() + " is not empty"));
  EXPECT_EQ(read_file(spec.out / "replays" / "drive.otr"), "x");
  fs::remove(spec.out / "replays" / "drive.otr");
  // An empty folder of those names loses nothing; --force replaces what is there.
  EXPECT_NO_THROW(check_hunt_out(spec.out, false, "", ""));
  write_file_atomic(spec.out / "hunt.md", "my notes\n");
  EXPECT_NO_THROW(check_hunt_out(spec.out, true, "", ""));
}

// A hunt whose hunt.md cannot be written (here a folder of that name) aborted with "terminate
// called without an active exception", leaving no hunt.json and replays half written. Now the
// workers are stopped, the runs in progress removed, hunt.json (written first) keeps the
// failure found, and the reason is printed with exit status 1.
TEST_F(HuntRobustness, AReportThatCannotBeWrittenStopsTheHuntCleanly) {
  const fs::path out = path("h");
  fs::create_directories(out / "hunt.md");
  write_file_atomic(out / "hunt.md" / "keep", "x");
  const auto [status, text] = overtake(
      {"hunt", "--policy", "seed001", "--traffic", "faithful", "--minutes", "2", "--failures", "1",
       "--budget-hours", "1", "--jobs", "2", "--quiet", "--force", "--out", out.string()});
  EXPECT_EQ(status, kExitFailure) << text;
  EXPECT_THAT(text, HasSubstr("hunt stopped: " + (out / "hunt.md").string()));
  EXPECT_THAT(text, HasSubstr("1 failure found before it kept in " + (out / "hunt.json").string()));
  EXPECT_THAT(text, Not(HasSubstr("terminate")));
  const json j = json::parse(read_file(out / "hunt.json"));
  ASSERT_EQ(j["failures"].size(), 1U);
  EXPECT_TRUE(fs::exists(out / j["failures"][0]["replay"].get<std::string>()));
  EXPECT_THAT(j["error"].get<std::string>(), HasSubstr("hunt.md"));
  EXPECT_TRUE(fs::is_empty(out / "runs"));  // no run's replay left, whole or .partial
  EXPECT_EQ(read_file(out / "hunt.md" / "keep"), "x");
}

// Replay names were slugs: maps mp/seed_2.csv and mp/seed-2.csv wrote the same replay, and a
// failure's replay was the other map's drive. Each run's files now have names of their own.
TEST_F(HuntRobustness, ReplayNamesAreUniquePerMapTrafficAndSeed) {
  HuntSpec spec = quick("h");
  spec.maps = {std::nullopt};
  spec.traffic = {"faithful", "calm"};
  EXPECT_EQ(hunt_run_name(spec, 0), "seed001-default-faithful-seed1");  // no clash: as before
  EXPECT_EQ(hunt_run_name(spec, 3), "seed001-default-calm-seed2");
  fs::create_directories(path("mp"));
  const std::string track =
      read_file(fs::path(OVERTAKE_SOURCE_DIR) / "data" / "tracks" / "default.csv");
  // The same road twice, as two files with different contents (a comment line).
  write_file_atomic(path("mp") / "seed_2.csv", "# one\n" + track);
  write_file_atomic(path("mp") / "seed-2.csv", "# two\n" + track);
  spec.maps = {path("mp") / "seed_2.csv", path("mp") / "seed-2.csv", std::nullopt};
  std::set<std::string> names;
  for (std::size_t k = 0; k < 12; ++k) names.insert(hunt_run_name(spec, k));
  EXPECT_EQ(names.size(), 12U);
  EXPECT_NE(hunt_run_name(spec, 0), hunt_run_name(spec, 2));  // seed 1 faithful on each map

  // Two runs, seed 2 on each map: the same road fails the same way on both, each failure with
  // its own map's replay.
  spec.first_seed = 2;
  spec.traffic = {"faithful"};
  spec.maps = {path("mp") / "seed_2.csv", path("mp") / "seed-2.csv"};
  spec.failures = 100;
  spec.budget_hours = 2 * spec.minutes / 60.0;
  const HuntOutcome o = run_hunt(spec, nullptr, {});
  ASSERT_EQ(o.runs, 2U);
  std::set<std::size_t> runs;
  std::set<std::string> replays;
  for (const HuntFailure& f : o.failures) {
    runs.insert(f.run);
    replays.insert(f.replay);
    const replay::Replay r = replay::read_replay(spec.out / f.replay);
    EXPECT_EQ(r.header.provenance.track, f.map) << f.replay;
  }
  ASSERT_EQ(runs.size(), 2U) << "a run on each map fails";
  EXPECT_EQ(replays.size(), 2U);
}

}  // namespace
}  // namespace overtake::app
