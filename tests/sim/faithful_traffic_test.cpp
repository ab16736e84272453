// Faithful traffic: each of the original's rules (docs/fidelity.md), one test or more each.

#include "overtake/sim/faithful_traffic.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>
#include <vector>

#include "overtake/core/road.hpp"
#include "overtake/core/state_archive.hpp"
#include "overtake/core/units.hpp"
#include "sim/test_maps.hpp"

namespace overtake::sim {
namespace {

constexpr double kDt = 0.02;

class FaithfulTest : public ::testing::Test {
 protected:
  explicit FaithfulTest(core::Map map = test::stadium_map())
      : map_(std::move(map)), line_(map_), chords_(map_) {}

  /// The ego standing or driving at chord (s, d), facing along the road.
  [[nodiscard]] EgoView ego_at(double s_m, double d_m, double speed_mps = 0.0) const {
    EgoView e;
    const core::Vec2 at = chords_.to_cartesian({s_m, d_m});
    e.body = {at, chords_.chord_heading_rad(s_m), 4.7, 1.9};
    e.speed_mps = speed_mps;
    e.closest_waypoint = chords_.closest(at);
    e.map_frenet = chords_.to_frenet(at, e.closest_waypoint);
    e.frenet = line_.to_frenet(at, line_.wrap_s(s_m));
    return e;
  }

  /// An ego far away from everything (traffic meets no ego).
  [[nodiscard]] EgoView ego_far(double s_m) const { return ego_at(s_m, 6.0); }

  /// Traffic with `cars` cars, all parked, batches held (tests place cars themselves).
  [[nodiscard]] FaithfulTraffic held(int cars, std::uint64_t seed = 1,
                                     const TrafficParams& p = TrafficParams{}) const {
    TrafficParams q = p;
    q.car_count = cars;
    FaithfulTraffic t(chords_, line_, q, road_, car_, seed);
    t.start(ego_far(0.0));
    t.hold_batches_for_testing();
    return t;
  }

  /// Bumper-to-bumper gap from car i's front to the ego's rear along the road.
  [[nodiscard]] double gap_to(const FaithfulTraffic& t, std::size_t i, const EgoView& ego) const {
    return ego.map_frenet.s_m - t.cars()[i].map_frenet.s_m - 4.7;
  }

