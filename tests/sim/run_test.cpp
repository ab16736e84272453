// The run loop and the scorecard stage: plan statuses counted per cycle, how a run ends (as a
// value, with its reason), the frames watchers see, and the pacing clock.

#include "overtake/sim/run.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>

#include "overtake/core/state_archive.hpp"
#include "overtake/sim/scorecard.hpp"
#include "sim/test_maps.hpp"

namespace overtake::sim {
namespace {

using ::testing::HasSubstr;

constexpr double kCruiseMps = 15.0;
constexpr double kLaneD = 6.0;

class RunTest : public ::testing::Test {
 protected:
  RunTest() : map_(test::circle_map()), line_(map_) {}

  World make_world(std::uint64_t seed = 1) {
    return World(map_, line_, params_, TrafficProfile::faithful, seed);
  }

  // Cruises lane 1; every 5th cycle says it fell back, every 7th (not 5th) that it took the
  // least bad of its candidates.
  PlannerFn cruise_with_statuses(int& cycle) const {
    return [this, &cycle](const core::Telemetry& t) {
      ++cycle;
      core::PlanResult r;
      for (int i = 1; i <= 50; ++i) {
        r.path.push_back(line_.to_cartesian({t.ego.s_m + kCruiseMps * params_.step_s * i, kLaneD}));
      }
      if (cycle % 5 == 0) {
        r.status = core::PlanStatus::fallback;
        r.reason = "fallback at cycle " + std::to_string(cycle);
      } else if (cycle % 7 == 0) {
        r.status = core::PlanStatus::least_bad;
        r.reason = "least bad at cycle " + std::to_string(cycle);
      }
      return r;
    };
  }

