#pragma once
// A watchdog for planners that run in overtake's own process (C++ plugins, Python planners):
// each plan() call is timed from another thread. A call that takes longer than the planner's
// reply timeout, or that is still running when the user stops the run (Ctrl-C, SIGTERM), is
// asked to give up (planner::Policy::interrupt: a Python planner raises in its thread). Code
// that cannot be interrupted, or does not give up within a grace, cannot be stopped from
// outside while it shares the process: overtake then ends the process, saying why. What is
// already written stays (a bench writes each finished run as it ends).

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "overtake/core/plan.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/planner/policy.hpp"

namespace overtake::planners {

/// How long an interrupted plan() call has to give up before overtake ends (timeout).
inline constexpr std::chrono::milliseconds kInterruptGrace{1000};
/// How long a plan() call may go on after the user stopped the run before overtake ends.
inline constexpr std::chrono::milliseconds kStopGrace{500};

/// Watches the plan() calls of one run's policy. Not copyable; the watcher thread ends with
/// it.
class PlanWatch {
 public:
  /// `label` names the planner in messages ("plugin keep_lane (./libkeep_lane.so)");
  /// `stop` is the run's stop flag (may be null).
  PlanWatch(planner::Policy& policy, std::string label, double timeout_s,
            const std::atomic<bool>* stop);
  ~PlanWatch();
  PlanWatch(const PlanWatch&) = delete;
  PlanWatch& operator=(const PlanWatch&) = delete;

  /// policy.plan(telemetry), watched. A call interrupted for its time throws
  /// std::runtime_error: what the planner said as it gave up, and the timeout.
  [[nodiscard]] core::PlanResult plan(const core::Telemetry& telemetry);

 private:
  void watch();
  [[noreturn]] void end_process(int status, const std::string& why) const;

  planner::Policy& policy_;
  std::string label_;
  std::chrono::nanoseconds timeout_;
  const std::atomic<bool>* stop_;
  std::atomic<std::int64_t> started_ns_{0};       ///< when the running call started; 0: none runs
  std::atomic<std::uint64_t> call_{0};            ///< the number of the latest call
  std::atomic<std::uint64_t> timed_out_call_{0};  ///< the call interrupted for its time
  std::mutex mutex_;
  std::condition_variable wake_;
  bool quit_ = false;
  std::thread thread_;
};

/// `policy`, each plan() call watched by a PlanWatch (its other calls passed through).
[[nodiscard]] std::unique_ptr<planner::Policy> watch_policy(std::unique_ptr<planner::Policy> policy,
                                                            std::string label, double timeout_s,
                                                            const std::atomic<bool>* stop);

}  // namespace overtake::planners
