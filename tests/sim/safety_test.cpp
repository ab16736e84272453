// Whose fault a collision was, and near misses (safety.hpp): the classification's rules one by
// one, TTC and headway on hand-made frames, and scripted scenarios in the world in which each
// kind of collision happens and is classified as it should be.

#include "overtake/sim/safety.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "overtake/sim/run.hpp"
#include "overtake/sim/traffic.hpp"
#include "overtake/sim/world.hpp"
#include "sim/test_maps.hpp"

namespace overtake::sim {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kLoopM = 7000.0;
using K = CollisionKind;

// --- the rules, on hand-made situations -------------------------------------------------

ContactBody body(double s_m, double d_m, double speed_mps) {
  ContactBody b;
  b.frenet = {s_m, d_m};
  b.speed_mps = speed_mps;
  return b;
}

ContactSituation situation(ContactBody ego, ContactBody car) {
  ContactSituation s;
  s.ego = ego;
  s.car = car;
  s.loop_length_m = kLoopM;
  return s;
}

LaneEntry entry(double s_ago, double ego_s, double ego_v, double car_s, double car_v) {
  LaneEntry e;
  e.s_ago = s_ago;
  e.ego = {ego_s, 6.0};
  e.car = {car_s, 6.0};
  e.ego_speed_mps = ego_v;
  e.car_speed_mps = car_v;
  return e;
}

CollisionClass classify(const ContactSituation& s) {
  return classify_collision(s, SafetyParams{});
}

TEST(CollisionRules, AStandingEgoIsNeverAtFaultAndAStandingCarAlwaysIsHit) {
  EXPECT_EQ(classify(situation(body(100, 6, 0.0), body(95.2, 6, 10))),
            (CollisionClass{K::ego_stopped, false}));
  EXPECT_EQ(classify(situation(body(100, 6, 0.04), body(104.8, 6, 10))),
            (CollisionClass{K::ego_stopped, false}));
  EXPECT_EQ(classify(situation(body(100, 6, 12), body(104.8, 6, 0.0))),
            (CollisionClass{K::car_stopped, true}));
}

TEST(CollisionRules, AStopByBrakingHarderThanTrafficIsJudgedAsTheSameStopAtACrawl) {
  // Rear-ended after braking at 8 m/s^2 over the last second: at 0.06 m/s and at 0.04 m/s
  // (standing, by the stopped threshold) alike the ego's, as a hard stop.
  for (const double v : {0.06, 0.04, 0.0}) {
    auto rear = situation(body(100, 6, v), body(95.2, 6, 5));
    rear.ego_deceleration_mps2 = 8.0;
    EXPECT_EQ(classify(rear), (CollisionClass{K::hit_from_behind_braking, true})) << v;
    // Without the hard braking: not the ego's, either way.
    rear.ego_deceleration_mps2 = 2.0;
    EXPECT_FALSE(classify(rear).at_fault) << v;
  }
  // A standing ego that braked hard is still not at fault for a car that drives into its
  // front or side.
  auto front = situation(body(100, 6, 0.0), body(104.8, 6, 3));
  front.ego_deceleration_mps2 = 8.0;
  EXPECT_EQ(classify(front), (CollisionClass{K::ego_stopped, false}));
}

TEST(CollisionRules, AFollowerInTheEgosOwnLaneRearEndingAStraddlingEgoIsNotItsFault) {
  // The ego's body reaches into the next lane (it has not entered that lane's follower's
  // lane: the follower is in the ego's own lane): an active rear collision (nuPlan), not the
  // ego's, where it once counted as the ego's lane change.
  auto rear = situation(body(100, 7.2, 15), body(95.2, 6.0, 20));
  rear.ego.in_two_lanes = true;
  EXPECT_EQ(classify(rear), (CollisionClass{K::hit_from_behind, false}));
  rear.ego_deceleration_mps2 = 7.0;
  EXPECT_EQ(classify(rear), (CollisionClass{K::hit_from_behind_braking, true}));
}

TEST(CollisionRules, FrontAndRearInOneLane) {
  // The ego 4.8 m behind the car (bumpers 0.1 m apart): it drove into it.
  EXPECT_EQ(classify(situation(body(100, 6, 20), body(104.8, 6.3, 15))),
            (CollisionClass{K::ego_hit_car_ahead, true}));
  // The car behind: it drove into the ego, which kept its lane and did not brake hard.
  auto rear = situation(body(100, 6, 15), body(95.2, 5.8, 20));
  rear.ego_deceleration_mps2 = 6.4;
  EXPECT_EQ(classify(rear), (CollisionClass{K::hit_from_behind, false}));
  // ... braking harder than traffic does: the ego's.
  rear.ego_deceleration_mps2 = 6.6;
  EXPECT_EQ(classify(rear), (CollisionClass{K::hit_from_behind_braking, true}));
}

TEST(CollisionRules, RearEndAcrossTheLoopsSeam) {
  // The ego just after the seam, the car just before it: the car is behind.
  EXPECT_EQ(classify(situation(body(2.0, 6, 15), body(kLoopM - 2.8, 6, 20))).kind,
            K::hit_from_behind);
  EXPECT_EQ(classify(situation(body(kLoopM - 2.8, 6, 20), body(2.0, 6, 15))).kind,
            K::ego_hit_car_ahead);
}

TEST(CollisionRules, SideContactsGoToWhoeverWasChangingLanes) {
  // Side by side (overlapping along the road, apart across it).
  auto ego_moves = situation(body(100, 7.6, 20), body(101, 9.6, 20));
  ego_moves.ego.in_two_lanes = true;
  EXPECT_EQ(classify(ego_moves), (CollisionClass{K::ego_lane_change, true}));
  auto car_moves = situation(body(100, 6.0, 20), body(101, 8.0, 20));
  car_moves.car.in_two_lanes = true;
  EXPECT_EQ(classify(car_moves), (CollisionClass{K::car_cut_in, false}));
  // Neither changing lanes (a wander): the one that moved more toward the other.
  auto wander = situation(body(100, 6.5, 20), body(101, 8.5, 20));
  wander.ego.toward_other_m = 0.6;
  wander.car.toward_other_m = 0.2;
  EXPECT_EQ(classify(wander), (CollisionClass{K::side_contact, true}));
  std::swap(wander.ego.toward_other_m, wander.car.toward_other_m);
  EXPECT_EQ(classify(wander), (CollisionClass{K::side_contact, false}));
}

TEST(CollisionRules, AGapTheFollowerCouldAbsorbOrNot) {
  const SafetyParams p;
  const core::CarFootprint size;
  // The one ahead holds its speed. Closing at 10 m/s, reacting after 1 s and braking at
  // 6.5 m/s^2 needs 10 + 100/13 = 17.7 m.
  EXPECT_FALSE(entry_absorbable(entry(0, 100, 15, 100 - 4.7 - 17.0, 25), 15, kLoopM, size, p));
  EXPECT_TRUE(entry_absorbable(entry(0, 100, 15, 100 - 4.7 - 18.5, 25), 15, kLoopM, size, p));
  // The same with the ego behind, closing on the car.
  EXPECT_FALSE(entry_absorbable(entry(0, 100, 25, 100 + 4.7 + 17.0, 15), 15, kLoopM, size, p));
  EXPECT_TRUE(entry_absorbable(entry(0, 100, 25, 100 + 4.7 + 18.5, 15), 15, kLoopM, size, p));
  // Not closing: any gap will do; beside the other: none will.
  EXPECT_TRUE(entry_absorbable(entry(0, 100, 25, 100 - 4.7 - 0.5, 20), 25, kLoopM, size, p));
  EXPECT_FALSE(entry_absorbable(entry(0, 100, 20, 100 - 3.0, 20), 20, kLoopM, size, p));
}

TEST(CollisionRules, WhatTheOneAheadDidAfterTheEntryCounts) {
  const SafetyParams p;
  const core::CarFootprint size;
  // A car enters 15 m ahead of the ego at the ego's 20 m/s and slows to 10 m/s over the 2.5 s
  // to the contact (4 m/s^2). Reacting after 1 s and then braking at 6.5 m/s^2, the ego would
  // have kept at least 9.8 m: it could have absorbed it.
  LaneEntry e = entry(0.0, 100, 20, 100 + 4.7 + 15.0, 20);
  e.entered_s_ago = 2.5;
  EXPECT_TRUE(entry_absorbable(e, 10.0, kLoopM, size, p));
  // Slowing at 6 m/s^2 (to 5 m/s), as traffic may brake: 15 m was too little room.
  EXPECT_FALSE(entry_absorbable(e, 5.0, kLoopM, size, p));
  // Braking at 8 m/s^2 (to 0 over the same 2.5 s): harder than traffic does, the cutter's
  // whatever the gap. The rule once assumed the one ahead would hold its speed: every one of
  // these was "absorbable".
  EXPECT_FALSE(entry_absorbable(e, 0.0, kLoopM, size, p));
  LaneEntry roomy = entry(0.0, 100, 20, 100 + 4.7 + 60.0, 20);
  roomy.entered_s_ago = 2.5;
  EXPECT_FALSE(entry_absorbable(roomy, 0.0, kLoopM, size, p));
  EXPECT_TRUE(entry_absorbable(roomy, 5.0, kLoopM, size, p));
  // A car ahead speeding up after its entry: easier than holding its speed.
  LaneEntry faster = entry(0.0, 100, 25, 100 + 4.7 + 17.0, 15);
  faster.entered_s_ago = 1.0;
  EXPECT_TRUE(entry_absorbable(faster, 20.0, kLoopM, size, p));
}

TEST(CollisionRules, ARecentLaneEntryDecidesFrontAndRearContacts) {
  // The ego moved in front of a follower that could not absorb the gap: the ego's.
  auto cut_in = situation(body(100, 6, 15), body(95.2, 6, 25));
  cut_in.ego_entry = entry(1.0, 90, 15, 70, 25);  // 15.3 m gap, closing at 10 m/s
  EXPECT_EQ(classify(cut_in), (CollisionClass{K::ego_lane_change, true}));
  // ... that it could have absorbed: the follower's.
  cut_in.ego_entry = entry(1.0, 90, 15, 50, 25);  // 35.3 m
  EXPECT_EQ(classify(cut_in), (CollisionClass{K::hit_from_behind, false}));
  // ... too long ago to be part of the lane change.
  cut_in.ego_entry = entry(3.5, 90, 15, 70, 25);
  EXPECT_EQ(classify(cut_in), (CollisionClass{K::hit_from_behind, false}));

  // A car moved in front of the ego: its fault when the ego could not absorb it, the ego's
  // when it could have braked.
  auto car_in = situation(body(100, 6, 20), body(104.8, 5.7, 12));
  car_in.car_entry = entry(0.0, 90, 20, 100, 12);  // 5.3 m, closing at 8 m/s
  EXPECT_EQ(classify(car_in), (CollisionClass{K::car_cut_in, false}));
  car_in.car_entry = entry(0.0, 60, 20, 100, 12);  // 35.3 m
  EXPECT_EQ(classify(car_in), (CollisionClass{K::ego_hit_car_ahead, true}));
  // A car that cut in 15 m ahead at the ego's speed, then braked at 8 m/s^2 until the
  // contact 2 s later: the cutter's (it was the ego's while the rule assumed the cutter
  // would hold its speed).
  auto brakes = situation(body(100, 6, 20), body(104.8, 6, 4));
  brakes.car_entry = entry(0.2, 100 - 4.7 - 15.0 - 24.0, 20, 100 - 24.0, 20);
  brakes.car_entry.entered_s_ago = 2.0;
  EXPECT_EQ(classify(brakes), (CollisionClass{K::car_cut_in, false}));
  // A car that changed lanes into the ego's rear: the car's.
  auto into_rear = situation(body(100, 6, 15), body(95.2, 6.4, 20));
  into_rear.car_entry = entry(0.5, 95, 15, 60, 20);
  EXPECT_EQ(classify(into_rear), (CollisionClass{K::car_cut_in, false}));
  // The ego moved into a lane and drove into the car ahead there: the ego's.
  auto into_ahead = situation(body(100, 6, 20), body(104.8, 6, 15));
  into_ahead.ego_entry = entry(0.5, 60, 20, 100, 15);
  EXPECT_EQ(classify(into_ahead), (CollisionClass{K::ego_lane_change, true}));
  // Both entered: the more recent one decides.
  into_ahead.car_entry = entry(0.2, 99, 20, 100, 15);
  EXPECT_EQ(classify(into_ahead), (CollisionClass{K::car_cut_in, false}));
}

TEST(CollisionRules, EveryKindHasAName) {
  for (std::size_t k = 0; k < kCollisionKindCount; ++k) {
    EXPECT_NE(to_string(static_cast<CollisionKind>(k)), "unknown") << k;
  }
}

// --- TTC and headway on hand-made frames ---------------------------------------------------

TEST(TimeToCollision, IsTheGapOverTheClosingSpeed) {
  EXPECT_DOUBLE_EQ(time_to_collision_s(25.0, 20.0, 15.0), 5.0);
  EXPECT_EQ(time_to_collision_s(25.0, 15.0, 15.0), kInf);
  EXPECT_EQ(time_to_collision_s(25.0, 10.0, 15.0), kInf);
  EXPECT_DOUBLE_EQ(time_to_collision_s(-1.0, 20.0, 15.0), 0.0);
}

TrafficCar car_at(int id, double s_m, double d_m, double speed_mps) {
  TrafficCar c;
  c.id = id;
  c.map_frenet = {s_m, d_m};
  c.speed_mps = speed_mps;
  return c;
}

class MonitorTest : public ::testing::Test {
 protected:
  SafetyMonitor monitor_{SafetyParams{}, 0.02, core::RoadParams{}, core::CarFootprint{}, kLoopM};
};

TEST_F(MonitorTest, TtcAndHeadwayToTheCarAheadInTheEgosLane) {
  const std::vector<TrafficCar> cars = {car_at(0, 130.0, 6.2, 15.0),  // ahead, lane 1
                                        car_at(1, 120.0, 10.0, 5.0),  // nearer, but lane 2
                                        car_at(2, 80.0, 6.0, 30.0)};  // behind
  (void)monitor_.observe({{100.0, 6.0}, 20.0}, cars, std::nullopt);
  const double gap = 30.0 - 4.7;
  EXPECT_NEAR(monitor_.current().ttc_ahead_s, gap / 5.0, 1e-12);
  EXPECT_NEAR(monitor_.current().headway_s, gap / 20.0, 1e-12);
  EXPECT_EQ(monitor_.current().ttc_entering_s, kInf);  // in one lane: entering none
}

TEST_F(MonitorTest, TheCarAheadAcrossTheSeam) {
  const std::vector<TrafficCar> cars = {car_at(0, 15.0, 6.0, 10.0)};
  (void)monitor_.observe({{kLoopM - 10.0, 6.0}, 20.0}, cars, std::nullopt);
  EXPECT_NEAR(monitor_.current().ttc_ahead_s, (25.0 - 4.7) / 10.0, 1e-9);
}

TEST_F(MonitorTest, EnteringALaneMeasuresItsLeaderAndFollower) {
  std::vector<TrafficCar> cars = {car_at(0, 70.0, 10.0, 26.0),    // behind in lane 2
                                  car_at(1, 160.0, 10.0, 12.0)};  // ahead in lane 2
  (void)monitor_.observe({{100.0, 6.0}, 20.0}, cars, std::nullopt);
  EXPECT_EQ(monitor_.current().ttc_entering_s, kInf);
  // The ego moves over until its body reaches into lane 2.
  double s = 100.0;
  for (int k = 1; k <= 16; ++k) {
    const double d = 6.0 + 0.1 * k;
    s += 0.4;
    cars[0].map_frenet.s_m += 0.52;
    cars[1].map_frenet.s_m += 0.24;
    (void)monitor_.observe({{s, d}, 20.0}, cars, std::nullopt);
  }
  const double behind = (s - cars[0].map_frenet.s_m - 4.7) / 6.0;
  const double ahead = (cars[1].map_frenet.s_m - s - 4.7) / 8.0;
  EXPECT_NEAR(monitor_.current().ttc_entering_s, std::min(behind, ahead), 1e-9);
}

TEST_F(MonitorTest, TouchesOfOneCarAreOneContactUntilTheyHaveBeenApartForTheGap) {
  // A car bumping into the ego's rear again and again (pushed apart, closing again), then
  // apart for longer than the gap (5 s, 250 steps), then touching again; another car between.
  std::vector<TrafficCar> cars = {car_at(3, 95.3, 6.0, 20.0), car_at(4, 104.7, 6.0, 20.0)};
  double s = 100.0;
  const auto step = [&](std::optional<int> touching) {
    s += 0.4;
    for (TrafficCar& c : cars) c.map_frenet.s_m += 0.4;
    return monitor_.observe({{s, 6.0}, 20.0}, cars, touching);
  };
  (void)monitor_.observe({{s, 6.0}, 20.0}, cars, std::nullopt);
  std::vector<std::optional<ContactStep>> seen;
  for (int k = 0; k < 5; ++k) seen.push_back(step(3));
  for (int k = 0; k < 200; ++k) seen.push_back(step(std::nullopt));  // 4 s apart
  for (int k = 0; k < 5; ++k) seen.push_back(step(3));               // the same contact
  for (int k = 0; k < 3; ++k) seen.push_back(step(4));               // another car
  for (int k = 0; k < 5; ++k) seen.push_back(step(3));               // still the first
  ASSERT_TRUE(seen.front().has_value());
  EXPECT_TRUE(seen.front()->begins);
  EXPECT_EQ(seen.front()->index, 0);
  for (std::size_t i = 1; i < seen.size(); ++i) {
    if (!seen[i]) continue;
    const bool other = i >= 210 && i < 213;
    EXPECT_EQ(seen[i]->index, other ? 1 : 0) << i;
    EXPECT_EQ(seen[i]->begins, i == 210) << i;
    if (!other) {
      EXPECT_EQ(seen[i]->collision, seen.front()->collision) << i;
    }
  }
  EXPECT_EQ(monitor_.contacts_begun(), 2);
  // 251 steps apart (more than the gap): a new contact, classified afresh.
  for (int k = 0; k < 251; ++k) (void)step(std::nullopt);
  const std::optional<ContactStep> again = step(3);
  ASSERT_TRUE(again.has_value());
  EXPECT_TRUE(again->begins);
  EXPECT_EQ(again->index, 2);
  EXPECT_EQ(monitor_.contacts_begun(), 3);
}

TEST_F(MonitorTest, OpenContactsGoThroughACheckpoint) {
  std::vector<TrafficCar> cars = {car_at(3, 95.3, 6.0, 20.0)};
  (void)monitor_.observe({{100.0, 6.0}, 20.0}, cars, std::nullopt);
  (void)monitor_.observe({{100.4, 6.0}, 20.0}, cars, 3);
  (void)monitor_.observe({{100.8, 6.0}, 20.0}, cars, std::nullopt);
  core::StateArchive out;
  monitor_.archive(out);
  monitor_.archive_contacts(out);
  const std::string bytes = out.take();
  SafetyMonitor restored{SafetyParams{}, 0.02, core::RoadParams{}, core::CarFootprint{}, kLoopM};
  core::StateArchive in(bytes, "monitor");
  restored.archive(in);
  restored.archive_contacts(in);
  in.expect_end();
  const auto a = monitor_.observe({{101.2, 6.0}, 20.0}, cars, 3);
  const auto b = restored.observe({{101.2, 6.0}, 20.0}, cars, 3);
  ASSERT_TRUE(a && b);
  EXPECT_FALSE(b->begins);  // the same contact goes on
  EXPECT_EQ(a->index, b->index);
  EXPECT_EQ(a->collision, b->collision);
}

// --- scripted scenarios in the world -------------------------------------------------------

constexpr double kEgoS = 1000.0;

/// A path that follows (s(t), d(t)) on the reference line, extending the queued path.
PlannerFn follow(const World& world, std::function<core::FrenetPoint(double t_s)> at) {
  return [&world, at = std::move(at)](const core::Telemetry& t) {
    core::PlanResult r;
    r.path = t.previous_path;
    const double step = world.params().step_s;
    const double t_end = world.time_s() + static_cast<double>(r.path.size()) * step;
    for (int k = 1; r.path.size() < 50; ++k) {
      r.path.push_back(world.line().to_cartesian(at(t_end + k * step)));
    }
    return r;
  };
}

/// d(t) of a minimum-jerk lane change from `from_d` to `to_d` starting at t0 over `dur_s`.
double lane_change_d(double t, double t0, double dur_s, double from_d, double to_d) {
  const double x = std::clamp((t - t0) / dur_s, 0.0, 1.0);
  return from_d + (to_d - from_d) * x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
}

class SafetyScenario : public ::testing::Test {
 protected:
  SafetyScenario() : map_(test::circle_map()), line_(map_) {}

