// C++ planner plugins (overtake/planner_plugin.h): loading and its refusals (versions: the
// same major and an older or equal minor load, anything else is refused saying both), what a
// plugin is told and in which units, plugins built against the frozen 2.0 header reading and
// driving in this overtake, plugins that fail while driving or starting (the run ends
// planner_failed with the reason, nothing crashes), the example plugin driving without
// collisions, and `drive`/`bench --policy-lib` through the binary.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstddef>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <dlfcn.h>
#include <unistd.h>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/core/text_check.hpp"
#include "overtake/core/units.hpp"
#include "overtake/planner_plugin.h"
#include "overtake/planners/catalog.hpp"
#include "overtake/plugin/plugin.hpp"
#include "overtake/protocol/codec.hpp"
#include "overtake/protocol/server.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "process_support.hpp"

namespace overtake::plugin {
namespace {

using nlohmann::json;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;
namespace fs = std::filesystem;

/// The test plugin built from tests/plugin/plugins/misbehaving.cpp with MISBEHAVE=mode (or
/// another test plugin, by the end of its target's name).
std::string misbehaving(const std::string& mode) {
  return std::string(OVERTAKE_PLUGIN_DIR) + "/libovertake_test_plugin_" + mode + ".so";
}

/// "major.minor", as the loader's messages write a version.
std::string abi(int major, int minor) {
  return std::to_string(major) + "." + std::to_string(minor);
}
const std::string kOurVersion = abi(OVERTAKE_PLUGIN_ABI_MAJOR, OVERTAKE_PLUGIN_ABI_MINOR);

/// PluginError's message when loading `path`, or "" when it loads.
std::string load_error(const std::string& path) {
  try {
    (void)load_plugin(path);
  } catch (const PluginError& e) {
    return e.what();
  }
  return "";
}

const run::Track& track() {
  static const auto t = run::load_track(std::nullopt);
  return *t;
}

/// A drive of the plugin at `path` (under the plugin's own name).
run::DriveResult drive_plugin(const std::string& path, double minutes, std::uint64_t seed,
                              const std::string& traffic = "faithful") {
  planners::PlannerFlags flags;
  flags.libs = {path};
  run::DriveOptions o;
  o.planners = planners::catalog_from_flags(flags);
  o.policy = o.planners->added_names().at(0);
  o.minutes = minutes;
  o.seed = seed;
  o.traffic = traffic;
  return run::drive(o);
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

TEST(PluginLoad, AVersion1PluginIsRefusedSayingToRebuildIt) {
  const std::string e = load_error(misbehaving("old_major"));
  EXPECT_THAT(e, HasSubstr("libovertake_test_plugin_old_major.so"));
  EXPECT_THAT(e, HasSubstr("built for plugin ABI version 1, but this overtake speaks version " +
                           kOurVersion));
  EXPECT_THAT(e, HasSubstr("no longer loads version 1 plugins"));
  EXPECT_THAT(e, HasSubstr("rebuild it against this overtake's overtake/planner_plugin.h"));
}

TEST(PluginLoad, ANewerMinorIsRefusedNamingBothVersions) {
  const std::string e = load_error(misbehaving("newer_minor"));
  const std::string theirs = abi(OVERTAKE_PLUGIN_ABI_MAJOR, OVERTAKE_PLUGIN_ABI_MINOR + 1);
  EXPECT_THAT(e, HasSubstr("libovertake_test_plugin_newer_minor.so"));
  EXPECT_THAT(e, HasSubstr("built for plugin ABI version " + theirs +
                           ", but this overtake speaks version " + kOurVersion));
  EXPECT_THAT(e, HasSubstr("use an overtake of plugin ABI version " + theirs + " or later"));
  EXPECT_THAT(e, HasSubstr("or rebuild it"));
}

TEST(PluginLoad, AnotherMajorIsRefusedNamingBothVersions) {
  const std::string e = load_error(misbehaving("newer_major"));
  EXPECT_THAT(e, HasSubstr("built for plugin ABI version " + abi(OVERTAKE_PLUGIN_ABI_MAJOR + 1, 0) +
                           ", but this overtake speaks version " + kOurVersion));
}

TEST(PluginLoad, AnOlderMinorLoads) {
  // Built against the frozen 2.0 header (tests/plugin/abi/v2_0).
  EXPECT_EQ(load_error(misbehaving("echo_v2_0")), "");
  EXPECT_EQ(load_error(misbehaving("keep_lane_v2_0")), "");
}

TEST(PluginLoad, AMissingFunctionIsNamedWithTheFile) {
  const std::string e = load_error(OVERTAKE_MISSING_SYMBOL_PLUGIN);
  EXPECT_THAT(e, HasSubstr("overtake_plugin_destroy"));
  EXPECT_THAT(e, HasSubstr("libovertake_test_plugin_missing_symbol.so"));
}

TEST(PluginLoad, TheCatalogTurnsARefusalIntoAUsageError) {
  planners::PlannerFlags flags;
  flags.libs = {misbehaving("old_major")};
  EXPECT_THROW((void)planners::catalog_from_flags(flags), base::UsageError);
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

TEST(PluginLoad, APluginMayGiveNoSummary) {
  const LoadedPlugin p = load_plugin(misbehaving("quiet"));
  EXPECT_EQ(p.name, "misbehaving_quiet");
  EXPECT_EQ(p.summary, "");
}

TEST(PluginLoad, TheWatchdogsTestPluginLoads) {
  const LoadedPlugin p = load_plugin(OVERTAKE_NEVER_RETURNS_PLUGIN);
  EXPECT_EQ(p.name, "never_returns");
}

TEST(PluginLoad, TheCodeStaysMappedAfterTheLastHandleIsGone) {
  // A plugin's thread may still be finishing, or a plan call abandoned, when overtake closes
  // the library: its code must stay where it is. No other test loads this plugin.
  {
    const LoadedPlugin p = load_plugin(OVERTAKE_NEVER_RETURNS_PLUGIN);
    const auto policy = p.make(track().line, planner::PlannerParams{});
    ASSERT_TRUE(policy);
  }
  void* still = ::dlopen(OVERTAKE_NEVER_RETURNS_PLUGIN, RTLD_NOW | RTLD_NOLOAD);
  EXPECT_NE(still, nullptr) << "the library was unloaded";
  if (still != nullptr) ::dlclose(still);
}

// ---- what the plugin is told ----------------------------------------------------------

/// A telemetry with every field set, a previous path of two points and one car.
core::Telemetry full_telemetry() {
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
  return t;
}

/// Checks the points the echo plugin answers for full_telemetry(), up to the sensor fusion
/// (the fields every 2.x has), in the order tests/plugin/plugins/misbehaving.cpp writes them.
void expect_echo_of_full_telemetry(const std::vector<core::Vec2>& e) {
  ASSERT_GE(e.size(), 8U + 2U + 4U);
  EXPECT_EQ(e[0], (core::Vec2{909.48, 1128.67}));
  EXPECT_EQ(e[1], (core::Vec2{124.8336, 6.164833}));
  // Yaw in degrees and speed in mph, exactly as the original's wire prints them.
  EXPECT_EQ(e[2].x, 271.5);
  EXPECT_EQ(e[2].y, 49.5);
  EXPECT_EQ(e[3], (core::Vec2{2.0, 126.5}));
  EXPECT_EQ(e[4], (core::Vec2{6.25, 1.0}));
  // The sizes of setup, telemetry and path as this overtake has them.
  EXPECT_EQ(e[5], (core::Vec2{static_cast<double>(sizeof(overtake_plugin_setup)),
                              static_cast<double>(sizeof(overtake_telemetry))}));
  EXPECT_EQ(e[6].x, static_cast<double>(sizeof(overtake_path)));
  EXPECT_EQ(e[7], (core::Vec2{0.0, 0.0}));  // arrays with elements are not NULL
  EXPECT_EQ(e[8], (core::Vec2{910.0, 1128.5}));
  EXPECT_EQ(e[9], (core::Vec2{911.0, 1128.25}));
  // Sensor fusion: [id, x, y, vx, vy, s, d], velocity in m/s.
  EXPECT_EQ(e[10], (core::Vec2{4.0, 775.99}));
  EXPECT_EQ(e[11], (core::Vec2{1132.11, 22.1}));
  EXPECT_EQ(e[12], (core::Vec2{-0.3651, 85.3}));
  EXPECT_EQ(e[13], (core::Vec2{2.012, 0.0}));
}

TEST(PluginTelemetry, TheOriginalsUnitsAndFieldsReachThePlugin) {
  const LoadedPlugin p = load_plugin(misbehaving("echo"));
  auto policy = p.make(track().line, planner::PlannerParams{});
  const core::Telemetry t = full_telemetry();
  const std::vector<core::Vec2> e = policy->plan(t).path;
  ASSERT_EQ(e.size(), 8U + 2U + 4U + 1U);
  expect_echo_of_full_telemetry(e);
  EXPECT_EQ(e[6].y, static_cast<double>(sizeof(overtake_telemetry)));  // built against this
  // 2.1: the speed in m/s as well.
  EXPECT_EQ(e[14], (core::Vec2{t.ego.speed_mps, 0.0}));
}

TEST(PluginTelemetry, EmptyArraysAreNull) {
  const LoadedPlugin p = load_plugin(misbehaving("echo"));
  auto policy = p.make(track().line, planner::PlannerParams{});
  const core::Vec2 both_null{1.0, 1.0};
  core::Telemetry empty;
  EXPECT_EQ(policy->plan(empty).path.at(7), both_null);
  EXPECT_EQ(policy->plan(full_telemetry()).path.at(7), (core::Vec2{0.0, 0.0}));
  // Again empty, now that the arrays behind them have had storage.
  EXPECT_EQ(policy->plan(empty).path.at(7), both_null);
}

TEST(PluginTelemetry, APluginBuiltAgainst2_0ReadsTheFieldsItKnows) {
  const LoadedPlugin p = load_plugin(misbehaving("echo_v2_0"));
  auto policy = p.make(track().line, planner::PlannerParams{});
  const std::vector<core::Vec2> e = policy->plan(full_telemetry()).path;
  // Every field of 2.0 where 2.0 put it, and nothing after the sensor fusion: the plugin
  // knows no speed_mps. It was built with a shorter telemetry: 2.1 appended one double.
  ASSERT_EQ(e.size(), 8U + 2U + 4U);
  expect_echo_of_full_telemetry(e);
  EXPECT_EQ(e[6].y, static_cast<double>(offsetof(overtake_telemetry, speed_mps)));
}

TEST(PluginTelemetry, APluginBuiltAgainst2_0Drives) {
  const run::DriveResult r = drive_plugin(misbehaving("keep_lane_v2_0"), 2.0, 1);
  const json j = run::report_to_json(r.report, r.provenance);
  EXPECT_EQ(j["end"], "completed") << j["ended_early"];
  EXPECT_EQ(j["incident_counts"]["collision"], 0);
  EXPECT_GT(j["distance_miles"].get<double>(), 1.0);
}

// ---- plugins that fail while driving --------------------------------------------------

struct Failure {
  const char* mode;
  const char* reason;
};

class FailingPlugin : public ::testing::TestWithParam<Failure> {};

TEST_P(FailingPlugin, EndsTheRunAsPlannerFailedNamingThePlugin) {
  const Failure f = GetParam();
  const run::DriveResult r = drive_plugin(misbehaving(f.mode), 0.5, 1);
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
                      Failure{"struct_size", "wrote over the path's struct_size"},
                      Failure{"quiet", "failed (status 3): no reason given"},
                      Failure{"far", "point 0 is (1e+300, 0): beyond 1,000 km of the map's origin"},
                      Failure{"cut_reason", "failed (status 5): \xC3\xA9\xC3\xA9"},
                      Failure{"create_fails", "create failed: no config given for 3 lanes"},
                      Failure{"create_throws", "create threw an exception: cannot start"}),
    [](const ::testing::TestParamInfo<Failure>& p) { return std::string(p.param.mode); });

TEST(FailingPlugin, AReasonThatFillsCreatesBufferIsCutShort) {
  const run::DriveResult r = drive_plugin(misbehaving("create_unterminated"), 0.5, 1);
  EXPECT_EQ(r.report.outcome.end, sim::RunEnd::planner_failed);
  // The loader's buffer is 1024 bytes: 1023 characters and the NUL it puts at the end.
  const std::string reason = r.report.outcome.reason;
  EXPECT_THAT(reason, HasSubstr("create failed: " + std::string(1023, 'x')));
  EXPECT_THAT(reason, Not(HasSubstr(std::string(1024, 'x'))));
}

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
  const run::DriveResult r = drive_plugin(OVERTAKE_KEEP_LANE_PLUGIN, 3.0, seed, traffic);
  const json j = run::report_to_json(r.report, r.provenance);
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
  EXPECT_TRUE(j["plan_status"].is_null()) << j["plan_status"];  // the ABI carries points only
}

TEST_F(PluginCli, PlannerParamsReachThePluginAndTheRunsRecord) {
  const fs::path report = dir_ / "report.json";
  const auto [status, out, err] =
      run({"drive", "--policy-lib", std::string("lane=") + OVERTAKE_KEEP_LANE_PLUGIN,
           "--planner-params", R"(lane={"cruise_mps":12})", "--minutes", "1", "--seed", "1",
           "--quiet", "--json", report.string()});
  ASSERT_EQ(status, 0) << err;
  const json j = json::parse(read(report));
  EXPECT_EQ(j["config"]["planner"]["params"], json::parse(R"({"cruise_mps":12.0})"));
  // 12 m/s is 26.8 mph: the plugin's own cruise (49 mph) would be far faster.
  EXPECT_LT(j["mean_speed_mph"].get<double>(), 26.9);
  EXPECT_GT(j["mean_speed_mph"].get<double>(), 15.0);
}

TEST_F(PluginCli, BadPlannerParamsAreRefusedBeforeAnyRunNamingWhatIsWrong) {
  const std::string lib = std::string("lane=") + OVERTAKE_KEEP_LANE_PLUGIN;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {R"(other={"cruise_mps":12})", "'other' names no --policy-py or --policy-lib planner"},
      {"lane", "no '=' after the planner's name"},
      {"lane=[12]", "not a JSON object"},
      {R"(lane={"cruise_mps":"fast"})", "the value of 'cruise_mps' is not a finite number"},
      {R"(lane={"cruise_mps":1e999})", "not a JSON object"}};
  for (const auto& [given, why] : cases) {
    const fs::path report = dir_ / "report.json";
    const auto [status, out, err] = run({"drive", "--policy-lib", lib, "--planner-params", given,
                                         "--minutes", "0.5", "--json", report.string()});
    EXPECT_EQ(status, 2) << given;
    EXPECT_THAT(err, AllOf(HasSubstr("--planner-params"), HasSubstr(why))) << given;
    EXPECT_FALSE(fs::exists(report)) << given;
  }
  {
    const auto [status, out, err] =
        run({"drive", "--policy-lib", lib, "--planner-params", R"(lane={"cruise_mps":12})",
             "--planner-params", R"(lane={"cruise_mps":13})", "--minutes", "0.5"});
    EXPECT_EQ(status, 2);
    EXPECT_THAT(err, HasSubstr("the planner lane was given parameters before"));
  }
  // A planner program takes its parameters in its command.
  const auto [status, out, err] =
      run({"bench", "--planner-cmd", "sleep 1", "--planner-name", "p", "--planner-params",
           R"(p={"x":1})", "--seeds", "1", "--out", (dir_ / "bench").string()});
  EXPECT_EQ(status, 2);
  EXPECT_THAT(err, HasSubstr("a planner program takes its parameters in its command"));
  EXPECT_FALSE(fs::exists(dir_ / "bench" / "runs.jsonl"));
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
      run({"drive", "--policy-lib", misbehaving("newer_minor"), "--minutes", "1"});
  EXPECT_EQ(status, 2);
  EXPECT_THAT(err, AllOf(HasSubstr("--policy-lib"),
                         HasSubstr("ABI version " +
                                   abi(OVERTAKE_PLUGIN_ABI_MAJOR, OVERTAKE_PLUGIN_ABI_MINOR + 1))));
}

TEST(FailingPlugin, AReasonCutInTheMiddleOfACharacterIsKeptAsValidUtf8) {
  const run::DriveResult r = drive_plugin(misbehaving("cut_reason"), 0.5, 1);
  const std::string reason = r.report.outcome.reason;
  // 511 whole "é" of the 1,023 bytes snprintf kept, and its last byte as U+FFFD.
  EXPECT_THAT(reason, HasSubstr("failed (status 5): "));
  const std::size_t at = reason.find("failed (status 5): ") + 19;
  std::string want;
  for (int i = 0; i < 511; ++i) want += "\xC3\xA9";
  EXPECT_EQ(reason.substr(at), want + "\xEF\xBF\xBD");
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

// A reason cut in the middle of a character once aborted the bench ("incomplete UTF-8
// string") with runs.jsonl empty: every policy's finished runs were lost.
TEST_F(PluginCli, AReasonThatIsNotUtf8LosesNoRunOfTheBench) {
  const fs::path out_dir = dir_ / "bench";
  const auto [status, out, err] =
      run({"bench", "--policy-lib", OVERTAKE_KEEP_LANE_PLUGIN, "--policy-lib",
           "cut=" + misbehaving("cut_reason"), "--policies", "keep_lane,cut", "--seeds", "1-2",
           "--traffic", "calm", "--minutes", "0.5", "--jobs", "2", "--quiet", "--out",
           out_dir.string()});
  ASSERT_TRUE(status.has_value());
  EXPECT_LT(*status, 128) << "killed by a signal: " << err;
  std::ifstream runs(out_dir / "runs.jsonl");
  std::map<std::string, int> ends;
  for (std::string line; std::getline(runs, line);) {
    EXPECT_TRUE(core::is_valid_utf8(line));
    const json j = json::parse(line);
    ends[j["config"]["policy"].get<std::string>() + " " + j["end"].get<std::string>()] += 1;
    if (j["config"]["policy"] == "cut") {
      EXPECT_THAT(j["ended_early"].get<std::string>(), HasSubstr("\xC3\xA9\xEF\xBF\xBD"));
    }
  }
  EXPECT_EQ(ends,
            (std::map<std::string, int>{{"cut planner_failed", 2}, {"keep_lane completed", 2}}))
      << err;
  EXPECT_TRUE(fs::exists(out_dir / "summary.json")) << err;
}

}  // namespace
}  // namespace overtake::plugin
