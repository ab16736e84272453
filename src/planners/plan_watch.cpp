#include "overtake/planners/plan_watch.hpp"

#include <unistd.h>

#include <cstdio>
#include <stdexcept>

#include "overtake/base/errors.hpp"
#include "overtake/base/text.hpp"

namespace overtake::planners {

using base::fixed_text;
using base::kExitPlannerStuck;
namespace {

using Clock = std::chrono::steady_clock;

std::int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

// How often the watcher looks: a tenth of the shortest grace.
constexpr auto kTick = std::chrono::milliseconds(20);

}  // namespace

PlanWatch::PlanWatch(planner::Policy& policy, std::string label, double timeout_s,
                     const std::atomic<bool>* stop)
    : policy_(policy),
      label_(std::move(label)),
      timeout_(std::chrono::nanoseconds(static_cast<std::int64_t>(timeout_s * 1e9))),
      stop_(stop),
      thread_([this] { watch(); }) {}

PlanWatch::~PlanWatch() {
  {
    const std::lock_guard lock(mutex_);
    quit_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

core::PlanResult PlanWatch::plan(const core::Telemetry& telemetry) {
  const std::uint64_t call = call_.fetch_add(1, std::memory_order_relaxed) + 1;
  started_ns_.store(now_ns(), std::memory_order_release);
  try {
    core::PlanResult result = policy_.plan(telemetry);
    started_ns_.store(0, std::memory_order_release);
    return result;
  } catch (const std::exception& e) {
    started_ns_.store(0, std::memory_order_release);
    if (timed_out_call_.load(std::memory_order_acquire) == call) {
      // The planner's own message says who it is and where it was interrupted.
      throw std::runtime_error(std::string(e.what()) + "; its reply timeout is " +
                               fixed_text(static_cast<double>(timeout_.count()) / 1e9, 2) +
                               " s (--planner-reply-timeout)");
    }
    throw;
  }
}

void PlanWatch::watch() {
  std::uint64_t seen_call = 0;  // the call the flags below are about
  bool asked_timeout = false, asked_stop = false;
  std::int64_t asked_at = 0;
  std::unique_lock lock(mutex_);
  while (!wake_.wait_for(lock, kTick, [this] { return quit_; })) {
    const std::int64_t started = started_ns_.load(std::memory_order_acquire);
    if (started == 0) continue;
    const std::uint64_t call = call_.load(std::memory_order_relaxed);
    if (call != seen_call) {
      seen_call = call;
      asked_timeout = asked_stop = false;
    }
    const std::int64_t now = now_ns();
    const bool stopping = stop_ != nullptr && stop_->load(std::memory_order_relaxed);
    if (stopping) {
      if (!asked_stop) {
        asked_stop = true;
        asked_at = now;
        (void)policy_.interrupt(core::PlanInterruption::user_stop);
      } else if (now - asked_at > std::chrono::nanoseconds(kStopGrace).count()) {
        end_process(130, "stopped while " + label_ +
                             " was planning, and it did not return within " +
                             fixed_text(kStopGrace.count() / 1000.0, 1) + " s");
      }
      continue;
    }
    if (now - started <= timeout_.count()) continue;
    if (!asked_timeout) {
      asked_timeout = true;
      asked_at = now;
      timed_out_call_.store(call, std::memory_order_release);
      if (!policy_.interrupt(core::PlanInterruption::timeout)) {
        end_process(kExitPlannerStuck,
                    label_ + " has not returned from plan() in " +
                        fixed_text(static_cast<double>(timeout_.count()) / 1e9, 2) +
                        " s (--planner-reply-timeout), and code inside overtake's own process "
                        "cannot be stopped from outside");
      }
    } else if (now - asked_at > std::chrono::nanoseconds(kInterruptGrace).count()) {
      end_process(kExitPlannerStuck,
                  label_ + " has not returned from plan() in " +
                      fixed_text(static_cast<double>(timeout_.count()) / 1e9, 2) +
                      " s (--planner-reply-timeout), and did not give up when interrupted (it "
                      "is blocked outside Python code: a sleep, a lock, a C extension)");
    }
  }
}

namespace {

class WatchedPolicy final : public planner::Policy {
 public:
  WatchedPolicy(std::unique_ptr<planner::Policy> inner, std::string label, double timeout_s,
                const std::atomic<bool>* stop)
      : inner_(std::move(inner)), watch_(*inner_, std::move(label), timeout_s, stop) {}
  core::PlanResult plan(const core::Telemetry& telemetry) override {
    return watch_.plan(telemetry);
  }
  bool archive_state(core::StateArchive& ar) override { return inner_->archive_state(ar); }
  bool interrupt(core::PlanInterruption why) noexcept override { return inner_->interrupt(why); }

 private:
  std::unique_ptr<planner::Policy> inner_;  // before watch_, which refers to it
  PlanWatch watch_;
};

}  // namespace

std::unique_ptr<planner::Policy> watch_policy(std::unique_ptr<planner::Policy> policy,
                                              std::string label, double timeout_s,
                                              const std::atomic<bool>* stop) {
  return std::make_unique<WatchedPolicy>(std::move(policy), std::move(label), timeout_s, stop);
}

void PlanWatch::end_process(int status, const std::string& why) const {
  const std::string text =
      "overtake: " + why +
      ". overtake ends here; every run finished before is kept (a bench's runs.jsonl: go on "
      "with `overtake bench --resume`).\n";
  (void)!::write(2, text.data(), text.size());
  // Not exit(): the planner's thread is still inside its code, and destructors of what it
  // uses must not run under it.
  ::_exit(status);
}

}  // namespace overtake::planners
