// C++ planner plugins (overtake/planner_plugin.h): loading and its refusals, what a plugin
// is told and in which units, plugins that fail while driving (the run ends planner_failed
// with the reason, nothing crashes), the example plugin driving without collisions, and
// `drive`/`bench --policy-lib` through the binary.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <unistd.h>

#include "overtake/app/commands.hpp"
#include "overtake/app/io.hpp"
#include "overtake/app/planners.hpp"
#include "overtake/core/units.hpp"
#include "overtake/plugin/plugin.hpp"
#include "overtake/protocol/codec.hpp"
#include "overtake/protocol/server.hpp"
#include "process_support.hpp"

namespace overtake::plugin {
namespace {

using nlohmann::json;
using ::testing::AllOf;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

/// The test plugin built from tests/plugin/plugins/misbehaving.cpp with MISBEHAVE=mode.
std::string misbehaving(const std::string& mode) {
  return std::string(OVERTAKE_PLUGIN_DIR) + "/libovertake_test_plugin_" + mode + ".so";
}

/// PluginError's message when loading `path`, or "" when it loads.
std::string load_error(const std::string& path) {
  try {
    (void)load_plugin(path);
  } catch (const PluginError& e) {
    return e.what();
  }
  return "";
}

const app::Track& track() {
  static const auto t = app::load_track(std::nullopt);
  return *t;
}

/// A drive of the plugin at `path` (under the plugin's own name).
app::DriveResult drive_plugin(const std::string& path, double minutes, std::uint64_t seed,
                              const std::string& traffic = "faithful") {
  app::PlannerFlags flags;
  flags.libs = {path};
  app::DriveOptions o;
  o.planners = app::catalog_from_flags(flags);
  o.policy = o.planners->added_names().at(0);
  o.minutes = minutes;
  o.seed = seed;
  o.traffic = traffic;
  return app::drive(o);
}

// ---- loading ---------------------------------------------------------------------------

TEST(PluginLoad, TheExampleGivesItsNameAndSummary) {
  const LoadedPlugin p = load_plugin(OVERTAKE_KEEP_LANE_PLUGIN);
  EXPECT_EQ(p.name, "keep_lane");
  EXPECT_THAT(p.summary, HasSubstr("lane"));
  ASSERT_TRUE(p.make);
}

TEST(PluginLoad, AMissingFileIsRefusedWithTheLoadersReason) {
  EXPECT_THAT(load_error("/nonexistent/libnothing.so"),
              AllOf(HasSubstr("/nonexistent/libnothing.so"), HasSubstr("cannot load")));
}

TEST(PluginLoad, AFileThatIsNoLibraryIsRefused) {
  const fs::path f = fs::temp_directory_path() / ("not_a_plugin_" + std::to_string(::getpid()));
  std::ofstream(f) << "hello\n";
  EXPECT_THAT(load_error(f.string()), HasSubstr("cannot load"));
  fs::remove(f);
}

TEST(PluginLoad, AWrongVersionSaysBothVersions) {
  const std::string e = load_error(misbehaving("wrong_version"));
  EXPECT_THAT(e, HasSubstr("libovertake_test_plugin_wrong_version.so"));
  EXPECT_THAT(e, HasSubstr("ABI version 99"));
  EXPECT_THAT(e, HasSubstr("speaks version 1"));
}

TEST(PluginLoad, AMissingFunctionIsNamedWithTheFile) {
  const std::string e = load_error(OVERTAKE_MISSING_SYMBOL_PLUGIN);
  EXPECT_THAT(e, HasSubstr("overtake_plugin_destroy"));
  EXPECT_THAT(e, HasSubstr("libovertake_test_plugin_missing_symbol.so"));
}

TEST(PluginLoad, TheCatalogTurnsARefusalIntoAUsageError) {
  app::PlannerFlags flags;
  flags.libs = {misbehaving("wrong_version")};
  EXPECT_THROW((void)app::catalog_from_flags(flags), app::UsageError);
}

TEST(PluginLoad, TheLibraryStaysLoadedWhileAPolicyLives) {
  std::unique_ptr<planner::Policy> policy;
  {
    const LoadedPlugin p = load_plugin(OVERTAKE_KEEP_LANE_PLUGIN);
    policy = p.make(track().line, planner::PlannerParams{});
  }  // the factory is gone; the policy keeps the library
  core::Telemetry t;
  t.ego.s_m = 124.8336;
  t.ego.d_m = 6.0;
  t.ego.position = track().line.to_cartesian({t.ego.s_m, t.ego.d_m});
  t.ego.yaw_rad = track().line.frame(t.ego.s_m).heading_rad;
  const core::PlanResult r = policy->plan(t);
  EXPECT_EQ(r.path.size(), 50U);
}

// ---- what the plugin is told ----------------------------------------------------------

TEST(PluginTelemetry, TheOriginalsUnitsAndFieldsReachThePlugin) {
  const LoadedPlugin p = load_plugin(misbehaving("echo"));
  auto policy = p.make(track().line, planner::PlannerParams{});
  core::Telemetry t;
  t.ego.position = {909.48, 1128.67};
  t.ego.s_m = 124.8336;
  t.ego.d_m = 6.164833;
  t.ego.yaw_rad = core::deg_to_rad(271.5);
  t.ego.speed_mps = core::mph_to_mps(49.5);
  t.previous_path = {{910.0, 1128.5}, {911.0, 1128.25}};
  t.end_path = {126.5, 6.25};
  core::CarObservation car;
  car.id = 4;
  car.position = {775.99, 1132.11};
  car.velocity_mps = {22.1, -0.3651};
  car.s_m = 85.3;
  car.d_m = 2.012;
  t.cars = {car};
  const std::vector<core::Vec2> e = policy->plan(t).path;
  ASSERT_EQ(e.size(), 5U + 2U + 4U);
  EXPECT_EQ(e[0], (core::Vec2{909.48, 1128.67}));
  EXPECT_EQ(e[1], (core::Vec2{124.8336, 6.164833}));
  // Yaw in degrees and speed in mph, exactly as the original's wire prints them.
  EXPECT_EQ(e[2].x, 271.5);
  EXPECT_EQ(e[2].y, 49.5);
  EXPECT_EQ(e[3], (core::Vec2{2.0, 126.5}));
  EXPECT_EQ(e[4], (core::Vec2{6.25, 1.0}));
  EXPECT_EQ(e[5], (core::Vec2{910.0, 1128.5}));
  EXPECT_EQ(e[6], (core::Vec2{911.0, 1128.25}));
  // Sensor fusion: [id, x, y, vx, vy, s, d], velocity in m/s.
  EXPECT_EQ(e[7], (core::Vec2{4.0, 775.99}));
  EXPECT_EQ(e[8], (core::Vec2{1132.11, 22.1}));
  EXPECT_EQ(e[9], (core::Vec2{-0.3651, 85.3}));
  EXPECT_EQ(e[10], (core::Vec2{2.012, 0.0}));
}

// ---- plugins that fail while driving --------------------------------------------------

struct Failure {
  const char* mode;
  const char* reason;
};

class FailingPlugin : public ::testing::TestWithParam<Failure> {};

TEST_P(FailingPlugin, EndsTheRunAsPlannerFailedNamingThePlugin) {
  const Failure f = GetParam();
  const app::DriveResult r = drive_plugin(misbehaving(f.mode), 0.5, 1);
  EXPECT_EQ(r.report.outcome.end, sim::RunEnd::planner_failed);
  EXPECT_THAT(r.report.outcome.reason, HasSubstr(std::string("plugin misbehaving_") + f.mode));
  EXPECT_THAT(r.report.outcome.reason, HasSubstr(f.reason));
}

INSTANTIATE_TEST_SUITE_P(
    Modes, FailingPlugin,
    ::testing::Values(Failure{"throws", "threw an exception: planner exploded"},
                      Failure{"nan", "non-finite point (index 0)"},
                      Failure{"status", "failed (status 7): lost track of the lane"},
                      Failure{"too_many", "more than the buffers'"},
                      Failure{"create_fails", "create failed: no config given"},
                      Failure{"create_throws", "create threw an exception: cannot start"}),
    [](const ::testing::TestParamInfo<Failure>& p) { return std::string(p.param.mode); });

TEST(FailingPluginServe, ASessionRepliesManualAndGoesOn) {
  const LoadedPlugin p = load_plugin(misbehaving("status"));
  protocol::PlannerSession session(p.make(track().line, planner::PlannerParams{}), {}, 1 << 20);
  core::Telemetry t;
  t.ego.position = {909.48, 1128.67};
  t.ego.s_m = 124.8336;
  t.ego.d_m = 6.164833;
  const std::string text = protocol::format_telemetry(t);
  for (int i = 0; i < 30; ++i) {
    const protocol::FrameOutcome o = session.handle({text, false, false, text.size()});
    ASSERT_TRUE(o.reply.has_value());
    if (i < 20) {
      EXPECT_TRUE(o.planned);
    } else {
      EXPECT_FALSE(o.planned);
      EXPECT_EQ(*o.reply, "42[\"manual\",{}]");
      ASSERT_TRUE(o.warning.has_value());
      EXPECT_THAT(*o.warning, HasSubstr("lost track of the lane"));
    }
  }
}

// ---- the example plugin ---------------------------------------------------------------

class ExamplePlugin : public ::testing::TestWithParam<std::tuple<const char*, int>> {};

TEST_P(ExamplePlugin, DrivesWithoutCollisionsWithinTheLimits) {
  const auto [traffic, seed] = GetParam();
  const app::DriveResult r = drive_plugin(OVERTAKE_KEEP_LANE_PLUGIN, 3.0, seed, traffic);
  const json j = app::report_to_json(r.report, r.provenance);
  EXPECT_EQ(j["end"], "completed") << j["ended_early"];
  EXPECT_EQ(j["incident_counts"]["collision"], 0);
  EXPECT_EQ(j["incident_counts"]["speeding"], 0);
  EXPECT_EQ(j["incident_counts"]["max_acceleration"], 0);
  EXPECT_EQ(j["incident_counts"]["max_jerk"], 0);
  EXPECT_GT(j["distance_miles"].get<double>(), 1.5);  // 3 minutes, mostly near 49 mph
  EXPECT_EQ(j["config"]["policy"], "keep_lane");
}

INSTANTIATE_TEST_SUITE_P(Runs, ExamplePlugin,
                         ::testing::Combine(::testing::Values("faithful", "calm"),
                                            ::testing::Values(1, 2)),
                         [](const auto& p) {
                           return std::string(std::get<0>(p.param)) + "_seed" +
                                  std::to_string(std::get<1>(p.param));
                         });

// ---- through the binary ----------------------------------------------------------------

class PluginCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("overtake_plugin_cli_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  /// Runs the binary; its exit status (nullopt: it hung), stdout and stderr.
  std::tuple<std::optional<int>, std::string, std::string> run(
      const std::vector<std::string>& args) {
    const pid_t pid = test::start_overtake(args, dir_ / "out.txt", dir_ / "err.txt");
    const auto status = test::exit_status(pid, std::chrono::minutes(5));
    return {status, read(dir_ / "out.txt"), read(dir_ / "err.txt")};
  }
  static std::string read(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }
  fs::path dir_;
};

TEST_F(PluginCli, DriveRunsThePlugin) {
  const fs::path report = dir_ / "report.json";
  const auto [status, out, err] =
      run({"drive", "--policy-lib", OVERTAKE_KEEP_LANE_PLUGIN, "--minutes", "1", "--seed", "1",
           "--quiet", "--json", report.string()});
  ASSERT_EQ(status, 0) << err;
  const json j = json::parse(read(report));
  EXPECT_EQ(j["config"]["policy"], "keep_lane");
  EXPECT_EQ(j["incident_counts"]["collision"], 0);
}

TEST_F(PluginCli, DriveWithAFailingPluginEndsCleanlyWithTheReason) {
  const auto [status, out, err] = run(
      {"drive", "--policy-lib", misbehaving("throws"), "--minutes", "1", "--seed", "1", "--quiet"});
  ASSERT_TRUE(status.has_value());
  EXPECT_EQ(*status, 1) << err;  // kExitFailure: the run ended, the program did not crash
  EXPECT_THAT(out + err, HasSubstr("planner exploded"));
}

TEST_F(PluginCli, DriveRefusesABadPluginBeforeRunning) {
  const auto [status, out, err] =
      run({"drive", "--policy-lib", misbehaving("wrong_version"), "--minutes", "1"});
  EXPECT_EQ(status, 2);
  EXPECT_THAT(err, AllOf(HasSubstr("--policy-lib"), HasSubstr("ABI version 99")));
}

TEST_F(PluginCli, BenchRunsPluginsBesideEachOtherAndSurvivesAFailingOne) {
  const fs::path out_dir = dir_ / "bench";
  const auto [status, out, err] = run(
      {"bench", "--policy-lib", OVERTAKE_KEEP_LANE_PLUGIN, "--policy-lib",
       "bad=" + misbehaving("nan"), "--policies", "keep_lane,bad", "--seeds", "1-2", "--traffic",
       "calm", "--minutes", "0.5", "--jobs", "2", "--quiet", "--out", out_dir.string()});
  ASSERT_TRUE(status.has_value());
  EXPECT_LT(*status, 1000) << "killed by a signal: " << err;
  std::ifstream runs(out_dir / "runs.jsonl");
  int keep_lane = 0, bad = 0;
  for (std::string line; std::getline(runs, line);) {
    const json j = json::parse(line);
    if (j["config"]["policy"] == "keep_lane") {
      ++keep_lane;
      EXPECT_EQ(j["end"], "completed");
    } else if (j["config"]["policy"] == "bad") {
      ++bad;
      EXPECT_EQ(j["end"], "planner_failed");
      EXPECT_THAT(j["ended_early"].get<std::string>(), HasSubstr("non-finite point"));
    }
  }
  EXPECT_EQ(keep_lane, 2) << err;
  EXPECT_EQ(bad, 2) << err;
}

}  // namespace
}  // namespace overtake::plugin
