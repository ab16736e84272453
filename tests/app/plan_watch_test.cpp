// The watchdog of planners that share overtake's process (plugins, Python planners): a
// plan() call past its reply timeout is interrupted and fails its run with a message that
// says so; Ctrl-C interrupts one at once; a planner that cannot be interrupted, or does not
// give up, ends the process (tested in a child process) within a bounded time.

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/base/errors.hpp"
#include "overtake/base/io.hpp"
#include "overtake/planners/plan_watch.hpp"
#include "process_support.hpp"

namespace overtake {
namespace {

using namespace std::chrono_literals;

// A planner that plans for `busy` each cycle; with `interruptible`, a call gives up (throws)
// when interrupted, as an interrupted Python planner does.
class SlowPolicy final : public planner::Policy {
 public:
  SlowPolicy(std::chrono::milliseconds busy, bool interruptible)
      : busy_(busy), interruptible_(interruptible) {}
  core::PlanResult plan(const core::Telemetry& /*telemetry*/) override {
    asked_ = false;
    const auto until = std::chrono::steady_clock::now() + busy_;
    while (std::chrono::steady_clock::now() < until) {
      if (asked_.load())
        throw std::runtime_error(why_ == 0 ? "gave up (timeout)" : "gave up (stop)");
      std::this_thread::sleep_for(1ms);
    }
    return core::normal_plan({{1.0, 2.0}});
  }
  bool interrupt(core::PlanInterruption why) noexcept override {
    ++interrupts;
    if (!interruptible_) return false;
    why_ = why == core::PlanInterruption::timeout ? 0 : 1;
    asked_ = true;
    return true;
  }
  std::atomic<int> interrupts{0};

 private:
  std::chrono::milliseconds busy_;
  bool interruptible_;
  std::atomic<bool> asked_{false};
  std::atomic<int> why_{0};
};

TEST(PlanWatch, CallsWithinTheTimeoutAreLeftAlone) {
  SlowPolicy policy(30ms, true);
  planners::PlanWatch watch(policy, "the planner p", 0.5, nullptr);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(watch.plan({}).path.size(), 1u);
  EXPECT_EQ(policy.interrupts.load(), 0);
}

TEST(PlanWatch, ACallPastItsTimeoutIsInterruptedAndSaysSo) {
  SlowPolicy policy(60s, true);
  planners::PlanWatch watch(policy, "the Python planner slow (slow.py:plan)", 0.2, nullptr);
  const auto t0 = std::chrono::steady_clock::now();
  try {
    (void)watch.plan({});
    ADD_FAILURE() << "the call was not interrupted";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_EQ(what, "gave up (timeout); its reply timeout is 0.20 s (--planner-reply-timeout)");
  }
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 1s);
  EXPECT_EQ(policy.interrupts.load(), 1);
}

TEST(PlanWatch, AStopInterruptsTheRunningCallAtOnce) {
  SlowPolicy policy(60s, true);
  std::atomic<bool> stop{false};
  planners::PlanWatch watch(policy, "the planner p", 3600.0, &stop);
  std::thread stopper([&] {
    std::this_thread::sleep_for(100ms);
    stop = true;
  });
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_THROW((void)watch.plan({}), std::runtime_error);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 500ms);
  stopper.join();
}

// In a child process: a planner that cannot be interrupted (or ignores it) ends the process
// with status 3 (past the timeout) or 130 (after a stop), within the grace; the message names
// the planner.
int status_of_child(bool stop_it, std::string* message) {
  int err[2];
  if (::pipe(err) != 0) return -1;
  const pid_t child = ::fork();
  if (child == 0) {
    ::dup2(err[1], 2);
    SlowPolicy policy(60s, false);
    std::atomic<bool> stop{false};
    planners::PlanWatch watch(policy, "the plugin stuck (./libstuck.so)", stop_it ? 3600.0 : 0.2,
                              &stop);
    std::thread stopper([&] {
      std::this_thread::sleep_for(100ms);
      if (stop_it) stop = true;
    });
    stopper.detach();
    (void)watch.plan({});
    _exit(0);
  }
  ::close(err[1]);
  int status = 0;
  ::waitpid(child, &status, 0);
  char buf[4096];
  const ssize_t n = ::read(err[0], buf, sizeof buf);
  ::close(err[0]);
  if (message && n > 0) message->assign(buf, static_cast<std::size_t>(n));
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(PlanWatch, APlannerThatCannotBeInterruptedEndsTheProcess) {
  std::string message;
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(status_of_child(false, &message), base::kExitPlannerStuck);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 2s);
  EXPECT_NE(message.find("the plugin stuck (./libstuck.so) has not returned from plan() in 0.20 s"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("--resume"), std::string::npos) << message;

  const auto t1 = std::chrono::steady_clock::now();
  EXPECT_EQ(status_of_child(true, &message), 130);
  EXPECT_LT(std::chrono::steady_clock::now() - t1, 1500ms);  // the stop, then at most 0.5 s
  EXPECT_NE(message.find("stopped while the plugin stuck"), std::string::npos) << message;
}

// ---- through the binary, with a plugin whose plan() never returns ---------------------------

namespace fs = std::filesystem;

class PlanWatchCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    root_ = fs::temp_directory_path() /
            (std::string("overtake-watch-") + info->name() + "-" + std::to_string(::getpid()));
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  fs::path root_;
};

