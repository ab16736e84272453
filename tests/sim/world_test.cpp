// The world: the start pose, the ego's perfect controller, telemetry contents (s and d as the
// original measures them) and rounding, contact between bodies.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "overtake/core/units.hpp"
#include "overtake/core/wire_number.hpp"
#include "overtake/sim/faithful_traffic.hpp"
#include "overtake/sim/scorecard.hpp"
#include "overtake/sim/world.hpp"
#include "sim/test_maps.hpp"

namespace overtake::sim {
namespace {

class WorldTest : public ::testing::Test {
 protected:
  WorldTest() : map_(test::circle_map()), line_(map_) {}

  World make_world(int cars = 12, bool rounding = true, std::uint64_t seed = 1,
                   TrafficProfile profile = TrafficProfile::faithful) {
    WorldParams p;
    p.traffic.car_count = cars;
    p.wire_rounding = rounding;
    return World(map_, line_, p, profile, seed);
  }

  // n points along lane 1 from the ego, `spacing_m` apart.
  std::vector<core::Vec2> ahead(const World& w, int n, double spacing_m) const {
    std::vector<core::Vec2> out;
    for (int i = 1; i <= n; ++i)
      out.push_back(line_.to_cartesian({w.ego().frenet.s_m + spacing_m * i, 6.0}));
    return out;
  }