  core::Map map_;
  core::ReferenceLine line_;
  WorldParams params_;
};

TEST_F(RunTest, EveryCycleIsCountedByItsPlanStatus) {
  World world = make_world();
  RunOptions opts;
  opts.duration_s = 20.0;
  opts.steps_per_call = 2;
  int cycle = 0;
  const RunReport r = run_drive(world, cruise_with_statuses(cycle), opts);
  ASSERT_EQ(r.planner_cycles, 500);  // 1000 steps, 2 per cycle
  ASSERT_EQ(cycle, 500);
  const auto count = [&](core::PlanStatus s) {
    return r.plan_status_cycles[static_cast<std::size_t>(s)];
  };
  EXPECT_EQ(count(core::PlanStatus::fallback), 100);       // 5, 10, ..., 500
  EXPECT_EQ(count(core::PlanStatus::least_bad), 71 - 14);  // multiples of 7, not of 35
  EXPECT_EQ(count(core::PlanStatus::normal), 500 - 100 - 57);
  EXPECT_EQ(r.first_plan_reason, "fallback at cycle 5");
  EXPECT_EQ(r.outcome.end, RunEnd::completed);
  EXPECT_FALSE(r.outcome.ended_early());
  EXPECT_EQ(ended_early_text(r.outcome), "");
}

// A planner that does not say how it planned (a program over the protocol): its cycles are
// counted, but by no status; the run's statuses are unknown, not normal. A run that mixes
// both keeps the known counts. A checkpoint keeps the unknown ones.
TEST_F(RunTest, CyclesWhoseStatusIsUnknownAreCountedApart) {
  World world = make_world();
  RunOptions opts;
  opts.duration_s = 4.0;
  opts.steps_per_call = 2;
  int cycle = 0;
  const PlannerFn inner = cruise_with_statuses(cycle);
  const RunReport unknown = run_drive(
      world,
      [&](const core::Telemetry& t) {
        core::PlanResult r = inner(t);
        r.status_known = false;
        return r;
      },
      opts);
  EXPECT_EQ(unknown.planner_cycles, 100);
  EXPECT_EQ(unknown.plan_status_unknown_cycles, 100);
  EXPECT_EQ(unknown.plan_status_cycles, core::PlanStatusCounts{});
  EXPECT_EQ(unknown.first_plan_reason, "");
  EXPECT_FALSE(unknown.plan_status_known());

  World again = make_world();
  cycle = 0;
  const RunReport mixed = run_drive(
      again,
      [&](const core::Telemetry& t) {
        core::PlanResult r = inner(t);
        r.status_known = cycle > 50;
        return r;
      },
      opts);
  EXPECT_EQ(mixed.planner_cycles, 100);
  EXPECT_EQ(mixed.plan_status_unknown_cycles, 50);
  EXPECT_EQ(mixed.plan_status_cycles[static_cast<std::size_t>(core::PlanStatus::fallback)], 10);
  EXPECT_EQ(mixed.first_plan_reason, "fallback at cycle 55");
  EXPECT_TRUE(mixed.plan_status_known());

  World w = make_world();
  Scorecard card(w);
  core::PlanResult remote = core::normal_plan({});
  remote.status_known = false;
  for (int i = 0; i < 3; ++i) card.count_cycle(remote, 1.0, 1.0);
  card.count_cycle(core::normal_plan({}), 1.0, 1.0);
  core::StateArchive out;
  card.archive(out);
  const std::string bytes = out.take();
  Scorecard restored(w);
  core::StateArchive in(bytes, "scorecard");
  restored.archive(in);
  in.expect_end();
  const RunReport r = restored.report(w, {}, CycleClock::round_trip);
  EXPECT_EQ(r.planner_cycles, 4);
  EXPECT_EQ(r.plan_status_unknown_cycles, 3);
  EXPECT_EQ(r.plan_status_cycles[static_cast<std::size_t>(core::PlanStatus::normal)], 1);
}

TEST_F(RunTest, APlannerThatThrowsEndsTheRunWithItsReasonAndTheReportSoFar) {
  World world = make_world();
  RunOptions opts;
  opts.duration_s = 60.0;
  opts.steps_per_call = 1;
  int cycle = 0;
  const PlannerFn inner = cruise_with_statuses(cycle);
  const RunReport r = run_drive(
      world,
      [&](const core::Telemetry& t) {
        if (cycle == 250) throw PlannerFailure("the planner stalled");
        return inner(t);
      },
      opts);
  EXPECT_EQ(r.outcome.end, RunEnd::planner_failed);
  EXPECT_TRUE(r.outcome.ended_early());
  EXPECT_DOUBLE_EQ(r.outcome.t_s, 5.0);  // 250 cycles of one step
  EXPECT_EQ(r.outcome.reason, "the planner stalled");
  EXPECT_EQ(ended_early_text(r.outcome), "planner failed at t = 5.000000 s: the planner stalled");
  EXPECT_EQ(r.planner_cycles, 250);
  EXPECT_DOUBLE_EQ(r.duration_s, 5.0);
  EXPECT_GT(r.distance_m, 0.0);
}

TEST_F(RunTest, AStopEndsTheRunAsStoppedEvenWhenThePlannerThrowsBecauseOfIt) {
  std::atomic<bool> stop{false};
  RunOptions opts;
  opts.duration_s = 60.0;
  opts.steps_per_call = 1;
  opts.stop = &stop;
  int cycle = 0;
  const PlannerFn inner = cruise_with_statuses(cycle);
  {
    World world = make_world();
    const RunReport r = run_drive(
        world,
        [&](const core::Telemetry& t) {
          if (cycle == 100) stop = true;
          return inner(t);
        },
        opts);
    EXPECT_EQ(r.outcome.end, RunEnd::stopped);
    EXPECT_EQ(ended_early_text(r.outcome), "stopped");
    EXPECT_EQ(r.planner_cycles, 101);  // the cycle that saw the stop came back, then it ended
  }
  // A planner whose wait was cut short by the stop throws: still the user's stop, not a failure.
  stop = false;
  cycle = 0;
  World world = make_world();
  const RunReport r = run_drive(
      world,
      [&](const core::Telemetry& t) {
        if (cycle == 100) {
          stop = true;
          throw PlannerFailure("stopped");
        }
        return inner(t);
      },
      opts);
  EXPECT_EQ(r.outcome.end, RunEnd::stopped);
}

// What watchers see: the frame before the first step, then one per step, each incident once
// with the frame of the step it was counted in, and each path after the frame it was planned
// from.
class Recorder final : public RunObserver {
 public:
  void on_frame(const Frame& f, std::span<const Incident> incidents) override {
    steps.push_back(f.step);
    cars_per_frame.push_back(f.cars.size());
    last_distance_m = f.distance_m;
    for (const Incident& i : incidents) {
      incident_steps.push_back(f.step);
      seen.push_back(i);
    }
  }
  void on_path(std::span<const core::Vec2> path) override {
    path_after_step.push_back(steps.empty() ? -1 : steps.back());
    EXPECT_EQ(path.size(), 50u);
  }
  std::vector<long> steps, path_after_step, incident_steps;
  std::vector<std::size_t> cars_per_frame;
  std::vector<Incident> seen;
  double last_distance_m = 0.0;
};

TEST_F(RunTest, WatchersSeeEveryFrameEveryIncidentOnceAndEveryPath) {
  World world = make_world();
  Recorder rec;
  RunOptions opts;
  opts.duration_s = 10.0;
  opts.steps_per_call = 3;
  opts.observer = &rec;
  // A cruise above the limit: speeding incidents (and the acceleration of the start).
  const RunReport r = run_drive(
      world,
      [&](const core::Telemetry& t) {
        std::vector<core::Vec2> path;
        for (int i = 1; i <= 50; ++i)
          path.push_back(line_.to_cartesian({t.ego.s_m + 0.5 * i, kLaneD}));
        return core::normal_plan(std::move(path));
      },
      opts);
  ASSERT_EQ(rec.steps.size(), 501u);
  for (std::size_t i = 0; i < rec.steps.size(); ++i) EXPECT_EQ(rec.steps[i], static_cast<long>(i));
  for (std::size_t n : rec.cars_per_frame) EXPECT_EQ(n, 12u);
  ASSERT_FALSE(r.incidents.empty());
  EXPECT_EQ(rec.seen, r.incidents);
  for (std::size_t i = 0; i < rec.seen.size(); ++i) {
    EXPECT_EQ(rec.incident_steps[i], std::lround(rec.seen[i].t_s / params_.step_s));
  }
  EXPECT_EQ(static_cast<long>(rec.path_after_step.size()), r.planner_cycles);
  for (std::size_t i = 0; i < rec.path_after_step.size(); ++i) {
    EXPECT_EQ(rec.path_after_step[i], static_cast<long>(3 * i));
  }
  EXPECT_DOUBLE_EQ(rec.last_distance_m, r.distance_m);
}

TEST(PaceClock, RealTimePutsStepKAtKStepTimesAfterTheStart) {
  const auto start = PaceClock::Clock::now();
  const PaceClock real(Pace::real_time, 0.02, start);
  EXPECT_EQ(real.due(0), start);
  EXPECT_EQ(real.due(50) - start,
            std::chrono::duration_cast<PaceClock::Clock::duration>(std::chrono::seconds(1)));
  EXPECT_EQ(real.due(7) - real.due(6), real.due(1) - real.due(0));
  const PaceClock free(Pace::unpaced, 0.02, start);
  EXPECT_EQ(free.due(1000), start);  // every step is due at once
}

TEST_F(RunTest, TheStepperSaysWhenTheNextStepIsDue) {
  World world = make_world();
  RunOptions opts;
  opts.duration_s = 1.0;
  opts.pace = Pace::real_time;
  Stepper run(world, opts);
  const auto first = run.next_step_due();
  // Stepping without waiting for the clock (as a loop does once a step is due) moves the due
  // time on by one step time each step.
  run.step();
  run.step();
  EXPECT_EQ(run.next_step_due() - first, 2 * std::chrono::duration_cast<PaceClock::Clock::duration>(
                                                 std::chrono::duration<double>(0.02)));
  EXPECT_FALSE(run.finished());
  run.end(RunEnd::planner_failed, "gone");
  run.end(RunEnd::stopped);  // the first end counts
  EXPECT_TRUE(run.finished());
  const RunReport r = run.report();
  EXPECT_EQ(r.outcome.end, RunEnd::planner_failed);
  EXPECT_DOUBLE_EQ(r.outcome.t_s, 0.04);
  EXPECT_EQ(r.outcome.reason, "gone");
}

TEST(RunEnd, NamesAreTheReportKeys) {
  EXPECT_EQ(to_string(RunEnd::completed), "completed");
  EXPECT_EQ(to_string(RunEnd::stopped), "stopped");
  EXPECT_EQ(to_string(RunEnd::planner_failed), "planner_failed");
  EXPECT_EQ(core::to_string(core::PlanStatus::least_bad), "least_bad");
}

}  // namespace
}  // namespace overtake::sim