  core::Map map_;
  core::ReferenceLine line_;
  core::WaypointFrenet chords_;
  core::RoadParams road_;
  core::CarFootprint car_;
  FaithfulTrafficParams f_;
};

/// The steady speed of the speed law at a throttle wander w: cap * K / (K + drag).
double steady_ratio(const FaithfulTrafficParams& f, double wander) {
  const double k = f.accel_sensitivity_per_mph * core::kMphPerMps * f.engine_mps2 * wander;
  return k / (k + f.drag_per_s);
}

// --- the smooth noise of the wander ------------------------------------------------------

TEST(SmoothNoise, StaysInTheUnitRangeAndMovesSmoothly) {
  SmoothNoise n(7);
  double prev = n.at(0.0);
  double lo = 1.0;
  double hi = 0.0;
  for (int i = 1; i < 100000; ++i) {
    const double v = n.at(i * 0.002);
    EXPECT_GE(v, 0.0);
    EXPECT_LE(v, 1.0);
    EXPECT_LT(std::abs(v - prev), 0.01);  // no jumps at lattice points
    lo = std::min(lo, v);
    hi = std::max(hi, v);
    prev = v;
  }
  EXPECT_LT(lo, 0.3);
  EXPECT_GT(hi, 0.7);
  SmoothNoise again(7);
  EXPECT_EQ(again.at(123.4), SmoothNoise(7).at(123.4));
}

// A checkpoint's lattice cell is bounded: from a cell far behind, the next sample would draw
// once per cell passed (a state made to hang a restore).
TEST(SmoothNoise, ACheckpointRestoresTheSignalAndRefusesACellOutOfRange) {
  SmoothNoise n(7);
  (void)n.at(1234.5);
  core::StateArchive out;
  n.archive(out, 2000);
  const std::string bytes = out.take();
  SmoothNoise back(1);
  core::StateArchive in(bytes, "noise");
  back.archive(in, 2000);
  EXPECT_EQ(back.at(1300.25), n.at(1300.25));
  SmoothNoise tight(1);
  core::StateArchive small(bytes, "noise");
  try {
    tight.archive(small, 1000);
    FAIL() << "a cell beyond the bound restored";
  } catch (const core::StateError& e) {
    EXPECT_NE(std::string(e.what()).find("noise cell: 1234 is outside [0, 1000]"),
              std::string::npos)
        << e.what();
  }
}

// --- start and placement -----------------------------------------------------------------

TEST_F(FaithfulTest, EveryCarStartsParkedOffTheRoadAndTheFirstFramePlacesOneToThree) {
  std::set<int> first_batches;
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    FaithfulTraffic t(chords_, line_, TrafficParams{}, road_, car_, seed);
    const EgoView ego = ego_at(124.8336, 6.164833);
    t.start(ego);
    for (const TrafficCar& c : t.cars()) {
      EXPECT_TRUE(c.parked);
      EXPECT_EQ(c.speed_mps, 0.0);
      EXPECT_EQ(c.reported_velocity_mps, core::Vec2{});
      EXPECT_LT(c.map_frenet.d_m, -100.0) << "car " << c.id;  // far on the divider's side
      EXPECT_GT(core::distance(c.position, ego.body.center), 200.0);
    }
    t.step(ego, kDt);
    int placed = 0;
    for (const TrafficCar& c : t.cars()) placed += c.parked ? 0 : 1;
    first_batches.insert(placed);
    EXPECT_GE(placed, 1);
    EXPECT_LE(placed, 3);
  }
  EXPECT_GE(first_batches.size(), 2u);  // the batch size is drawn
}

TEST_F(FaithfulTest, PlacedExactlyOnAWaypointBehindOrAheadWithItsCapAsTheFirstVelocity) {
  const PlacementParams pl;
  int behind = 0;
  int ahead = 0;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    FaithfulTraffic t(chords_, line_, TrafficParams{}, road_, car_, seed);
    const EgoView ego = ego_at(400.0, 6.0);
    t.start(ego);
    t.step(ego, kDt);
    for (std::size_t i = 0; i < t.cars().size(); ++i) {
      const TrafficCar& c = t.cars()[i];
      if (c.parked) continue;
      // On a waypoint's lane point, at offset -3..-2 or 4..5 from the ego's closest waypoint.
      bool on_spot = false;
      for (int off : {-3, -2, 4, 5}) {
        const std::size_t wp = chords_.wrap_index(static_cast<long>(ego.closest_waypoint) + off);
        if (core::distance(c.position, chords_.offset_point(wp, core::lane_center_d(c.lane))) <
            1e-9) {
          on_spot = true;
          const double cap = t.drivers()[i].cap_mps;
          if (off < 0) {
            ++behind;
            EXPECT_GE(cap, pl.behind_min_speed_mps);
            EXPECT_LE(cap, pl.behind_max_speed_mps);
          } else {
            ++ahead;
            EXPECT_GE(cap, pl.ahead_min_speed_mps);
            EXPECT_LE(cap, pl.ahead_max_speed_mps);
          }
          // The first frame reports the cap read as m/s (2.237 times too fast), along the road.
          EXPECT_NEAR(core::norm(c.reported_velocity_mps), core::mps_to_mph(cap), 1e-9);
          EXPECT_GT(core::dot(c.reported_velocity_mps, chords_.forward(wp)),
                    0.99 * core::mps_to_mph(cap));
        }
      }
      EXPECT_TRUE(on_spot) << "car " << i << " seed " << seed;
    }
    // The next step clamps it to the cap.
    t.step(ego, kDt);
    for (std::size_t i = 0; i < t.cars().size(); ++i) {
      if (t.cars()[i].parked) continue;
      EXPECT_LE(t.cars()[i].speed_mps, t.drivers()[i].cap_mps + 1e-12);
      EXPECT_LE(core::norm(t.cars()[i].reported_velocity_mps), t.drivers()[i].cap_mps + 1e-12);
    }
  }
  EXPECT_GT(behind, 5);
  EXPECT_GT(ahead, 5);
}