  RunReport run(Scenario sc, const std::function<core::FrenetPoint(double)>& ego, double duration_s,
                const WorldParams& params = {}) {
    std::stable_sort(sc.events.begin(), sc.events.end(),
                     [](const ScenarioEvent& a, const ScenarioEvent& b) { return a.t_s < b.t_s; });
    World world(map_, line_, params, sc);
    RunOptions opts;
    opts.duration_s = duration_s;
    opts.steps_per_call = 2;
    return run_drive(world, follow(world, ego), opts);
  }

  /// Every collision counted, and its one class (the class of the contact holds while it
  /// lasts, so a persisting contact counted again has the same).
  static std::optional<CollisionClass> the_class(const RunReport& r) {
    std::optional<CollisionClass> c;
    for (const Incident& i : r.incidents) {
      if (i.type != IncidentType::collision) continue;
      EXPECT_TRUE(i.collision.has_value());
      if (!c) c = i.collision;
      EXPECT_EQ(i.collision, c) << "t " << i.t_s;
    }
    return c;
  }

  static Scenario ego_at(double speed_mps) {
    Scenario sc;
    sc.ego_s_m = kEgoS;
    sc.ego_d_m = 6.0;
    sc.ego_speed_mps = speed_mps;
    return sc;
  }

  static std::function<core::FrenetPoint(double)> steady(double speed_mps, double d_m = 6.0) {
    return [=](double t) { return core::FrenetPoint{kEgoS + speed_mps * t, d_m}; };
  }

