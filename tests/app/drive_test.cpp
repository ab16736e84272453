// `overtake drive` end to end: determinism, the JSON report's keys, and bad flags.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "overtake/app/cli.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"

namespace overtake::app {

using base::read_file;
using base::UsageError;
using base::write_file_atomic;
using run::drive;
using run::DriveOptions;
using run::DriveResult;
using run::report_to_json;
namespace {

using nlohmann::json;
using ::testing::HasSubstr;

json report_without_timing(const DriveOptions& o) {
  const DriveResult r = drive(o);
  json j = report_to_json(r.report, r.provenance);
  j.erase("timing");
  return j;
}

DriveOptions short_drive(std::uint64_t seed, const std::string& traffic = "faithful") {
  DriveOptions o;
  o.minutes = 2.0;
  o.seed = seed;
  o.traffic = traffic;
  return o;
}

TEST(DriveDeterminism, SameSeedSameReportByteForByte) {
  for (const char* traffic : {"faithful", "calm"}) {
    const std::string a = report_without_timing(short_drive(7, traffic)).dump();
    const std::string b = report_without_timing(short_drive(7, traffic)).dump();
    EXPECT_EQ(a, b) << traffic;
  }
}

TEST(DriveDeterminism, DifferentSeedsDiffer) {
  EXPECT_NE(report_without_timing(short_drive(1)).dump(),
            report_without_timing(short_drive(2)).dump());
}

TEST(DriveReport, HasTheDocumentedKeys) {
  const json j = report_without_timing(short_drive(3));
  for (const char* key :
       {"distance_miles", "duration_s", "mean_speed_mph", "best_incident_free_miles",
        "incident_counts", "incidents", "peak", "lane_changes", "config"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  for (const char* type :
       {"collision", "speeding", "max_acceleration", "max_jerk", "outside_lane"}) {
    EXPECT_TRUE(j["incident_counts"].contains(type)) << type;
  }
  for (const char* key : {"speed_mph", "acceleration_mps2", "jerk_mps3", "strict_acceleration_mps2",
                          "strict_jerk_mps3"}) {
    EXPECT_TRUE(j["peak"].contains(key)) << key;
  }
  EXPECT_EQ(j["config"]["seed"], 3);
  EXPECT_EQ(j["config"]["policy"], "reference");
  EXPECT_EQ(j["config"]["traffic"], "faithful");
  EXPECT_EQ(j["config"]["map"]["path"], "builtin:default");
  EXPECT_EQ(j["config"]["steps_per_call"], "random 1-3");
  EXPECT_DOUBLE_EQ(j["duration_s"].get<double>(), 120.0);
  // How it ended, as a value beside the one-line text, and how the planner planned.
  EXPECT_EQ(j["end"], "completed");
  EXPECT_TRUE(j["ended_early"].is_null());
  const json& cycles = j["plan_status"]["cycles"];
  EXPECT_EQ(cycles["normal"].get<long>() + cycles["least_bad"].get<long>() +
                cycles["fallback"].get<long>(),
            j["planner_cycles"].get<long>());
}

// The lane changes the reference's behaviour chose and its trajectory layer did not take, by
// why: on the built-in track in faithful traffic it happens every few seconds, for the cost of
// the shorter gap (a path into the lane passed the checks) about as often as for safety (seed
// 1, 10 minutes: 57 and 53). A policy without a decision layer of its own declines none.
TEST(DriveReport, CountsTheLaneChangesThePlannerDeclined) {
  DriveOptions o = short_drive(1);
  o.minutes = 10.0;
  const DriveResult r = drive(o);
  const json declined =
      report_to_json(r.report, r.provenance)["plan_status"]["lane_changes_declined"];
  const long cost = declined["for_cost"].get<long>();
  const long safety = declined["for_safety"].get<long>();
  EXPECT_GT(cost, 10);
  EXPECT_GT(safety, 10);
  // Each is a cycle whose behaviour wanted another lane: far fewer than the cycles.
  EXPECT_LT(cost + safety, r.report.planner_cycles / 20);
  o.policy = "walkthrough";
  o.minutes = 2.0;
  const DriveResult w = drive(o);
  const json none = report_to_json(w.report, w.provenance)["plan_status"]["lane_changes_declined"];
  EXPECT_EQ(none["for_cost"], 0);
  EXPECT_EQ(none["for_safety"], 0);
}

TEST(DriveReport, TimingLivesUnderItsOwnKey) {
  const DriveResult r = drive(short_drive(3));
  const json j = report_to_json(r.report, r.provenance);
  ASSERT_TRUE(j.contains("timing"));
  EXPECT_GT(j["timing"]["p50_us"].get<double>(), 0.0);
  EXPECT_GE(j["timing"]["p99_us"].get<double>(), j["timing"]["p50_us"].get<double>());
  EXPECT_GE(j["timing"]["max_us"].get<double>(), j["timing"]["p99_us"].get<double>());
  // An in-process planner is timed on its thread's CPU clock; the wall clock is kept beside.
  EXPECT_EQ(j["timing"]["clock"], "thread_cpu");
  EXPECT_GE(j["timing"]["wall_max_us"].get<double>(), j["timing"]["wall_p99_us"].get<double>());
  EXPECT_GT(j["timing"]["wall_p99_us"].get<double>(), 0.0);
}

TEST(DriveReport, FixedStepsPerCallIsRecorded) {
  DriveOptions o = short_drive(3);
  o.steps_per_call = 2;
  const DriveResult r = drive(o);
  EXPECT_EQ(report_to_json(r.report, r.provenance)["config"]["steps_per_call"], "2");
  // 2 minutes at 2 steps per reply: 3000 planner cycles.
  EXPECT_EQ(r.report.planner_cycles, 3000);
}

std::string usage_error(const DriveOptions& o) {
  try {
    (void)drive(o);
  } catch (const UsageError& e) {
    return e.what();
  }
  return "";
}

TEST(DriveErrors, UnknownPolicyListsTheAvailableOnes) {
  DriveOptions o = short_drive(1);
  o.policy = "nope";
  const std::string e = usage_error(o);
  EXPECT_THAT(e, HasSubstr("--policy: unknown policy 'nope'"));
  EXPECT_THAT(e, HasSubstr("walkthrough"));
}

TEST(DriveErrors, UnknownTrafficProfile) {
  EXPECT_THAT(usage_error(short_drive(1, "dense")),
              HasSubstr("--traffic: unknown profile 'dense'"));
}

TEST(DriveErrors, BadNumbersNameTheFlag) {
  DriveOptions o = short_drive(1);
  o.minutes = 0;
  EXPECT_THAT(usage_error(o), HasSubstr("--minutes must be more than 0"));
  o.minutes = -3;
  EXPECT_THAT(usage_error(o), HasSubstr("--minutes"));
  o = short_drive(1);
  o.steps_per_call = 5000;
  EXPECT_THAT(usage_error(o), HasSubstr("--steps-per-call must be between 1 and 1000"));
}

TEST(DriveErrors, BadMapFileIsAMapErrorNamingTheLine) {
  const auto path = std::filesystem::temp_directory_path() / "overtake_drive_bad_map.csv";
  write_file_atomic(path, "0 0 0 0 1\n1 2 3\n");
  DriveOptions o = short_drive(1);
  o.map = path;
  try {
    (void)drive(o);
    FAIL();
  } catch (const core::MapError& e) {
    EXPECT_THAT(std::string(e.what()), HasSubstr(path.string() + ":2:"));
  }
  std::filesystem::remove(path);
}

int cli(std::vector<const char*> args) {
  args.insert(args.begin(), "overtake");
  return run_cli(static_cast<int>(args.size()), args.data());
}

TEST(Cli, ExitCodesAndMessages) {
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"drive", "--minutes", "abc"}), 2);
  EXPECT_THAT(testing::internal::GetCapturedStderr(), HasSubstr("--minutes"));

  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"drive", "--policy", "nope", "--minutes", "0.1"}), 2);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_THAT(err, HasSubstr("unknown policy 'nope' (available: "));
  EXPECT_THAT(err, HasSubstr("walkthrough"));

  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"drive", "--map", "/nonexistent/map.csv"}), 2);
  EXPECT_THAT(testing::internal::GetCapturedStderr(), HasSubstr("/nonexistent/map.csv"));

  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"fly"}), 2);
  (void)testing::internal::GetCapturedStderr();
}

