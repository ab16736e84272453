// The warm-up of a cut scenario: what a planner from outside was told, stored exactly and read
// back checked; played to a planner, the answers compared as the world reads them, and "in
// step" only once the last answers in a row matched; run_drive plays it before the first
// cycle, without moving the world, and ends the run at its start when the planner fails in it.

#include "overtake/sim/warm_up.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <stdexcept>

#include "overtake/core/state_archive.hpp"
#include "overtake/sim/run.hpp"
#include "sim/test_maps.hpp"

namespace overtake::sim {
namespace {

using ::testing::HasSubstr;

// A window of `n` cycles whose answers are distinct paths (cycle k answers k + 1 points).
WarmUp window(int n, int in_step = 4) {
  WarmUp w;
  w.in_step_cycles = in_step;
  for (int k = 0; k < n; ++k) {
    WarmUpCycle c;
    c.step = 3L * k + 7;
    c.telemetry.ego = {{100.0 + k * 0.4, 50.25}, 0.1 * k, 20.0 + 0.01 * k, 300.0 + k, 6.0};
    c.telemetry.previous_path = {{101.0 + k, 50.0}, {102.0 + k, 50.125}};
    c.telemetry.end_path = {310.5 + k, 6.25};
    core::CarObservation car;
    car.id = k % 3;
    car.position = {120.0 + k, 46.0};
    car.velocity_mps = {21.5, -0.25};
    car.s_m = 320.0 + k;
    car.d_m = 2.0;
    c.telemetry.cars = {car, car};
    c.telemetry.cars[1].id = 11;
    for (int i = 0; i <= k; ++i) c.answer.push_back({200.0 + 0.5 * i + k, 60.0 + 0.001 * i});
    w.cycles.push_back(std::move(c));
  }
  return w;
}

// A planner that answers the recorded answer of the cycle it is told (found by its ego's x),
// except for the cycles `wrong` says.
std::function<core::PlanResult(const core::Telemetry&)> replaying(const WarmUp& w,
                                                                  std::function<bool(int)> wrong) {
  return [&w, wrong](const core::Telemetry& t) {
    for (std::size_t k = 0; k < w.cycles.size(); ++k) {
      if (w.cycles[k].telemetry.ego.position.x != t.ego.position.x) continue;
      core::PlanResult r = core::normal_plan(w.cycles[k].answer);
      if (wrong(static_cast<int>(k))) r.path.back().x += 0.5;
      return r;
    }
    throw std::runtime_error("told something never recorded");
  };
}

TEST(WarmUp, BytesRoundTripExactly) {
  WarmUp w = window(30);
  w.from_run_start = true;
  w.cycles[4].telemetry.previous_path.clear();  // a cycle with nothing queued
  w.cycles[5].telemetry.cars.clear();
  const std::string bytes = encode_warm_up(w);
  EXPECT_EQ(decode_warm_up(bytes, "w"), w);
  EXPECT_EQ(decode_warm_up(encode_warm_up(WarmUp{}), "empty"), WarmUp{});
}

TEST(WarmUp, DamagedBytesAreRefusedNamingThem) {
  const std::string bytes = encode_warm_up(window(5));
  const auto refusal = [](const std::string& b) {
    try {
      (void)decode_warm_up(b, "scenario x: cut.warm_up.telemetry");
    } catch (const core::StateError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_THAT(refusal(bytes.substr(0, bytes.size() - 3)),
              HasSubstr("scenario x: cut.warm_up.telemetry"));
  EXPECT_THAT(refusal("NOTAWARMUP"), HasSubstr("a warm-up"));
  EXPECT_THAT(refusal(bytes + "x"), HasSubstr("scenario x"));
  std::string bad_version = bytes;
  bad_version[8] = 9;
  EXPECT_THAT(refusal(bad_version), HasSubstr("version"));
}

TEST(WarmUp, AnswersAreComparedAsTheWorldReadsThem) {
  const std::vector<core::Vec2> a = {{1234.5678, 10.0}};
  // The wire keeps 7 significant digits: 1234.5678 and 1234.56781 are read the same.
  EXPECT_TRUE(same_answer(a, std::vector<core::Vec2>{{1234.56781, 10.0}}));
  EXPECT_EQ(answer_digest(a), answer_digest(std::vector<core::Vec2>{{1234.56781, 10.0}}));
  EXPECT_FALSE(same_answer(a, std::vector<core::Vec2>{{1234.569, 10.0}}));
  EXPECT_NE(answer_digest(a), answer_digest(std::vector<core::Vec2>{{1234.569, 10.0}}));
  EXPECT_FALSE(same_answer(a, std::vector<core::Vec2>{{1234.5678, 10.0}, {1.0, 1.0}}));
}

TEST(WarmUp, APlannerComesInStepOnceItsLastAnswersMatch) {
  const WarmUp w = window(20, 4);
  WarmUpResult r;
  // Wrong for the first 6 cycles (its state starts elsewhere), then as recorded.
  play_warm_up(w, replaying(w, [](int k) { return k < 6; }), nullptr, r);
  EXPECT_EQ(r.cycles, 20u);
  EXPECT_EQ(r.played, 20u);
  EXPECT_TRUE(r.in_step);
  EXPECT_EQ(r.in_step_after, 10u);  // cycles 7 to 10 matched: in step after the 10th
  EXPECT_EQ(r.matched, 14u);
  EXPECT_EQ(r.first_difference, 0);
  EXPECT_EQ(r.last_difference, 5);
  EXPECT_EQ(r.first_difference_step, 7);
  EXPECT_EQ(r.digests.size(), 20u);
}

TEST(WarmUp, APlannerWhoseLastAnswersDifferIsNotInStep) {
  const WarmUp w = window(20, 4);
  WarmUpResult r;
  // Matched long enough once, then differs again two cycles before the end.
  play_warm_up(w, replaying(w, [](int k) { return k == 17; }), nullptr, r);
  EXPECT_FALSE(r.in_step);
  EXPECT_EQ(r.in_step_after, 0u);
  EXPECT_EQ(r.last_difference, 17);
  // Every answer as recorded: in step after the 4th.
  play_warm_up(w, replaying(w, [](int) { return false; }), nullptr, r);
  EXPECT_TRUE(r.in_step);
  EXPECT_EQ(r.in_step_after, 4u);
  EXPECT_EQ(r.first_difference, -1);
  // A window shorter than the run asked for: in step when every answer matched.
  const WarmUp short_window = window(3, 25);
  play_warm_up(short_window, replaying(short_window, [](int) { return false; }), nullptr, r);
  EXPECT_TRUE(r.in_step);
  EXPECT_EQ(r.in_step_after, 3u);
}

TEST(WarmUp, TwoPlaysAreComparedCycleByCycle) {
  const WarmUp w = window(10);
  WarmUpResult a;
  WarmUpResult b;
  play_warm_up(w, replaying(w, [](int) { return false; }), nullptr, a);
  play_warm_up(w, replaying(w, [](int k) { return k == 7; }), nullptr, b);
  EXPECT_EQ(first_disagreement(a, a), -1);
  EXPECT_EQ(first_disagreement(a, b), 7);
}

TEST(WarmUp, AStopEndsThePlay) {
  const WarmUp w = window(10);
  std::atomic<bool> stop{false};
  int told = 0;
  WarmUpResult r;
  play_warm_up(
      w,
      [&](const core::Telemetry& t) {
        if (++told == 3) stop = true;
        return replaying(w, [](int) { return false; })(t);
      },
      &stop, r);
  EXPECT_EQ(r.played, 3u);
  EXPECT_FALSE(r.in_step);
}

class RunWarmUp : public ::testing::Test {
 protected:
  RunWarmUp() : map_(test::circle_map()), line_(map_) {}
  core::Map map_;
  core::ReferenceLine line_;
  WorldParams params_;
};

// run_drive tells the planner the window first, then the world's own telemetry; the world has
// not moved meanwhile, and the report carries the warm-up's account.
TEST_F(RunWarmUp, RunDrivePlaysTheWindowBeforeTheFirstCycle) {
  World world(map_, line_, params_, TrafficProfile::faithful, 3);
  const WarmUp w = window(8, 2);
  std::vector<double> told_x;
  RunOptions o;
  o.duration_s = 1.0;
  o.warm_up = &w;
  const RunReport report = run_drive(
      world,
      [&](const core::Telemetry& t) {
        told_x.push_back(t.ego.position.x);
        for (const WarmUpCycle& c : w.cycles) {
          if (c.telemetry.ego.position.x == t.ego.position.x) return core::normal_plan(c.answer);
        }
        return core::normal_plan({});
      },
      o);
  ASSERT_GT(told_x.size(), 8u);
  for (std::size_t k = 0; k < 8; ++k) EXPECT_EQ(told_x[k], w.cycles[k].telemetry.ego.position.x);
  ASSERT_TRUE(report.warm_up.has_value());
  EXPECT_TRUE(report.warm_up->in_step);
  EXPECT_EQ(report.warm_up->in_step_after, 2u);
  EXPECT_EQ(report.outcome.end, RunEnd::completed);
  EXPECT_NEAR(report.duration_s, 1.0, 1e-9);
}

TEST_F(RunWarmUp, APlannerThatFailsInTheWarmUpEndsTheRunAtItsStart) {
  World world(map_, line_, params_, TrafficProfile::faithful, 3);
  const WarmUp w = window(8);
  RunOptions o;
  o.duration_s = 10.0;
  o.warm_up = &w;
  int told = 0;
  const RunReport report = run_drive(
      world,
      [&](const core::Telemetry&) -> core::PlanResult {
        if (++told == 5) throw PlannerFailure("the planner program crashed");
        return core::normal_plan({});
      },
      o);
  EXPECT_EQ(report.outcome.end, RunEnd::planner_failed);
  EXPECT_THAT(report.outcome.reason,
              HasSubstr("in the warm-up, at its cycle 5 of 8: the planner program crashed"));
  EXPECT_EQ(report.duration_s, 0.0);
  ASSERT_TRUE(report.warm_up.has_value());
  EXPECT_EQ(report.warm_up->played, 4u);
  EXPECT_FALSE(report.warm_up->in_step);
}

}  // namespace
}  // namespace overtake::sim
