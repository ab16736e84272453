// Planners from outside brought in step before a cut (docs/scenarios.md): a failure of the example
// planner program is hunted, cut with the warm-up, and repeats at its step through `hunt`'s own
// check and through `sim --scenario`; a planner program that is not deterministic is named as
// such; a program driving another map than overtake's gets the hint; bad --warm-up values and
// damaged warm-ups are refused naming them.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>

#include "overtake/app/cli.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/scenario_file.hpp"
#include "overtake/sandbox/planner_process.hpp"
#include "overtake/scenarios/cut.hpp"
#include "process_support.hpp"
#include "temp_dir.hpp"

namespace overtake::app {

using base::read_file;
using base::UsageError;
using run::ConfigError;
using run::pack_blob;
using run::parse_scenario;
using sandbox::private_network_available;
using scenarios::parse_warm_up;
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;

class WarmUpTest : public ::testing::Test {
 protected:
  void SetUp() override {
    // The programs listen on a fixed port: each run gets a network of its own, and a test
    // never counts on the host's port being free.
    std::string why;
    if (!private_network_available(&why)) GTEST_SKIP() << "no private network: " << why;
  }

  [[nodiscard]] fs::path path(const std::string& name) const { return dir_.path() / name; }

  int run(const std::vector<std::string>& args) {
    const pid_t pid = test::start_overtake(args, path("stdout"), path("stderr"));
    const auto status = test::exit_status(pid, std::chrono::minutes(5));
    out_ = read_file(path("stdout"));
    err_ = read_file(path("stderr"));
    return status.value_or(-1);
  }

  static std::string example() {
    return (fs::path(OVERTAKE_BINARY_DIR) / "tests" / "overtake_example_program").string() + " " +
           (fs::path(OVERTAKE_SOURCE_DIR) / "data/tracks/default.csv").string();
  }
  static std::string course_planner() {
    return (fs::path(OVERTAKE_BINARY_DIR) / "tests" / "overtake_course_planner").string();
  }

