// `overtake sim --planner` stopped by Ctrl-C (SIGINT) or SIGTERM: the real binary, started
// from here against planners in this process. The run stops at the next step and still
// prints its scorecard, writes --json and finishes --record, with ended_early "stopped" and
// exit status 130, also while it waits for a planner that has stalled.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <optional>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "overtake/app/interrupt.hpp"
#include "overtake/app/io.hpp"
#include "overtake/sim/replay.hpp"
#include "test_support.hpp"

extern char** environ;  // NOLINT: POSIX, for posix_spawn

namespace overtake::protocol {
namespace {

using ::testing::HasSubstr;
using namespace testing;  // NOLINT: the test helpers
namespace fs = std::filesystem;

const fs::path kBinary = fs::path(OVERTAKE_BINARY_DIR) / "overtake";

// The binary with these arguments, its stdout and stderr into files.
pid_t start(const std::vector<std::string>& args, const fs::path& out, const fs::path& err) {
  std::vector<std::string> all = {kBinary.string()};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t files;
  posix_spawn_file_actions_init(&files);
  posix_spawn_file_actions_addopen(&files, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&files, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, argv[0], &files, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&files);
  if (rc != 0) throw std::runtime_error("cannot start " + kBinary.string());
  return pid;
}

// The child's exit status, or nullopt if it is still running after `timeout` (then killed).
std::optional<int> exit_status(pid_t pid, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) {
      if (WIFEXITED(status)) return WEXITSTATUS(status);
      return 1000 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);  // killed by a signal
    }
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      return std::nullopt;
    }
    std::this_thread::sleep_for(10ms);
  }
}

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
    const pid_t pid = start(args, dir_ / "out.txt", dir_ / "err.txt");
    const auto until = std::chrono::steady_clock::now() + 20s;
    while (!running() && std::chrono::steady_clock::now() < until)
      std::this_thread::sleep_for(10ms);
    ASSERT_TRUE(running()) << "the run did not start: " << app::read_file(dir_ / "err.txt");
    std::this_thread::sleep_for(200ms);
    const auto sent = std::chrono::steady_clock::now();
    ASSERT_EQ(::kill(pid, sig), 0);
    const auto status = exit_status(pid, 15s);
    ASSERT_TRUE(status) << "still running 15 s after the signal";
    EXPECT_LT(std::chrono::steady_clock::now() - sent, 3s) << "stops at the next step";
    EXPECT_EQ(*status, app::kExitInterrupted) << app::read_file(dir_ / "err.txt");

    const std::string out = app::read_file(dir_ / "out.txt");
    EXPECT_THAT(out, HasSubstr("overtake sim: planner "));
    EXPECT_THAT(out, HasSubstr("ENDED EARLY: stopped"));
    ASSERT_TRUE(fs::exists(json)) << out;
    const auto j = nlohmann::json::parse(app::read_file(json));
    EXPECT_EQ(j["ended_early"], "stopped");
    EXPECT_GT(j["duration_s"].get<double>(), 0.0);
    EXPECT_LT(j["duration_s"].get<double>(), 600.0 * 60.0);
    EXPECT_GT(j["planner_cycles"].get<long>(), 0);
    // The replay is finished (not left as a .partial), its end record the same report.
    EXPECT_FALSE(fs::exists(otr.string() + ".partial"));
    const sim::Replay replay = sim::read_replay(otr);
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
        planner::make_policy("walkthrough", track->line, app::default_config().planner);
    return FakeAction{
        {t.ok() && t.value() ? format_control(policy->plan(*t.value())) : std::string(kManual)}};
  });
  stop_with(SIGINT, planner.url(), [&got] { return got.load() > 50; }, {"--reply-timeout", "600"});
}

}  // namespace
}  // namespace overtake::protocol