TEST_F(FaithfulTest, NoSpotWithin6MetresOfAnotherCar) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    FaithfulTraffic t(chords_, line_, TrafficParams{}, road_, car_, seed);
    EgoView ego = ego_at(400.0, 6.0);
    t.start(ego);
    for (int k = 0; k < 1500; ++k) {  // 30 s: every car placed
      t.step(ego, kDt);
      for (std::size_t i = 0; i < t.cars().size(); ++i) {
        if (!t.drivers()[i].fresh) continue;
        for (std::size_t j = 0; j < t.cars().size(); ++j) {
          if (j == i) continue;
          EXPECT_GE(core::distance(t.cars()[i].position, t.cars()[j].position), 6.0 - 1.0)
              << "a car placed on top of another";
        }
      }
    }
    int parked = 0;
    for (const TrafficCar& c : t.cars()) parked += c.parked ? 1 : 0;
    EXPECT_EQ(parked, 0);
  }
}

class FaithfulTightCircle : public FaithfulTest {
 protected:
  FaithfulTightCircle() : FaithfulTest(test::circle_map(150.0, 15.0)) {}
};

TEST_F(FaithfulTightCircle, ReplacementGoesByStraightLineDistance) {
  // On a 150 m circle, in the middle lane (radius 156 m), 204 m of s (212 m along the lane)
  // is 196 m in a straight line: not re-placed. 240 m of s is 224 m straight: re-placed at
  // the next batch.
  for (const double along : {204.0, 240.0}) {
    FaithfulTraffic t(chords_, line_, TrafficParams{}, road_, car_, 3);
    const EgoView ego = ego_at(100.0, 6.0);
    t.start(ego);
    t.step(ego, kDt);  // the first batch
    for (std::size_t i = 0; i < t.cars().size(); ++i) {
      t.put_on_road_for_testing(i, 100.0 + along + 10.0 * static_cast<double>(i), 1, 0.0, 0.0);
    }
    const core::Vec2 before = t.cars()[0].position;
    ASSERT_EQ(core::distance(before, ego.body.center) > 200.0, along > 220.0);
    for (int k = 0; k < 62; ++k) t.step(ego, kDt);  // at least one batch
    const bool moved = core::distance(t.cars()[0].position, before) > 1.0;
    EXPECT_EQ(moved, along > 220.0) << along << " m along the road";
  }
}

// --- the speed law -----------------------------------------------------------------------

TEST_F(FaithfulTest, AFreeCarSettlesWellBelowItsCap) {
  FaithfulTraffic t = held(1, 5);
  const double cap = core::mph_to_mps(55.0);
  t.put_on_road_for_testing(0, 3000.0, 2, cap, cap);
  const EgoView ego = ego_far(2000.0);
  double lo = 1e9;
  double hi = 0.0;
  for (int k = 0; k < 90 * 50; ++k) {  // 90 s
    t.step(ego, kDt);
    if (k > 30 * 50) {
      lo = std::min(lo, t.cars()[0].speed_mps);
      hi = std::max(hi, t.cars()[0].speed_mps);
    }
  }
  // Between the steady speeds of the throttle wander's ends (0.9 and 1.0), with a little
  // room for the lag; the drawn cap itself is never reached.
  EXPECT_GT(lo, steady_ratio(f_, 0.9) * cap - 0.3);
  EXPECT_LT(hi, steady_ratio(f_, 1.0) * cap + 0.3);
  EXPECT_LT(hi, 0.9 * cap);
}

// --- following ---------------------------------------------------------------------------