TEST(Cli, DriveWritesTheJsonReport) {
  const auto path = std::filesystem::temp_directory_path() / "overtake_cli_report.json";
  std::filesystem::remove(path);
  testing::internal::CaptureStdout();
  EXPECT_EQ(cli({"drive", "--minutes", "0.5", "--seed", "4", "--json", path.c_str(), "--quiet"}),
            0);
  const std::string out = testing::internal::GetCapturedStdout();
  EXPECT_THAT(out, HasSubstr("mean speed"));
  const json j = json::parse(read_file(path));
  EXPECT_EQ(j["config"]["seed"], 4);
  EXPECT_DOUBLE_EQ(j["duration_s"].get<double>(), 30.0);
  std::filesystem::remove(path);
}

TEST(Cli, JsonToAnUnwritablePlaceFailsWithTheScorecardPrinted) {
  testing::internal::CaptureStdout();
  testing::internal::CaptureStderr();
  EXPECT_EQ(cli({"drive", "--minutes", "0.2", "--json", "/nonexistent/dir/r.json", "--quiet"}), 1);
  EXPECT_THAT(testing::internal::GetCapturedStdout(), HasSubstr("mean speed"));
  EXPECT_THAT(testing::internal::GetCapturedStderr(), HasSubstr("/nonexistent/dir/r.json"));
}

}  // namespace
}  // namespace overtake::app
