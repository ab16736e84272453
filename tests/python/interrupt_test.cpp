// A Python planner's call interrupted from another thread (planner::Policy::interrupt), as the
// watchdog of a drive does when a planner takes too long or the user stops the run: the call
// raises, the message says why, and nothing of it is left for later calls.

#include <gtest/gtest.h>
#include <pybind11/pybind11.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <memory>
#include <string>
#include <thread>

#include "overtake/core/reference_line.hpp"
#include "overtake/python/bridge.hpp"
#include "overtake/python/python_policy.hpp"
#include "sim/test_maps.hpp"

namespace overtake::python {
namespace {

namespace py = pybind11;
using namespace std::chrono_literals;

const std::string kPlanners =
    std::string(OVERTAKE_SOURCE_DIR) + "/tests/python/planners/interruptible.py";

// How a plan() ended: it answered, or threw with this message.
struct Outcome {
  bool answered = false;
  std::string error;
};

// Runs policy.plan() on a thread of its own.
std::future<Outcome> plan_on_a_thread(planner::Policy& policy) {
  std::packaged_task<Outcome()> task([&policy] {
    Outcome o;
    try {
      (void)policy.plan(core::Telemetry{});
      o.answered = true;
    } catch (const std::exception& e) {
      o.error = e.what();
    }
    return o;
  });
  std::future<Outcome> outcome = task.get_future();
  std::thread(std::move(task)).detach();
  return outcome;
}

// Interrupts the call until it returns (the first interruptions may come before the call has
// started, and do nothing), at most 20 s: a call that never returns ends the test program,
// which could not end otherwise.
Outcome interrupt_until_it_returns(planner::Policy& policy, std::future<Outcome>& running,
                                   core::PlanInterruption why) {
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  while (running.wait_for(50ms) != std::future_status::ready) {
    if (std::chrono::steady_clock::now() > deadline) {
      ADD_FAILURE() << "the interrupted call did not return within 20 s";
      (void)std::fflush(stdout);
      std::_Exit(1);
    }
    EXPECT_TRUE(policy.interrupt(why));
  }
  return running.get();
}

class PythonInterrupt : public ::testing::Test {
 protected:
  PythonInterrupt() : map_(test::circle_map()), line_(map_) {}

  std::unique_ptr<planner::Policy> make(const std::string& function) {
    return load_python_policy(kPlanners + ":" + function).make(line_, params_);
  }

  core::Map map_;
  core::ReferenceLine line_;
  planner::PlannerParams params_;
};

TEST_F(PythonInterrupt, ATimeoutRaisesTimeoutErrorInAnEndlessLoop) {
  const auto policy = make("spin");
  auto running = plan_on_a_thread(*policy);
  const Outcome o = interrupt_until_it_returns(*policy, running, core::PlanInterruption::timeout);
  EXPECT_FALSE(o.answered);
  EXPECT_NE(o.error.find("interruptible.py:spin did not answer in time and was interrupted "
                         "(TimeoutError at interruptible.py, line "),
            std::string::npos)
      << o.error;
  EXPECT_NE(o.error.find(", in spin)"), std::string::npos) << o.error;
}

TEST_F(PythonInterrupt, TheUsersStopRaisesKeyboardInterrupt) {
  const auto policy = make("spin");
  auto running = plan_on_a_thread(*policy);
  const Outcome o = interrupt_until_it_returns(*policy, running, core::PlanInterruption::user_stop);
  EXPECT_FALSE(o.answered);
  EXPECT_NE(o.error.find("interruptible.py:spin was stopped by the user (KeyboardInterrupt at "
                         "interruptible.py, line "),
            std::string::npos)
      << o.error;
}

TEST_F(PythonInterrupt, BetweenCallsAnInterruptionDoesNothing) {
  const auto policy = make("counts");
  EXPECT_TRUE(policy->interrupt(core::PlanInterruption::timeout));
  EXPECT_TRUE(policy->interrupt(core::PlanInterruption::user_stop));
  std::this_thread::sleep_for(100ms);
  EXPECT_EQ(policy->plan(core::Telemetry{}).path.size(), 3U);
  EXPECT_EQ(policy->plan(core::Telemetry{}).path.size(), 3U);
}

TEST_F(PythonInterrupt, OnlyTheInterruptedPolicysCallStops) {
  const auto endless = make("spin");
  const auto busy = make("for_a_second");  // runs Python on its thread meanwhile
  auto busy_running = plan_on_a_thread(*busy);
  auto endless_running = plan_on_a_thread(*endless);
  const Outcome stopped =
      interrupt_until_it_returns(*endless, endless_running, core::PlanInterruption::timeout);
  EXPECT_NE(stopped.error.find("TimeoutError"), std::string::npos) << stopped.error;
  ASSERT_EQ(busy_running.wait_for(20s), std::future_status::ready);
  const Outcome answered = busy_running.get();
  EXPECT_TRUE(answered.answered) << answered.error;
}

TEST_F(PythonInterrupt, AnExceptionSetAsTheCallReturnsIsNotRaisedInALaterCall) {
  const auto later = make("counts");  // also starts the interpreter
  std::unique_ptr<planner::Policy> policy;
  SharedObject planner;
  {
    py::gil_scoped_acquire gil;
    // A planner in C++: it has itself interrupted, waits for the exception to be set, and
    // answers without running a bytecode, so the exception is still pending as it returns.
    planner = share(py::cpp_function([&policy](const py::object& /*telemetry*/) {
      {
        py::gil_scoped_release nogil;
        EXPECT_TRUE(policy->interrupt(core::PlanInterruption::timeout));
        std::this_thread::sleep_for(300ms);  // the delivery takes the GIL meanwhile
      }
      return py::make_tuple(py::make_tuple(1.0, 2.0), py::make_tuple(0.0, 0.0));
    }));
  }
  policy = callable_policy_factory(planner, "self-interrupting")(line_, params_);
  EXPECT_EQ(policy->plan(core::Telemetry{}).path.size(), 2U);  // it answered: the answer counts
  // The next bytecode this thread runs is another planner's: it must not get that exception.
  EXPECT_EQ(later->plan(core::Telemetry{}).path.size(), 3U);
  EXPECT_EQ(later->plan(core::Telemetry{}).path.size(), 3U);
}

}  // namespace
}  // namespace overtake::python
