// The same seeds give the same reports, byte for byte, across restructurings: a set of runs
// (every policy, both traffic profiles, fixed and drawn latency, a scripted scenario, a
// replay) is driven through the `overtake` binary and each report compared with the one kept
// in tests/data/golden_reports.jsonl, key by key, as JSON text. Keys a report gained after
// the file was written are listed, not compared; a key the file has and the report lost
// fails. `timing` is never compared (it is not part of the determinism promise).
//
// To write the file anew after a change that is meant to change behaviour:
//   OVERTAKE_UPDATE_GOLDEN=1 ./build/release/tests/overtake_app_tests
//   --gtest_filter='GoldenReports.*'

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "process_support.hpp"

namespace overtake {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

struct GoldenRun {
  std::string name;
  std::vector<std::string> args;  // after `overtake drive`
};

std::vector<GoldenRun> golden_runs() {
  std::vector<GoldenRun> runs;
  const std::vector<std::string> policies = {"reference", "walkthrough", "seed000", "seed001",
                                             "seed002",   "seed003",     "seed004"};
  for (const std::string& policy : policies) {
    for (const std::string traffic : {"faithful", "calm"}) {
      for (const std::string seed : {"1", "5"}) {
        runs.push_back(
            {policy + "-" + traffic + "-seed" + seed,
             {"--policy", policy, "--traffic", traffic, "--seed", seed, "--minutes", "3"}});
      }
    }
  }
  runs.push_back({"reference-steps1", {"--seed", "3", "--minutes", "3", "--steps-per-call", "1"}});
  runs.push_back({"reference-steps3", {"--seed", "3", "--minutes", "3", "--steps-per-call", "3"}});
  const std::string scenarios = std::string(OVERTAKE_SOURCE_DIR) + "/tests/scenarios/";
  for (const std::string scenario : {"cut_in_20m", "hard_brake_ahead", "stop_and_go"}) {
    runs.push_back({"reference-scenario-" + scenario,
                    {"--scenario", scenarios + scenario + ".json", "--minutes", "1"}});
  }
  runs.push_back(
      {"seed003-scenario-cut_in_20m",
       {"--policy", "seed003", "--scenario", scenarios + "cut_in_20m.json", "--minutes", "1"}});
  return runs;
}

fs::path golden_file() {
  return fs::path(OVERTAKE_SOURCE_DIR) / "tests" / "data" / "golden_reports.jsonl";
}

json drive_report(const GoldenRun& run, const fs::path& dir) {
  const fs::path report = dir / (run.name + ".json");
  std::vector<std::string> args = {"drive", "--quiet", "--json", report.string()};
  args.insert(args.end(), run.args.begin(), run.args.end());
  const pid_t pid = test::start_overtake(args, dir / "stdout.txt", dir / "stderr.txt");
  const auto status = test::exit_status(pid, std::chrono::minutes(5));
  EXPECT_EQ(status, 0) << run.name;
  std::ifstream in(report);
  std::stringstream text;
  text << in.rdbuf();
  json j = json::parse(text.str());
  j.erase("timing");
  return j;
}

class GoldenReports : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("overtake-golden-" + std::to_string(::getpid()) + "-" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(GoldenReports, SameSeedsGiveTheSameReportsAsTheKeptOnes) {
  const std::vector<GoldenRun> runs = golden_runs();
  if (std::getenv("OVERTAKE_UPDATE_GOLDEN") != nullptr) {
    std::ostringstream out;
    for (const GoldenRun& run : runs) {
      out << json{{"name", run.name}, {"report", drive_report(run, dir_)}}.dump() << "\n";
    }
    std::ofstream(golden_file()) << out.str();
    GTEST_SKIP() << "wrote " << golden_file();
  }
  std::ifstream in(golden_file());
  ASSERT_TRUE(in) << "missing " << golden_file();
  std::vector<json> kept;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) kept.push_back(json::parse(line));
  }
  ASSERT_EQ(kept.size(), runs.size()) << "the kept file lists other runs; write it anew";
  std::vector<std::string> added;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    ASSERT_EQ(kept[i].at("name"), runs[i].name);
    const json& want = kept[i].at("report");
    const json got = drive_report(runs[i], dir_);
    for (const auto& [key, value] : want.items()) {
      ASSERT_TRUE(got.contains(key)) << runs[i].name << ": the report lost the key " << key;
      json got_value = got.at(key);
      json want_value = value;
      if (key == "config") {
        // The parameter hash is of the config's JSON text, whose keys changed when the facts
        // the modules share (the step, the car footprint, the road's edges) came to be given
        // once each; the parameter values are the same.
        got_value.erase("params_hash");
        want_value.erase("params_hash");
      }
      EXPECT_EQ(got_value.dump(), want_value.dump()) << runs[i].name << ": key " << key;
    }
    if (i == 0) {
      for (const auto& [key, value] : got.items()) {
        if (!want.contains(key)) added.push_back(key);
      }
    }
  }
  std::string note;
  for (const std::string& k : added) note += (note.empty() ? "" : ", ") + k;
  if (!note.empty())
    std::cout << "keys added since the kept reports (not compared): " << note << "\n";
}

// The comparison is not vacuous: another seed's report differs from the kept one in the keys
// that describe the drive.
TEST_F(GoldenReports, AnotherSeedDiffers) {
  std::ifstream in(golden_file());
  ASSERT_TRUE(in) << "missing " << golden_file();
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  const json want = json::parse(line).at("report");
  GoldenRun other = golden_runs().front();
  for (std::size_t i = 0; i + 1 < other.args.size(); ++i) {
    if (other.args[i] == "--seed") other.args[i + 1] = "2";
  }
  const json got = drive_report(other, dir_);
  EXPECT_NE(got.at("distance_miles").dump(), want.at("distance_miles").dump());
  EXPECT_NE(got.at("config").dump(), want.at("config").dump());
}

}  // namespace
}  // namespace overtake
