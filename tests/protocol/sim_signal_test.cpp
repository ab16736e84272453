// `overtake sim --planner` stopped by Ctrl-C (SIGINT) or SIGTERM: the real binary, started
// from here against planners in this process. The run stops at the next step and still
// prints its scorecard, writes --json and finishes --record, with ended_early "stopped" and
// exit status 130, also while it waits for a planner that has stalled.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <optional>

#include <unistd.h>

#include "overtake/app/interrupt.hpp"
#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/replay/replay.hpp"
#include "overtake/run/config.hpp"
#include "process_support.hpp"
#include "test_support.hpp"

namespace overtake::protocol {
namespace {

using ::testing::HasSubstr;
using namespace testing;  // NOLINT(google-build-using-namespace): the test helpers
namespace fs = std::filesystem;

const fs::path kBinary = test::overtake_binary();

class SimSignal : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(kBinary)) << kBinary << " is not built";
    dir_ = fs::temp_directory_path() /
           ("overtake_sim_signal_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // Runs `sim` against `url`, sends `sig` once `running` says the run is under way, and
  // checks that everything was written and the exit status is 130.
  void stop_with(int sig, const std::string& url, const std::function<bool()>& running,
                 const std::vector<std::string>& extra = {}) {
    const fs::path json = dir_ / "run.json";
    const fs::path otr = dir_ / "run.otr";
    std::vector<std::string> args = {"sim",    "--planner",   url,        "--minutes", "600",
                                     "--json", json.string(), "--record", otr.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const pid_t pid = test::start_overtake(args, dir_ / "out.txt", dir_ / "err.txt");
    const auto until = std::chrono::steady_clock::now() + 20s;
    while (!running() && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(10ms);
    ASSERT_TRUE(running()) << "the run did not start: " << base::read_file(dir_ / "err.txt");
    std::this_thread::sleep_for(200ms);
    const auto sent = std::chrono::steady_clock::now();
    ASSERT_EQ(::kill(pid, sig), 0);
    const auto status = test::exit_status(pid, 15s);
    ASSERT_TRUE(status) << "still running 15 s after the signal";
    EXPECT_LT(std::chrono::steady_clock::now() - sent, 3s) << "stops at the next step";
    EXPECT_EQ(*status, base::kExitInterrupted) << base::read_file(dir_ / "err.txt");

    const std::string out = base::read_file(dir_ / "out.txt");
    EXPECT_THAT(out, HasSubstr("overtake sim: planner "));
    EXPECT_THAT(out, HasSubstr("ENDED EARLY: stopped"));
    ASSERT_TRUE(fs::exists(json)) << out;
    const auto j = nlohmann::json::parse(base::read_file(json));
    EXPECT_EQ(j["ended_early"], "stopped");
    EXPECT_GT(j["duration_s"].get<double>(), 0.0);
    EXPECT_LT(j["duration_s"].get<double>(), 600.0 * 60.0);
    EXPECT_GT(j["planner_cycles"].get<long>(), 0);
    // The replay is finished (not left as a .partial), its end record the same report.
    EXPECT_FALSE(fs::exists(otr.string() + ".partial"));
    const replay::Replay replay = replay::read_replay(otr);
    EXPECT_FALSE(replay.frames.empty());
    const auto end = nlohmann::json::parse(replay.end_json);
    EXPECT_EQ(end["ended_early"], "stopped");
    EXPECT_EQ(end["duration_s"], j["duration_s"]);
  }

  fs::path dir_;
};

TEST_F(SimSignal, CtrlCAndSigtermStopTheRunAndKeepEverything) {
  for (const int sig : {SIGINT, SIGTERM}) {
    SCOPED_TRACE(sig == SIGINT ? "SIGINT" : "SIGTERM");
    ServerFixture server;
    stop_with(sig, server.url(), [&server] {
      for (const auto& line : server.log().lines()) {
        if (line.ends_with(" open")) return true;
      }
      return false;
    });
  }
}

TEST_F(SimSignal, CtrlCStopsTheWaitForAStalledPlanner) {
  std::atomic<int> got{0};
  FakePlanner planner([&got](std::string_view message, int index) {
    ++got;
    if (index >= 50) return FakeAction{};  // stalls: never answers again
    const auto t = parse_telemetry(message);
    const auto track = default_track();
    static const auto policy =
        planner::make_policy("walkthrough", track->line, run::default_config().planner);
    return FakeAction{{t.ok() && t.value() ? format_control(policy->plan(*t.value()).path)
                                           : std::string(kManual)}};
  });
  stop_with(SIGINT, planner.url(), [&got] { return got.load() > 50; }, {"--reply-timeout", "600"});
}

}  // namespace
}  // namespace overtake::protocol