TEST_F(FaithfulTest, AFollowerInsideItsReactionDistanceBrakesTowardPoint45OfTheLeader) {
  TrafficParams no_changes;
  no_changes.faithful.clear_steps = 1000000;  // held up, it would move over after a second
  FaithfulTraffic t = held(1, 1, no_changes);
  const double cap = core::mph_to_mps(50.0);
  // The ego (the body ahead) at 10 m/s; the follower 5 m behind its bumper, at 10 m/s.
  double ego_s = 500.0;
  t.put_on_road_for_testing(0, ego_s - 4.7 - 5.0, 1, 10.0, cap);
  EgoView ego = ego_at(ego_s, 6.0, 10.0);
  double min_speed = 1e9;
  bool surged = false;
  for (int k = 0; k < 15 * 50; ++k) {
    t.step(ego, kDt);
    const FaithfulTraffic::Driver& d = t.drivers()[0];
    if (d.reacting) {
      ASSERT_EQ(d.sight, SightKind::ego);
      // Reaction distance 0.5 * (50 - 10) = 20 m; the desired speed is 10 "mph".
      EXPECT_NEAR(d.desired_mph, 10.0, 1e-9);
      EXPECT_LT(d.sight_distance_m, 20.0);
      min_speed = std::min(min_speed, t.cars()[0].speed_mps);
    } else if (min_speed < 5.0 && t.cars()[0].speed_mps > 8.0) {
      surged = true;
    }
    ego_s += 10.0 * kDt;
    ego = ego_at(ego_s, 6.0, 10.0);
  }
  // It brakes towards 10 mph (0.45 of 10 m/s); below that target the throttle's pull against
  // drag settles it a little lower still.
  EXPECT_LT(min_speed, core::mph_to_mps(10.0) + 0.1);
  EXPECT_GT(min_speed, steady_ratio(f_, 0.9) * core::mph_to_mps(10.0) - 0.2);
  EXPECT_TRUE(surged);  // out of the reaction distance it speeds up again
}

TEST_F(FaithfulTest, TheReactionDistanceIsUnclampedAndBumperToBumper) {
  // A stopped ego, a follower with a 60 mph cap: 0.5 * (60 - 0) = 30 m.
  for (const double gap : {29.0, 31.0}) {
    FaithfulTraffic t = held(1);
    const double ego_s = 1000.0;
    t.put_on_road_for_testing(0, ego_s - 4.7 - gap, 1, 5.0, core::mph_to_mps(60.0));
    const EgoView ego = ego_at(ego_s, 6.0, 0.0);
    t.step(ego, kDt);
    const FaithfulTraffic::Driver& d = t.drivers()[0];
    EXPECT_EQ(d.sight, SightKind::ego);
    EXPECT_NEAR(d.sight_distance_m, gap, 0.05);
    EXPECT_EQ(d.reacting, gap < 30.0) << gap;
  }
  // A slow follower (40 mph cap) behind a car going 20 m/s: 0.5 * (40 - 20) = 10 m.
  FaithfulTraffic t = held(2);
  t.put_on_road_for_testing(1, 1000.0, 1, 20.0, 20.0);
  t.put_on_road_for_testing(0, 1000.0 - 4.7 - 12.0, 1, 17.0, core::mph_to_mps(40.0));
  t.step(ego_far(5000.0), kDt);
  EXPECT_EQ(t.drivers()[0].sight, SightKind::car);
  EXPECT_FALSE(t.drivers()[0].reacting);
}

TEST_F(FaithfulTest, ARayThatMeetsNothingReadsZeroAndRunsTheLaneChangeLogic) {
  // Alone on a long straight: the ray meets nothing; the car reacts (distance 0 < 10 m)
  // without braking, and changes lane now and then although nothing holds it up.
  FaithfulTraffic t = held(1);
  t.put_on_road_for_testing(0, 100.0, 0, 20.0, core::mph_to_mps(50.0));
  const EgoView ego = ego_far(3500.0);
  int changes = 0;
  int lane = 0;
  for (int k = 0; k < 40 * 50; ++k) {
    t.step(ego, kDt);
    const double s = t.cars()[0].map_frenet.s_m;
    if (s > 1200.0) break;  // the straight is 1500 m long; the ray sees 250 m
    const FaithfulTraffic::Driver& d = t.drivers()[0];
    EXPECT_EQ(d.sight, SightKind::nothing);
    EXPECT_TRUE(d.reacting);
    EXPECT_NEAR(d.desired_mph, 50.0, 1e-9);
    if (t.cars()[0].lane != lane) {
      ++changes;
      lane = t.cars()[0].lane;
    }
  }
  EXPECT_GE(changes, 1);
}