  test::TempDir dir_{"overtake-warm-up"};
  std::string out_, err_;
};

// Seed 6 in faithful traffic: the example program sideswipes a car at t 100.04 s (its own
// fault). hunt finds it, cuts it with the default warm-up, and its check drives both scenarios
// again at once: the same collision at the same step. `sim --scenario` repeats it too, the
// program in step before the start.
TEST_F(WarmUpTest, AFailureOfTheExampleProgramIsHuntedCutAndRepeatedAtItsStep) {
  const fs::path out = path("hunt");
  ASSERT_EQ(run({"hunt",     "--planner-cmd",  example(), "--planner-name", "example", "--traffic",
                 "faithful", "--first-seed",   "6",       "--minutes",      "2",       "--failures",
                 "1",        "--budget-hours", "0.034",   "--jobs",         "1",       "--quiet",
                 "--out",    out.string()}),
            0)
      << err_;
  const json hunt = json::parse(read_file(out / "hunt.json"));
  ASSERT_EQ(hunt["failures"].size(), 1u) << hunt.dump(2);
  EXPECT_DOUBLE_EQ(hunt["failures"][0]["t_s"].get<double>(), 100.04);
  EXPECT_EQ(hunt["failures"][0]["what"], "collision side_contact (at fault)");
  ASSERT_EQ(hunt["groups"].size(), 1u);
  const json& g = hunt["groups"][0];
  EXPECT_EQ(g["cut_error"], "");
  EXPECT_TRUE(g["reproduced"].get<bool>()) << g.dump(2);
  EXPECT_THAT(g["reproduces"]["reactive"].get<std::string>(), StartsWith("yes (in step after"));
  EXPECT_THAT(g["reproduces"]["replayed"].get<std::string>(), StartsWith("yes (in step after"));
  EXPECT_TRUE(g["nondeterministic"].is_null());
  // The command it prints brings the program, not a policy of that name.
  EXPECT_THAT(g["repro"].get<std::string>(), StartsWith("overtake sim --planner-cmd "));
  EXPECT_THAT(read_file(out / "hunt.md"), HasSubstr("yes (in step after"));

  const fs::path scenario = out / g["reactive"].get<std::string>();
  const json file = json::parse(read_file(scenario));
  EXPECT_GT(file["cut"]["warm_up"]["cycles"].get<int>(), 1000);  // 60 s of cycles
  EXPECT_TRUE(file["cut"]["from"]["exact_start"].get<bool>());
  for (const char* traffic : {"reactive", "replayed"}) {
    const fs::path report = path(std::string(traffic) + ".json");
    ASSERT_EQ(run({"sim", "--planner-cmd", example(), "--planner-name", "example", "--scenario",
                   (out / g[traffic].get<std::string>()).string(), "--planner-log",
                   path("sim.log").string(), "--json", report.string(), "--quiet"}),
              0)
        << err_;
    const json r = json::parse(read_file(report));
    ASSERT_EQ(r["collisions"]["contacts"].size(), 1u) << traffic << r["collisions"].dump(2);
    EXPECT_DOUBLE_EQ(r["collisions"]["contacts"][0]["t_s"].get<double>(), 100.04) << traffic;
    EXPECT_EQ(r["collisions"]["contacts"][0]["kind"], "side_contact") << traffic;
    EXPECT_TRUE(r["warm_up"]["in_step"].get<bool>()) << r["warm_up"].dump();
    // Nothing booked before the failure that the run did not book: the hand-over is smooth.
    for (const json& i : r["incidents"]) {
      EXPECT_GE(i["t_s"].get<double>(), 100.04) << traffic << " " << i.dump();
    }
  }
  // A suite of the hunt's scenarios with the program: the warm-up is played there too, so both
  // repeat the at-fault collision, and the suite fails them for it.
  ASSERT_EQ(
      run({"bench", "--scenarios", (out / "scenarios").string(), "--planner-cmd", example(),
           "--planner-name", "example", "--jobs", "2", "--quiet", "--out", path("suite").string()}),
      1)
      << err_;
  const json suite = json::parse(read_file(path("suite") / "suite.json"));
  ASSERT_EQ(suite["verdicts"].size(), 2u) << suite.dump(2);
  for (const json& v : suite["verdicts"]) {
    EXPECT_FALSE(v["pass"].get<bool>());
    EXPECT_THAT(v["failures"].dump(), HasSubstr("side_contact at t 100.04 s")) << v.dump();
    EXPECT_THAT(v["warm_up"].get<std::string>(), HasSubstr("in step after")) << v.dump();
  }
  // Without the warm-up the program starts afresh in a car at speed: it asks for a standstill.
  const fs::path afresh = path("afresh.json");
  ASSERT_EQ(run({"sim", "--planner-cmd", example(), "--planner-name", "example", "--scenario",
                 scenario.string(), "--no-warm-up", "--planner-log", path("sim.log").string(),
                 "--json", afresh.string(), "--quiet"}),
            0)
      << err_;
  const json r = json::parse(read_file(afresh));
  EXPECT_FALSE(r.contains("warm_up"));
  EXPECT_GT(r["incident_counts"]["max_acceleration"].get<int>(), 0) << r["incidents"].dump();
}

// A window too short to bring the program in step (1 s, where its target speed needs about 11 s
// to climb to its cap): the hunt cuts the failure again with every cycle from the run's first,
// and then it repeats in step.
TEST_F(WarmUpTest, AHuntCutsAgainFromTheRunsStartWhenTheWarmUpIsTooShort) {
  const fs::path out = path("hunt");
  ASSERT_EQ(run({"hunt",     "--planner-cmd",  example(), "--planner-name", "example", "--traffic",
                 "faithful", "--first-seed",   "6",       "--minutes",      "2",       "--failures",
                 "1",        "--budget-hours", "0.034",   "--warm-up",      "1",       "--jobs",
                 "1",        "--quiet",        "--out",   out.string()}),
            0)
      << err_;
  const json hunt = json::parse(read_file(out / "hunt.json"));
  ASSERT_EQ(hunt["groups"].size(), 1u) << hunt.dump(2);
  const json& g = hunt["groups"][0];
  EXPECT_EQ(g["warm_up"], "all (1 s did not bring it in step)") << g.dump(2);
  EXPECT_TRUE(g["reproduced"].get<bool>()) << g.dump(2);
  const json file = json::parse(read_file(out / g["reactive"].get<std::string>()));
  EXPECT_TRUE(file["cut"]["warm_up"]["from_run_start"].get<bool>());
  EXPECT_DOUBLE_EQ(file["cut"]["warm_up"]["start_s"].get<double>(), 0.0);
}

// A program whose answers move by a random amount: told the same twice, it answers differently,
// and hunt names it, with the first cycle that differed.
TEST_F(WarmUpTest, APlannerThatIsNotDeterministicIsNamed) {
  const fs::path out = path("hunt");
  ASSERT_EQ(run({"hunt",
                 "--planner-cmd",
                 course_planner() + " --random",
                 "--planner-name",
                 "jittery",
                 "--traffic",
                 "faithful",
                 "--minutes",
                 "1",
                 "--find",
                 "incidents",
                 "--failures",
                 "1",
                 "--budget-hours",
                 "0.2",
                 "--jobs",
                 "1",
                 "--warm-up",
                 "5",
                 "--quiet",
                 "--out",
                 out.string()}),
            0)
      << err_;
  const json hunt = json::parse(read_file(out / "hunt.json"));
  ASSERT_EQ(hunt["groups"].size(), 1u) << hunt.dump(2);
  const json& g = hunt["groups"][0];
  // (Its failure may come again by chance; the second drive tells it apart all the same.)
  ASSERT_TRUE(g["nondeterministic"].is_string()) << g.dump(2);
  EXPECT_THAT(g["nondeterministic"].get<std::string>(),
              HasSubstr("told the same twice, it answered differently at "));
  EXPECT_THAT(read_file(out / "hunt.md"), HasSubstr("The planner is not deterministic"));
}

// The example program reads the map it is given; told another track than the run's, its path
// leaves the road at once, and the scorecard and the report say why.
TEST_F(WarmUpTest, AProgramDrivingAnotherMapGetsTheHint) {
  const std::string program =
      (fs::path(OVERTAKE_BINARY_DIR) / "tests" / "overtake_example_program").string() + " " +
      (fs::path(OVERTAKE_SOURCE_DIR) / "data/tracks/seed2.csv").string();
  const fs::path report = path("r.json");
  ASSERT_EQ(run({"sim", "--planner-cmd", program, "--planner-name", "lost", "--minutes", "0.5",
                 "--planner-log", path("sim.log").string(), "--json", report.string()}),
            0)
      << err_;
  EXPECT_THAT(out_, HasSubstr("HINT: the planner's path left the road"));
  EXPECT_THAT(out_, HasSubstr("--map FILE"));
  const json r = json::parse(read_file(report));
  EXPECT_THAT(r["map_hint"].get<std::string>(), HasSubstr("may be driving another map"));
  // The bench says it under its table.
  ASSERT_EQ(run({"bench", "--planner-cmd", program, "--planner-name", "lost", "--seeds", "1-2",
                 "--minutes", "0.5", "--traffic", "faithful", "--jobs", "2", "--quiet", "--out",
                 path("bench").string()}),
            0)
      << err_;
  EXPECT_THAT(read_file(path("bench") / "summary.md"),
              HasSubstr("**Hint for lost**: in 2 of 2 runs the planner's path left the road"));
  // On its own map, no hint.
  ASSERT_EQ(run({"sim", "--planner-cmd", example(), "--planner-name", "home", "--minutes", "0.5",
                 "--planner-log", path("sim.log").string(), "--json", report.string()}),
            0)
      << err_;
  EXPECT_THAT(out_, Not(HasSubstr("HINT")));
  EXPECT_FALSE(json::parse(read_file(report)).contains("map_hint"));
}

TEST(WarmUpInput, BadWarmUpFlagsAreRefusedNamingThem) {
  double seconds = 0.0;
  bool all = false;
  parse_warm_up("all", seconds, all);
  EXPECT_TRUE(all);
  parse_warm_up("12.5", seconds, all);
  EXPECT_FALSE(all);
  EXPECT_DOUBLE_EQ(seconds, 12.5);
  for (const char* bad : {"", "abc", "-1", "5s", "nan", "1e9"}) {
    try {
      parse_warm_up(bad, seconds, all);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const UsageError& e) {
      EXPECT_THAT(e.what(), HasSubstr("--warm-up: '" + std::string(bad) + "'"));
    }
  }
}

TEST(WarmUpInput, ADamagedWarmUpIsRefusedNamingTheKey) {
  const auto refusal = [](const json& warm_up) {
    json j = {{"name", "x"},
              {"duration_s", 20},
              {"cut",
               {{"traffic", "reactive"},
                {"start_s", 10},
                {"at_s", 20},
                {"checkpoint", pack_blob("x")},
                {"warm_up", warm_up}}}};
    try {
      (void)parse_scenario(j, "s.json", core::RoadParams{});
    } catch (const ConfigError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_THAT(refusal(json::array()), HasSubstr("scenario.cut.warm_up: expected an object"));
  EXPECT_THAT(refusal({{"start_s", 1}, {"cycles", 3}}),
              HasSubstr("scenario.cut.warm_up.telemetry: missing"));
  EXPECT_THAT(refusal({{"start_s", 1}, {"cycles", 3}, {"telemetry", "%%%"}}),
              HasSubstr("scenario.cut.warm_up.telemetry: not base64"));
  EXPECT_THAT(refusal({{"start_s", 1}, {"cycles", -3}, {"telemetry", pack_blob("x")}}),
              HasSubstr("scenario.cut.warm_up.cycles"));
  EXPECT_THAT(refusal({{"start_s", 1}, {"cycles", 3}, {"telemetry", pack_blob("x")}, {"k", 1}}),
              HasSubstr("scenario.cut.warm_up.k: unknown key"));
}

}  // namespace
}  // namespace overtake::app
