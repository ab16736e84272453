// Both sides at once: `overtake serve` (walkthrough) driven by `overtake sim --planner` in
// lock-step gives exactly the report of an in-process `overtake drive` with the same seed,
// because every number crosses the wire as the in-process loop rounds it.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include <unistd.h>

#include "overtake/app/cli.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/replay/replay.hpp"
#include "overtake/run/drive.hpp"
#include "overtake/run/report.hpp"
#include "test_support.hpp"

namespace overtake::protocol {
namespace {

using namespace testing;  // NOLINT(google-build-using-namespace): the test helpers
using nlohmann::json;

int run_cli(std::vector<std::string> args) {
  args.insert(args.begin(), "overtake");
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  return app::run_cli(static_cast<int>(argv.size()), argv.data());
}

// The report without its time figures and its plan status (which only a planner in this
// process can tell: over the wire it is null, as over_the_wire checks).
json without_timing(json j) {
  j.erase("timing");
  j.erase("plan_status");
  return j;
}

json in_process(const run::DriveOptions& o) {
  const run::DriveResult r = run::drive(o);
  return without_timing(run::report_to_json(r.report, r.provenance));
}

json over_the_wire(const ServerFixture& server, const std::string& policy,
                   const std::vector<std::string>& extra, json* timing = nullptr) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("overtake-loopback-" + std::to_string(::getpid()) + ".json");
  std::vector<std::string> args = {"sim",  "--planner", server.url(),  "--name",
                                   policy, "--json",    path.string(), "--quiet"};
  args.insert(args.end(), extra.begin(), extra.end());
  EXPECT_EQ(run_cli(args), base::kExitOk);
  json j = json::parse(base::read_file(path));
  std::filesystem::remove(path);
  if (timing) *timing = j["timing"];
  EXPECT_TRUE(j["plan_status"].is_null()) << j["plan_status"];
  return without_timing(j);
}

TEST(ProtocolLoopback, LockStepOverTheWireEqualsInProcessDrive) {
  struct Variant {
    std::string policy;
    std::string traffic;
    std::uint64_t seed;
    int steps_per_call;
  };
  for (const Variant& v :
       {Variant{"walkthrough", "faithful", 7, 0}, Variant{"walkthrough", "calm", 7, 0},
        Variant{"walkthrough", "faithful", 11, 2}, Variant{"seed001", "faithful", 5, 0}}) {
    SCOPED_TRACE(v.policy + ", " + v.traffic + " seed " + std::to_string(v.seed) + " steps " +
                 std::to_string(v.steps_per_call));
    ServerFixture server(v.policy);
    run::DriveOptions o;
    o.policy = v.policy;
    o.minutes = 2.0;
    o.seed = v.seed;
    o.traffic = v.traffic;
    o.steps_per_call = v.steps_per_call;
    const json expected = in_process(o);
    std::vector<std::string> extra = {"--minutes", "2",      "--seed", std::to_string(v.seed),
                                      "--traffic", v.traffic};
    if (v.steps_per_call > 0) {
      extra.push_back("--steps-per-call");
      extra.push_back(std::to_string(v.steps_per_call));
    }
    json timing;
    const json got = over_the_wire(server, v.policy, extra, &timing);
    EXPECT_EQ(got.dump(), expected.dump());
    // A remote planner's time is the round trip over the wire (overtake's own thread time
    // would not measure the planner at all).
    EXPECT_EQ(timing["clock"], "round_trip");
    EXPECT_GT(timing["p50_us"].get<double>(), 0.0);
    EXPECT_EQ(timing["p99_us"], timing["wall_p99_us"]);
    EXPECT_GT(got["planner_cycles"].get<long>(), 1000);
    EXPECT_TRUE(got["ended_early"].is_null());
    EXPECT_EQ(server.log().warnings(), 0u) << server.log().dump();
  }
}

// `sim` is the drive's wiring with a remote planner: a scripted scenario runs over the wire
// as it does in process.
TEST(ProtocolLoopback, AScenarioOverTheWireEqualsInProcessDrive) {
  const std::string scenario =
      std::string(OVERTAKE_SOURCE_DIR) + "/tests/scenarios/cut_in_20m.json";
  ServerFixture server("walkthrough");
  run::DriveOptions o;
  o.policy = "walkthrough";
  o.scenario = scenario;
  o.minutes_from_scenario = true;
  const json expected = in_process(o);
  const json got = over_the_wire(server, "walkthrough", {"--scenario", scenario});
  EXPECT_EQ(got["config"]["traffic"], "scripted");
  EXPECT_EQ(got["config"]["scenario"], "cut-in 20 m ahead");
  EXPECT_GT(got["planner_cycles"].get<long>(), 100);
  EXPECT_EQ(got.dump(), expected.dump());
}

TEST(ProtocolLoopback, RealTimeAgainstOurServer) {
  ServerFixture server;
  json timing;
  const json got =
      over_the_wire(server, "walkthrough", {"--minutes", "0.02", "--realtime"}, &timing);
  EXPECT_EQ(timing["clock"], "round_trip");
  EXPECT_TRUE(got["ended_early"].is_null());
  EXPECT_DOUBLE_EQ(got["duration_s"].get<double>(), 1.2);
  EXPECT_GT(got["planner_cycles"].get<long>(), 20);
  EXPECT_GT(got["distance_miles"].get<double>(), 0.0);
  EXPECT_EQ(server.log().warnings(), 0u) << server.log().dump();
}

TEST(ProtocolLoopback, SimRecordsTheSameRunAsDrive) {
  ServerFixture server("walkthrough");
  const auto dir = std::filesystem::temp_directory_path() /
                   ("overtake-loopback-record-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  run::DriveOptions o;
  o.policy = "walkthrough";
  o.minutes = 0.5;
  o.seed = 7;
  o.record = dir / "drive.otr";
  (void)run::drive(o);
  EXPECT_EQ(run_cli({"sim", "--planner", server.url(), "--name", "walkthrough", "--minutes", "0.5",
                     "--seed", "7", "--record", (dir / "sim.otr").string(), "--quiet"}),
            base::kExitOk);
  const replay::Replay a = replay::read_replay(dir / "drive.otr");
  const replay::Replay b = replay::read_replay(dir / "sim.otr");
  // The same world states step by step, the same incidents, the same report.
  ASSERT_EQ(a.frames.size(), b.frames.size());
  for (std::size_t i = 0; i < a.frames.size(); ++i) {
    ASSERT_EQ(a.frames[i].position, b.frames[i].position) << "frame " << i;
    ASSERT_EQ(a.frames[i].cars.size(), b.frames[i].cars.size());
    for (std::size_t c = 0; c < a.frames[i].cars.size(); ++c) {
      ASSERT_EQ(a.frames[i].cars[c].position, b.frames[i].cars[c].position);
    }
  }
  EXPECT_EQ(a.paths.size(), b.paths.size());
  EXPECT_EQ(a.incidents.size(), b.incidents.size());
  EXPECT_EQ(without_timing(json::parse(a.end_json)), without_timing(json::parse(b.end_json)));
  EXPECT_EQ(b.header.provenance.policy, "walkthrough");

  // Real time: every step, and the paths as they arrived.
  EXPECT_EQ(run_cli({"sim", "--planner", server.url(), "--minutes", "0.02", "--realtime",
                     "--record", (dir / "rt.otr").string(), "--quiet"}),
            base::kExitOk);
  const replay::Replay rt = replay::read_replay(dir / "rt.otr");
  EXPECT_EQ(rt.frames.size(), 61u);
  EXPECT_GT(rt.paths.size(), 20u);
  EXPECT_DOUBLE_EQ(json::parse(rt.end_json)["duration_s"].get<double>(), 1.2);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace overtake::protocol