TEST_F(FaithfulTest, OnABendTheRayMeetsSceneryAndTheCarDoesNotReact) {
  FaithfulTraffic t = held(1);
  // The first bend of the stadium (radius 300 m) starts at s = 1500.
  t.put_on_road_for_testing(0, 1650.0, 1, 20.0, core::mph_to_mps(50.0));
  t.step(ego_far(3500.0), kDt);
  EXPECT_EQ(t.drivers()[0].sight, SightKind::scenery);
  EXPECT_FALSE(t.drivers()[0].reacting);
}

// --- lane changes ------------------------------------------------------------------------

TEST_F(FaithfulTest, ALaneChangeNeedsMoreThan50CountedClearStepsNearWaypoints) {
  FaithfulTraffic t = held(1);
  t.put_on_road_for_testing(0, 100.0, 0, 20.0, core::mph_to_mps(50.0));
  const EgoView ego = ego_far(3500.0);
  int counted = 0;
  int last_count = 0;
  for (int k = 0; k < 20 * 50; ++k) {
    const std::size_t next = chords_.next(t.cars()[0].position, t.cars()[0].closest_waypoint);
    const bool near = core::distance(chords_.position(next), t.cars()[0].position) < 15.0;
    t.step(ego, kDt);
    const FaithfulTraffic::Driver& d = t.drivers()[0];
    if (t.cars()[0].lane == 1) {
      // Changed: after the 51st counted step, and the counter starts again (this step
      // counted, as the original counts it in the same update).
      EXPECT_EQ(counted + 1, 51);
      EXPECT_EQ(d.lane_change_time, 1);
      return;
    }
    if (near) {
      ++counted;
      EXPECT_EQ(d.clear_counts[1], last_count + 1) << "step " << k;
    } else {
      EXPECT_EQ(d.clear_counts[1], last_count) << "counts only near a waypoint";
    }
    last_count = d.clear_counts[1];
  }
  FAIL() << "no lane change in 20 s";
}

TEST_F(FaithfulTest, ABlockedLaneResetsTheCountersAndFromTheMiddleBothSidesMustBeClear) {
  // Middle lane, nothing ahead; lane 2 holds a car right beside it (same s): every counted
  // step is blocked and resets the counters, so it never changes lane.
  FaithfulTraffic t = held(2);
  t.put_on_road_for_testing(0, 100.0, 1, 20.0, core::mph_to_mps(50.0));
  t.put_on_road_for_testing(1, 100.0, 2, 20.0, core::mph_to_mps(50.0));
  const EgoView ego = ego_far(3500.0);
  for (int k = 0; k < 25 * 50; ++k) {
    t.step(ego, kDt);
    if (t.cars()[0].map_frenet.s_m > 1300.0) break;
    // The two cars hold the same speed law; keep car 1 abreast of car 0.
    t.put_on_road_for_testing(1, t.cars()[0].map_frenet.s_m, 2, t.cars()[0].speed_mps,
                              core::mph_to_mps(50.0));
    EXPECT_EQ(t.cars()[0].lane, 1) << "step " << k;
    EXPECT_EQ(t.drivers()[0].clear_counts[0], 0);
  }
  // Both sides clear: from the middle it goes to the divider's side (lane 0).
  FaithfulTraffic u = held(1);
  u.put_on_road_for_testing(0, 100.0, 1, 20.0, core::mph_to_mps(50.0));
  for (int k = 0; k < 25 * 50 && u.cars()[0].lane == 1; ++k) u.step(ego, kDt);
  EXPECT_EQ(u.cars()[0].lane, 0);
}