  core::Map map_;
  core::ReferenceLine line_;
};

TEST_F(SafetyScenario, ARearEndIntoASteadyEgoIsNotItsFault) {
  Scenario sc = ego_at(15.0);
  sc.cars = {{kEgoS - 30.0, 1, 25.0}};
  const RunReport r = run(sc, steady(15.0), 6.0);
  ASSERT_GE(r.incident_counts[0], 1);
  EXPECT_EQ(the_class(r), (CollisionClass{K::hit_from_behind, false}));
  EXPECT_NEAR(r.incidents.front().t_s, (30.0 - 4.7) / 10.0, 0.1);
}

TEST_F(SafetyScenario, AnEgoThatBrakesHarderThanTrafficIsAtFaultWhenHitFromBehind) {
  Scenario sc = ego_at(20.0);
  sc.cars = {{kEgoS - 15.0, 1, 20.0}};
  // Brakes at 8 m/s^2 from t = 1 s until it stands.
  const auto braking = [](double t) {
    const double tb = std::clamp(t - 1.0, 0.0, 2.5);
    return core::FrenetPoint{kEgoS + 20.0 * std::min(t, 1.0) + 20.0 * tb - 4.0 * tb * tb, 6.0};
  };
  const RunReport r = run(sc, braking, 5.0);
  ASSERT_GE(r.incident_counts[0], 1);
  EXPECT_EQ(the_class(r), (CollisionClass{K::hit_from_behind_braking, true}));
}

TEST_F(SafetyScenario, TheEgoDrivingIntoACarAheadIsItsFault) {
  Scenario sc = ego_at(20.0);
  sc.cars = {{kEgoS + 30.0, 1, 10.0}};
  const RunReport r = run(sc, steady(20.0), 5.0);
  EXPECT_EQ(the_class(r), (CollisionClass{K::ego_hit_car_ahead, true}));
}

TEST_F(SafetyScenario, StandingStill) {
  Scenario stands = ego_at(0.0);
  stands.cars = {{kEgoS - 25.0, 1, 10.0}};
  const RunReport hit = run(stands, steady(0.0), 4.0);
  EXPECT_EQ(the_class(hit), (CollisionClass{K::ego_stopped, false}));

  // The ego drives into a standing car (the push sets it moving: later contacts are with a
  // moving car, so only the first is this kind).
  Scenario parked = ego_at(15.0);
  parked.cars = {{kEgoS + 30.0, 1, 0.0}};
  const RunReport into = run(parked, steady(15.0), 4.0);
  ASSERT_FALSE(into.incidents.empty());
  EXPECT_EQ(into.incidents.front().type, IncidentType::collision);
  EXPECT_EQ(into.incidents.front().collision, (CollisionClass{K::car_stopped, true}));
}

TEST_F(SafetyScenario, ACutInByTheEgoInFrontOfAFollowerThatCannotAbsorbItIsItsFault) {
  // The follower 35 m behind in lane 2 at 25 m/s; the ego, at 15 m/s, moves over at t = 1 s.
  Scenario sc = ego_at(15.0);
  sc.cars = {{kEgoS - 35.0, 2, 25.0}};
  const auto cut_in = [](double t) {
    return core::FrenetPoint{kEgoS + 15.0 * t, lane_change_d(t, 1.0, 2.0, 6.0, 10.0)};
  };
  const RunReport r = run(sc, cut_in, 6.0);
  ASSERT_GE(r.incident_counts[0], 1);
  EXPECT_EQ(the_class(r), (CollisionClass{K::ego_lane_change, true}));
}

TEST_F(SafetyScenario, ACutInThatTheFollowerCouldHaveAbsorbedIsNotTheEgosFault) {
  // The same lane change with the follower 71 m behind at 30 m/s: about 40 m of gap when the
  // ego's body enters lane 2 (needed: 15 + 225 / 13 = 32.3 m), hit 4.4 s in, inside the window.
  Scenario sc = ego_at(15.0);
  sc.cars = {{kEgoS - 71.0, 2, 30.0}};
  const auto cut_in = [](double t) {
    return core::FrenetPoint{kEgoS + 15.0 * t, lane_change_d(t, 1.0, 2.0, 6.0, 10.0)};
  };
  const RunReport r = run(sc, cut_in, 8.0);
  ASSERT_GE(r.incident_counts[0], 1);
  EXPECT_LT(r.incidents.front().t_s, 5.5);
  EXPECT_EQ(the_class(r), (CollisionClass{K::hit_from_behind, false}));
}

TEST_F(SafetyScenario, ACarCuttingInTooCloseIsItsFaultAndFartherAheadTheEgos) {
  // A car at 12 m/s in lane 0 moves into the ego's lane (3 s) while the ego holds 20 m/s.
  Scenario close = ego_at(20.0);
  close.cars = {{kEgoS + 25.0, 0, 12.0}};
  close.events = {{0.0, 0, ScenarioAction::change_lane, 1, 0.0, 0.0, 0.0}};
  const RunReport near = run(close, steady(20.0), 5.0);
  ASSERT_GE(near.incident_counts[0], 1);
  EXPECT_EQ(the_class(near), (CollisionClass{K::car_cut_in, false}));

  // 40 m ahead: about 26 m of gap when it enters, 13 m needed: the ego could have braked.
  Scenario far = close;
  far.cars = {{kEgoS + 40.0, 0, 12.0}};
  const RunReport late = run(far, steady(20.0), 7.0);
  ASSERT_GE(late.incident_counts[0], 1);
  EXPECT_EQ(the_class(late), (CollisionClass{K::ego_hit_car_ahead, true}));
}

TEST_F(SafetyScenario, ACarThatCutsInCloseAndThenBrakesIsItsFault) {
  // A car at the ego's 20 m/s cuts in about 15 m ahead and then brakes at 8 m/s^2, harder
  // than traffic does: the contact is its fault (the rule once assumed the cutter would hold
  // its speed, and booked it as the ego's driving into the car ahead).
  Scenario sc = ego_at(20.0);
  sc.cars = {{kEgoS + 4.7 + 15.0, 0, 20.0}};
  sc.events = {{0.0, 0, ScenarioAction::change_lane, 1, 0.0, 0.0, 0.0},
               {1.2, 0, ScenarioAction::brake, 0, 0.0, 8.0, 2.5}};
  const RunReport r = run(sc, steady(20.0), 5.0);
  ASSERT_GE(r.incident_counts[0], 1);
  EXPECT_EQ(the_class(r), (CollisionClass{K::car_cut_in, false}));
  ASSERT_EQ(r.contacts.size(), 1U);
  EXPECT_FALSE(r.contacts.front().collision.at_fault);
  // Braking at 5 m/s^2, as traffic does: reacting after a second and braking at 6.5 m/s^2,
  // the ego could have stopped behind it.
  sc.events[1].rate_mps2 = 5.0;
  sc.events[1].duration_s = 4.0;
  const RunReport soft = run(sc, steady(20.0), 6.0);
  ASSERT_EQ(soft.contacts.size(), 1U);
  EXPECT_EQ(soft.contacts.front().collision, (CollisionClass{K::ego_hit_car_ahead, true}));
}

TEST_F(SafetyScenario, AFollowerRearEndingAnEgoThatLeansIntoTheNextLaneIsNotItsFault) {
  // The ego drifts from the centre of lane 1 to d = 7.4 m (its body reaches 0.35 m into lane
  // 2, it never enters the follower's lane) and holds 15 m/s; a follower in lane 1 at 25 m/s
  // runs into its rear.
  Scenario sc = ego_at(15.0);
  sc.cars = {{kEgoS - 30.0, 1, 25.0}};
  const auto lean = [](double t) {
    return core::FrenetPoint{kEgoS + 15.0 * t, lane_change_d(t, 0.5, 1.0, 6.0, 7.4)};
  };
  const RunReport r = run(sc, lean, 5.0);
  ASSERT_EQ(r.contacts.size(), 1U);
  EXPECT_GT(r.contacts.front().t_s, 1.5);  // after the drift
  EXPECT_EQ(the_class(r), (CollisionClass{K::hit_from_behind, false}));
}

TEST_F(SafetyScenario, AHardStopIsTheEgosAtACrawlAndAtAStandAlike) {
  // The ego brakes at 8 m/s^2 from 20 m/s at t = 1 s down to `crawl` and holds it; the
  // follower brakes later and softer (5 m/s^2 from t = 1.5 s) and runs into it just after it
  // stops. Once a stop under the stopped threshold (0.05 m/s) excused the ego and the same
  // stop at 0.06 m/s did not.
  const auto hard_stop = [](double crawl) {
    return [crawl](double t) {
      const double tb = std::max(0.0, t - 1.0);
      const double t_stop = (20.0 - crawl) / 8.0;
      const double braking = std::min(tb, t_stop);
      const double s = 20.0 * std::min(t, 1.0) + 20.0 * braking - 4.0 * braking * braking +
                       crawl * std::max(0.0, tb - t_stop);
      return core::FrenetPoint{kEgoS + s, 6.0};
    };
  };
  for (const double crawl : {0.04, 0.06}) {
    Scenario sc = ego_at(20.0);
    sc.cars = {{kEgoS - 20.5, 1, 20.0}};
    sc.events = {{1.5, 0, ScenarioAction::brake, 0, 0.0, 5.0, 3.0}};
    const RunReport r = run(sc, hard_stop(crawl), 5.0);
    ASSERT_EQ(r.contacts.size(), 1U) << crawl;
    EXPECT_GT(r.contacts.front().t_s, 1.0 + (20.0 - crawl) / 8.0) << crawl;  // stopped
    EXPECT_EQ(the_class(r), (CollisionClass{K::hit_from_behind_braking, true})) << crawl;
  }
}

TEST_F(SafetyScenario, OneContactIsOneCollisionHoweverOftenTheRubricCountsIt) {
  // The ego at 20 m/s runs into a car at 10 m/s and keeps pushing it for 4 s: the bodies are
  // pushed apart and touch again step after step, the rubric counts a collision for every
  // second, and the report has one contact, with one class, that every count belongs to.
  Scenario sc = ego_at(20.0);
  sc.cars = {{kEgoS + 15.0, 1, 10.0}};
  const RunReport r = run(sc, steady(20.0), 5.5);
  ASSERT_GE(r.incident_counts[0], 3);
  ASSERT_EQ(r.contacts.size(), 1U);
  const Contact& c = r.contacts.front();
  EXPECT_EQ(c.car_id, 0);
  EXPECT_EQ(c.collision, (CollisionClass{K::ego_hit_car_ahead, true}));
  EXPECT_EQ(c.rubric_collisions, r.incident_counts[0]);
  EXPECT_NEAR(c.t_s, (15.0 - 4.7) / 10.0, 0.05);
  EXPECT_GT(c.end_t_s, c.t_s + 3.0);
  for (const Incident& i : r.incidents) {
    if (i.type == IncidentType::collision) {
      EXPECT_EQ(i.contact, 0) << i.t_s;
    }
  }
}

TEST_F(SafetyScenario, SideContacts) {
  // The ego moves over onto a car beside it in lane 2.
  Scenario beside = ego_at(20.0);
  beside.cars = {{kEgoS + 1.0, 2, 20.0}};
  const auto over = [](double t) {
    return core::FrenetPoint{kEgoS + 20.0 * t, lane_change_d(t, 1.0, 2.0, 6.0, 10.0)};
  };
  const RunReport ego_moves = run(beside, over, 4.0);
  ASSERT_GE(ego_moves.incident_counts[0], 1);
  EXPECT_EQ(the_class(ego_moves), (CollisionClass{K::ego_lane_change, true}));

  // The car beside moves over onto the ego.
  beside.events = {{1.0, 0, ScenarioAction::change_lane, 1, 0.0, 0.0, 0.0}};
  const RunReport car_moves = run(beside, steady(20.0), 4.0);
  ASSERT_GE(car_moves.incident_counts[0], 1);
  EXPECT_EQ(the_class(car_moves), (CollisionClass{K::car_cut_in, false}));
}

TEST_F(SafetyScenario, ANearMissIsMeasuredAndCountedOnce) {
  // Closing at 6 m/s on a car 40 m ahead that leaves the lane just in time.
  Scenario sc = ego_at(20.0);
  sc.cars = {{kEgoS + 40.0, 1, 14.0}};
  sc.events = {{3.0, 0, ScenarioAction::change_lane, 2, 0.0, 0.0, 0.0}};
  const RunReport r = run(sc, steady(20.0), 10.0);
  EXPECT_EQ(r.incident_counts[0], 0);
  const SafetySummary& s = r.safety;
  EXPECT_EQ(s.near_miss_episodes, 1);
  EXPECT_GT(s.min_ttc_ahead_s, 0.3);
  EXPECT_LT(s.min_ttc_ahead_s, 1.5);
  EXPECT_GT(s.ttc_below_s, 0.2);
  EXPECT_LT(s.ttc_below_s, 1.5);
  // The least headway and the least TTC are the same least gap, over 20 and over 6 m/s.
  EXPECT_NEAR(s.min_headway_s * 20.0, s.min_ttc_ahead_s * 6.0, 0.15);
  EXPECT_GT(s.headway_below_s, s.ttc_below_s);
  EXPECT_EQ(s.min_ttc_entering_s, kInf);  // the ego kept its lane
}

TEST_F(SafetyScenario, AContactIsNoNearMiss) {
  Scenario sc = ego_at(20.0);
  sc.cars = {{kEgoS + 30.0, 1, 10.0}};
  const RunReport r = run(sc, steady(20.0), 5.0);
  ASSERT_GE(r.incident_counts[0], 1);
  EXPECT_EQ(r.safety.near_miss_episodes, 0);
  EXPECT_LT(r.safety.min_ttc_ahead_s, 0.05);  // the last step before the contact
}

}  // namespace
}  // namespace overtake::sim