// A bench whose plugin never returns ends (status 3) naming the plugin, within the reply
// timeout and its grace; every run that finished before is in runs.jsonl, whole.
TEST_F(PlanWatchCli, APluginThatNeverReturnsEndsTheBenchKeepingFinishedRuns) {
  const fs::path out = root_ / "bench";
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = test::start_overtake(
      {"bench", "--policies", "walkthrough", "--policy-lib", OVERTAKE_NEVER_RETURNS_PLUGIN,
       "--seeds", "1-2", "--minutes", "0.2", "--jobs", "1", "--planner-reply-timeout", "0.5",
       "--out", out.string(), "--quiet"},
      root_ / "stdout", root_ / "stderr");
  EXPECT_EQ(test::exit_status(pid, std::chrono::seconds(60)), base::kExitPlannerStuck);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 30s);
  const std::string err = base::read_file(root_ / "stderr");
  EXPECT_NE(err.find("the plugin never_returns ("), std::string::npos) << err;
  EXPECT_NE(err.find("has not returned from plan() in 0.50 s"), std::string::npos) << err;
  std::ifstream rows(out / "runs.jsonl");
  std::string line;
  int finished = 0;
  while (std::getline(rows, line)) {
    const auto row = nlohmann::json::parse(line);  // whole rows only
    EXPECT_EQ(row["config"]["policy"], "walkthrough");
    EXPECT_EQ(row["end"], "completed");
    ++finished;
  }
  EXPECT_GE(finished, 1);
}

// Ctrl-C stops a drive whose plugin never returns within a second (status 130).
TEST_F(PlanWatchCli, CtrlCEndsADriveWhosePluginNeverReturnsWithinASecond) {
  const pid_t pid = test::start_overtake({"drive", "--policy-lib", OVERTAKE_NEVER_RETURNS_PLUGIN,
                                          "--minutes", "1", "--planner-reply-timeout", "600"},
                                         root_ / "stdout", root_ / "stderr");
  std::this_thread::sleep_for(1s);
  const auto t0 = std::chrono::steady_clock::now();
  ::kill(pid, SIGINT);
  EXPECT_EQ(test::exit_status(pid, std::chrono::seconds(10)), 130)
      << base::read_file(root_ / "stderr");
  EXPECT_LT(std::chrono::steady_clock::now() - t0,
            1500ms);  // within a second by design (a 0.5 s grace), with room for a loaded machine
  EXPECT_NE(base::read_file(root_ / "stderr").find("stopped while the plugin never_returns"),
            std::string::npos)
      << base::read_file(root_ / "stderr");
}

// `serve` with a plugin that never returns: the one thread that serves is stuck in it, yet
// Ctrl-C ends the server within a second; with a well-behaved planner Ctrl-C stops it cleanly.
TEST_F(PlanWatchCli, CtrlCEndsServeEvenWhenItsPluginNeverReturns) {
  const auto listening_port = [this]() -> std::string {
    for (int i = 0; i < 500; ++i) {
      const std::string err = base::read_file(root_ / "serve.err");
      const std::size_t at = err.find("listening on ws://127.0.0.1:");
      if (at != std::string::npos) {
        const std::size_t from = at + std::string("listening on ws://127.0.0.1:").size();
        return err.substr(from, err.find_first_not_of("0123456789", from) - from);
      }
      std::this_thread::sleep_for(10ms);
    }
    return {};
  };
  for (const bool stuck : {false, true}) {
    SCOPED_TRACE(stuck ? "a plugin that never returns" : "keep_lane");
    const pid_t server = test::start_overtake(
        {"serve", "--policy-lib", stuck ? OVERTAKE_NEVER_RETURNS_PLUGIN : OVERTAKE_KEEP_LANE_PLUGIN,
         "--port", "0", "--planner-reply-timeout", "600"},
        root_ / "serve.out", root_ / "serve.err");
    const std::string port = listening_port();
    ASSERT_FALSE(port.empty()) << base::read_file(root_ / "serve.err");
    const pid_t client =
        test::start_overtake({"sim", "--planner", "ws://127.0.0.1:" + port, "--minutes", "1",
                              "--reply-timeout", "600", "--quiet"},
                             root_ / "sim.out", root_ / "sim.err");
    std::this_thread::sleep_for(1s);
    const auto t0 = std::chrono::steady_clock::now();
    ::kill(server, SIGINT);
    const auto status = test::exit_status(server, std::chrono::seconds(10));
    EXPECT_LT(std::chrono::steady_clock::now() - t0, 1500ms);
    EXPECT_EQ(status, stuck ? 130 : 0) << base::read_file(root_ / "serve.err");
    if (stuck) {
      EXPECT_NE(base::read_file(root_ / "serve.err").find("stopped while the plugin never_returns"),
                std::string::npos)
          << base::read_file(root_ / "serve.err");
    }
    (void)test::exit_status(client, std::chrono::seconds(20));
  }
}

}  // namespace
}  // namespace overtake