TEST_F(FaithfulTest, NoLaneChangeWithin100StepsOfTheLastOneOrBelow15Mph) {
  FaithfulTraffic t = held(1);
  t.put_on_road_for_testing(0, 100.0, 0, 20.0, core::mph_to_mps(50.0));
  const EgoView ego = ego_far(3500.0);
  int last_change = -1000;
  int lane = 0;
  for (int k = 0; k < 60 * 50; ++k) {
    t.step(ego, kDt);
    if (t.cars()[0].map_frenet.s_m > 1300.0) break;
    if (t.cars()[0].lane != lane) {
      EXPECT_GT(k - last_change, 100);
      last_change = k;
      lane = t.cars()[0].lane;
    }
  }
  // A crawling car never counts.
  FaithfulTraffic slow = held(1);
  slow.put_on_road_for_testing(0, 100.0, 0, 5.0, core::mph_to_mps(12.0));
  for (int k = 0; k < 20 * 50; ++k) slow.step(ego, kDt);
  EXPECT_EQ(slow.cars()[0].lane, 0);
  EXPECT_EQ(slow.drivers()[0].clear_counts[1], 0);
}

TEST_F(FaithfulTest, ALaneChangeSwitchesTheLaneAtOnceAndSteersOver) {
  FaithfulTraffic t = held(1);
  t.put_on_road_for_testing(0, 100.0, 0, 20.0, core::mph_to_mps(50.0));
  const EgoView ego = ego_far(3500.0);
  int switched = -1;
  double d_at_switch = 0.0;
  for (int k = 0; k < 20 * 50; ++k) {
    t.step(ego, kDt);
    if (switched < 0 && t.cars()[0].lane == 1) {
      switched = k;
      d_at_switch = t.cars()[0].map_frenet.d_m;
    }
    if (switched >= 0 && k == switched + 5 * 50) break;
  }
  ASSERT_GE(switched, 0);
  EXPECT_LT(d_at_switch, 3.0);                        // the index changed before the car moved over
  EXPECT_NEAR(t.cars()[0].map_frenet.d_m, 6.0, 0.6);  // 5 s later: in the new lane
}

// --- contact -----------------------------------------------------------------------------

TEST_F(FaithfulTest, AfterAContactTheCarBehindSlowsAndVeersAway) {
  FaithfulTraffic t = held(1);
  t.put_on_road_for_testing(0, 1000.0, 1, 20.0, core::mph_to_mps(50.0));
  const core::OrientedBox front{
      t.cars()[0].position +
          5.0 * core::Vec2{std::cos(t.cars()[0].heading_rad), std::sin(t.cars()[0].heading_rad)},
      t.cars()[0].heading_rad, 4.7, 1.9};
  t.on_contact(0, {}, 15.0, front);
  const FaithfulTraffic::Driver& d = t.drivers()[0];
  EXPECT_GT(d.avoid_until_s, t.time_s());
  EXPECT_EQ(d.avoid_slowdown, 0.5);
  EXPECT_NE(d.avoid_offset_m, 0.0);
  t.step(ego_far(3500.0), kDt);
  EXPECT_LT(t.drivers()[0].desired_mph, 0.5 * 50.0 + 1e-9);
  EXPECT_LT(t.drivers()[0].pedal, 0.0);
}

TEST_F(FaithfulTest, SameSeedSameTraffic) {
  const auto run = [&](std::uint64_t seed) {
    FaithfulTraffic t(chords_, line_, TrafficParams{}, road_, car_, seed);
    double s = 200.0;
    EgoView ego = ego_at(s, 6.0, 20.0);
    t.start(ego);
    for (int k = 0; k < 3000; ++k) {
      t.step(ego, kDt);
      s += 20.0 * kDt;
      ego = ego_at(s, 6.0, 20.0);
    }
    return t.cars();
  };
  const auto a = run(4);
  const auto b = run(4);
  const auto c = run(5);
  bool differs = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].position, b[i].position);
    EXPECT_EQ(a[i].speed_mps, b[i].speed_mps);
    EXPECT_EQ(a[i].heading_rad, b[i].heading_rad);
    EXPECT_EQ(a[i].lane, b[i].lane);
    if (!(a[i].position == c[i].position)) differs = true;
  }
  EXPECT_TRUE(differs);
}

}  // namespace
}  // namespace overtake::sim