  core::Map map_;
  core::ReferenceLine line_;
};

TEST_F(WorldTest, EgoStartsAtRestOnTheChordPointRoundedToCentimetres) {
  const World w = make_world();
  EXPECT_EQ(w.ego().speed_mps, 0.0);
  const core::Vec2 exact = w.chords().to_cartesian({124.8336, 6.164833});
  EXPECT_EQ(w.ego().position.x, std::round(exact.x * 100.0) / 100.0);
  EXPECT_EQ(w.ego().position.y, std::round(exact.y * 100.0) / 100.0);
  // The yaw is the chord's heading to a whole degree.
  const double yaw_deg = core::rad_to_deg(w.ego().yaw_rad);
  EXPECT_NEAR(yaw_deg, std::round(yaw_deg), 1e-9);
  EXPECT_NEAR(yaw_deg, core::rad_to_deg(w.chords().chord_heading_rad(124.8336)), 0.5);
  const core::Telemetry t = w.telemetry();
  EXPECT_NEAR(t.ego.s_m, 124.8336, 0.01);
  EXPECT_NEAR(t.ego.d_m, 6.164833, 0.01);
  EXPECT_TRUE(t.previous_path.empty());
  EXPECT_EQ(t.end_path, (core::FrenetPoint{0.0, 0.0}));
}

TEST(WorldStart, OnTheOriginalMapTheFirstTelemetryIsTheOriginals) {
  // The original sends x 909.48, y 1128.67, yaw 0, s 124.83, d 6.16 at the start.
  const core::Map map = test::original_start_map();
  const core::ReferenceLine line(map);
  const World w(map, line, WorldParams{}, TrafficProfile::faithful, 1);
  const core::Telemetry t = w.telemetry();
  EXPECT_EQ(t.ego.position.x, core::wire_round(909.48));
  EXPECT_EQ(t.ego.position.y, core::wire_round(1128.67));
  EXPECT_EQ(t.ego.yaw_rad, 0.0);
  EXPECT_NEAR(t.ego.s_m, 124.83, 0.005);
  EXPECT_NEAR(t.ego.d_m, 6.16, 0.005);
  EXPECT_EQ(t.ego.speed_mps, 0.0);
  // Every car waits parked off the road.
  for (const auto& c : t.cars) EXPECT_LT(c.d_m, -100.0);
}

TEST(WorldStart, TheDefaultTrackStartsHeadingAlongX) {
  const core::Map map = test::stadium_map();
  const core::ReferenceLine line(map);
  const World w(map, line, WorldParams{}, TrafficProfile::faithful, 1);
  EXPECT_EQ(w.telemetry().ego.yaw_rad, 0.0);
}

TEST_F(WorldTest, AWorldWithASharedOpenRoadTableIsTheWorldThatBuildsItsOwn) {
  const core::Map stadium = test::stadium_map();
  const core::ReferenceLine line(stadium);
  WorldParams p;
  const auto table = build_open_road_table(line, p.road, p.traffic.faithful);
  ASSERT_EQ(table->open.size(), static_cast<std::size_t>(p.road.lane_count) * table->bins);
  // On a stadium's bends a ray along a lane leaves the road; on its straights it does not.
  EXPECT_GT(std::count(table->open.begin(), table->open.end(), 0), 0);
  EXPECT_GT(std::count(table->open.begin(), table->open.end(), 1), 0);
  for (std::uint64_t seed : {1U, 7U}) {
    World own(stadium, line, p, TrafficProfile::faithful, seed);
    World shared(stadium, line, p, TrafficProfile::faithful, seed, table);
    for (int step = 0; step < 3000; ++step) {  // a minute, the ego standing
      own.step();
      shared.step();
    }
    EXPECT_EQ(own.telemetry(), shared.telemetry()) << "seed " << seed;
  }
}

TEST_F(WorldTest, WithOnePointLeftTheCarStaysAndThePointIsDropped) {
  World w = make_world(0);
  const core::Vec2 start = w.ego().position;
  w.apply_path(ahead(w, 1, 0.4));
  ASSERT_EQ(w.queue().size(), 1u);
  w.step();
  EXPECT_EQ(w.ego().position, start);
  EXPECT_EQ(w.ego().speed_mps, 0.0);
  EXPECT_TRUE(w.queue().empty());
  EXPECT_TRUE(w.telemetry().previous_path.empty());
}

TEST_F(WorldTest, EgoMovesOntoTheNextPointAndFacesTheOneAfter) {
  World w = make_world(0);
  const auto path = core::round_like_wire(ahead(w, 5, 0.4));
  const core::Vec2 start = w.ego().position;
  w.apply_path(path);
  w.step();
  EXPECT_EQ(w.ego().position, path[0]);
  EXPECT_NEAR(w.ego().speed_mps, core::distance(start, path[0]) / 0.02, 1e-9);
  EXPECT_NEAR(w.ego().yaw_rad, std::atan2(path[1].y - path[0].y, path[1].x - path[0].x), 1e-12);
  EXPECT_EQ(w.queue().size(), 4u);
  // Driving to the last point: with one point left the car stops, and the point goes.
  for (int i = 0; i < 10; ++i) w.step();
  EXPECT_EQ(w.ego().position, path[3]);
  EXPECT_EQ(w.ego().speed_mps, 0.0);
  EXPECT_TRUE(w.queue().empty());
}

TEST_F(WorldTest, TelemetryReportsTheQueueAndItsEndMeasuredFromTheEgosWaypoint) {
  World w = make_world(0);
  const auto path = core::round_like_wire(ahead(w, 50, 0.4));
  w.apply_path(path);
  w.step();
  w.step();
  const core::Telemetry t = w.telemetry();
  ASSERT_EQ(t.previous_path.size(), 48u);
  const core::FrenetPoint end = w.chords().to_frenet(w.queue().back(), w.ego().closest_waypoint);
  EXPECT_NEAR(t.end_path.s_m, end.s_m, 1e-3);
  EXPECT_NEAR(t.end_path.d_m, end.d_m, 1e-3);
  EXPECT_NEAR(t.ego.s_m, w.ego().map_frenet.s_m, 1e-3);
  EXPECT_NEAR(t.ego.d_m, w.ego().map_frenet.d_m, 1e-4);
  // The speed of the last step: from the first point to the second, over 0.02 s.
  EXPECT_NEAR(core::mps_to_mph(t.ego.speed_mps),
              core::mps_to_mph(core::distance(path[0], path[1]) / 0.02), 1e-4);
}

TEST_F(WorldTest, OnABendTheReportedDIsTheChordsNotTheCurves) {
  // A 150 m circle with waypoints 38 m apart: a car on its lane's true centre reads up to
  // L^2 / 8R = 1.2 m off it on the chords.
  const core::Map map = test::circle_map(150.0, 38.0);
  const core::ReferenceLine line(map);
  World w(map, line, WorldParams{}, TrafficProfile::faithful, 1);
  double worst = 0.0;
  for (double s = 0.0; s < 38.0; s += 1.0) {
    const core::Vec2 p = line.to_cartesian({s, 6.0});
    const core::FrenetPoint f = w.chords().to_frenet(p);
    worst = std::max(worst, std::abs(f.d_m - 6.0));
  }
  EXPECT_GT(worst, 0.9);
  EXPECT_LT(worst, 1.4);
}

TEST_F(WorldTest, EveryNumberIsRoundedLikeTheWireAndPathPointsToo) {
  World w = make_world();
  w.apply_path(ahead(w, 50, 0.41234567));
  for (int i = 0; i < 7; ++i) w.step();
  const core::Telemetry t = w.telemetry();
  auto rounded = [](double v) { return core::wire_round(v) == v; };
  EXPECT_TRUE(rounded(t.ego.position.x) && rounded(t.ego.position.y) && rounded(t.ego.s_m) &&
              rounded(t.ego.d_m));
  for (const auto& p : t.previous_path) EXPECT_TRUE(rounded(p.x) && rounded(p.y));
  for (const auto& c : t.cars) {
    EXPECT_TRUE(rounded(c.position.x) && rounded(c.position.y) && rounded(c.velocity_mps.x) &&
                rounded(c.velocity_mps.y) && rounded(c.s_m) && rounded(c.d_m));
  }
  // The car drives the rounded points.
  for (const auto& p : w.queue()) EXPECT_TRUE(rounded(p.x) && rounded(p.y));
}

TEST_F(WorldTest, AllTwelveCarsAreReportedWithTheOriginalsFrenetPosition) {
  for (const TrafficProfile profile : {TrafficProfile::faithful, TrafficProfile::calm}) {
    World w = make_world(12, false, 1, profile);
    w.apply_path(ahead(w, 1000, 0.4));
    for (int step = 0; step < 1500; ++step) {
      w.step();
      if (step % 50 != 0) continue;
      const core::Telemetry t = w.telemetry();
      ASSERT_EQ(t.cars.size(), 12u);
      for (std::size_t i = 0; i < t.cars.size(); ++i) {
        const auto& c = t.cars[i];
        EXPECT_EQ(c.id, static_cast<int>(i));
        const core::FrenetPoint f = w.chords().to_frenet(c.position);
        EXPECT_NEAR(f.s_m, c.s_m, 1e-6) << "car " << i;
        EXPECT_NEAR(f.d_m, c.d_m, 1e-6) << "car " << i;
      }
    }
  }
}

TEST_F(WorldTest, CarsAcrossTheLapWrapReportWrappedS) {
  // Start the ego just before the end of the loop so that traffic straddles the wrap.
  WorldParams p;
  p.ego.start_s_m = line_.length_m() - 30.0;
  World w(map_, line_, p, TrafficProfile::calm, 3);
  const core::Telemetry t = w.telemetry();
  bool some_after_wrap = false;
  for (const auto& c : t.cars) {
    EXPECT_GE(c.s_m, 0.0);
    EXPECT_LT(c.s_m, line_.length_m());
    if (c.s_m < 200.0) some_after_wrap = true;
  }
  EXPECT_TRUE(some_after_wrap);
}

TEST_F(WorldTest, DrivingIntoAStandingCarIsACollisionAndPushesItAhead) {
  World w = make_world(1);
  auto& traffic = static_cast<FaithfulTraffic&>(w.traffic_for_testing().model());
  traffic.hold_batches_for_testing();
  // A car standing (cap 0) 20 m ahead in the ego's lane; the ego drives at 15 m/s into it.
  traffic.put_on_road_for_testing(0, w.ego().map_frenet.s_m + 20.0, 1, 0.0, 0.0);
  w.apply_path(ahead(w, 200, 0.3));
  Scorecard card(w);
  for (int i = 0; i < 150; ++i) {
    w.step();
    card.observe_step(w);
    // Never inside each other after a step.
    const core::OrientedBox car = w.traffic().footprint(w.traffic().cars()[0]);
    const auto pen = core::box_penetration(w.ego_footprint(), car);
    EXPECT_TRUE(!pen || pen->depth_m < 1e-9) << "step " << i;
  }
  const auto counts = card.referee().counts();
  EXPECT_GE(counts[static_cast<std::size_t>(IncidentType::collision)], 1);
  const auto& incidents = card.referee().incidents();
  const auto hit = std::find_if(incidents.begin(), incidents.end(), [](const Incident& i) {
    return i.type == IncidentType::collision;
  });
  ASSERT_NE(hit, incidents.end());
  EXPECT_EQ(hit->value, 0.0);  // the car's id
  // The car is still ahead of the ego: pushed, not driven through.
  EXPECT_GT(w.traffic().cars()[0].map_frenet.s_m, w.ego().map_frenet.s_m);
}

TEST_F(WorldTest, AStoppedEgoIsTouchedAtMostOncePerContact) {
  // A fast car comes up behind an ego that has stopped; it cannot brake in time. It
  // touches the ego once, is pushed out, slows and keeps clear: one collision.
  World w = make_world(1);
  auto& traffic = static_cast<FaithfulTraffic&>(w.traffic_for_testing().model());
  traffic.hold_batches_for_testing();
  traffic.put_on_road_for_testing(0, w.ego().map_frenet.s_m - 4.7 - 32.0, 1, 26.0,
                                  core::mph_to_mps(60.0));
  int touching_episodes = 0;
  bool was = false;
  Scorecard card(w);
  for (int i = 0; i < 30 * 50; ++i) {
    w.step();
    card.observe_step(w);
    const core::OrientedBox car = w.traffic().footprint(w.traffic().cars()[0]);
    const bool now = core::distance(car.center, w.ego().position) < 4.7 + 0.05;
    if (now && !was) ++touching_episodes;
    was = now;
    EXPECT_LT(w.traffic().cars()[0].map_frenet.s_m, w.ego().map_frenet.s_m) << "step " << i;
  }
  EXPECT_EQ(touching_episodes, 1);
  EXPECT_EQ(card.referee().counts()[static_cast<std::size_t>(IncidentType::collision)], 1);
}

TEST_F(WorldTest, SameSeedSameWorld) {
  World a = make_world(12, true, 5);
  World b = make_world(12, true, 5);
  a.apply_path(ahead(a, 1000, 0.4));
  b.apply_path(ahead(b, 1000, 0.4));
  for (int i = 0; i < 2000; ++i) {
    a.step();
    b.step();
  }
  EXPECT_EQ(a.telemetry(), b.telemetry());
  World c = make_world(12, true, 6);
  c.apply_path(ahead(c, 1000, 0.4));
  for (int i = 0; i < 2000; ++i) c.step();
  EXPECT_NE(a.telemetry().cars, c.telemetry().cars);
}

}  // namespace
}  // namespace overtake::sim
