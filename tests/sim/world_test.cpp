// The world: the ego's perfect controller, telemetry contents and rounding, collisions.

#include <gtest/gtest.h>

#include <cmath>

#include "overtake/core/wire_number.hpp"
#include "overtake/sim/world.hpp"
#include "sim/test_maps.hpp"

namespace overtake::sim {
namespace {

class WorldTest : public ::testing::Test {
 protected:
  WorldTest() : map_(test::circle_map()), line_(map_) {}

  World make_world(int cars = 12, bool rounding = true, std::uint64_t seed = 1) {
    WorldParams p;
    p.traffic.car_count = cars;
    p.wire_rounding = rounding;
    return World(map_, line_, p, TrafficProfile::faithful, seed);
  }

  // n points along lane 1 from the ego, `spacing_m` apart.
  std::vector<core::Vec2> ahead(const World& w, int n, double spacing_m) const {
    std::vector<core::Vec2> out;
    for (int i = 1; i <= n; ++i) out.push_back(line_.to_cartesian({w.ego().frenet.s_m + spacing_m * i, 6.0}));
    return out;
  }

  core::Map map_;
  core::ReferenceLine line_;
};

TEST_F(WorldTest, EgoStartsAtRestInTheMiddleLane) {
  const World w = make_world();
  EXPECT_EQ(w.ego().speed_mps, 0.0);
  EXPECT_NEAR(w.ego().frenet.s_m, 124.8336, 1e-6);
  EXPECT_NEAR(w.ego().frenet.d_m, 6.164833, 1e-6);
  const core::Telemetry t = w.telemetry();
  EXPECT_TRUE(t.previous_path.empty());
  EXPECT_EQ(t.end_path, (core::FrenetPoint{0.0, 0.0}));
}

TEST_F(WorldTest, APathOfOnePointLeavesTheCarStanding) {
  World w = make_world(0);
  const core::Vec2 start = w.ego().position;
  w.apply_path(ahead(w, 1, 0.4));
  for (int i = 0; i < 10; ++i) w.step();
  EXPECT_EQ(w.ego().position, start);
  EXPECT_EQ(w.ego().speed_mps, 0.0);
  EXPECT_EQ(w.queue().size(), 1u);
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
  // Driving to the last point: with one point left the car stops.
  for (int i = 0; i < 10; ++i) w.step();
  EXPECT_EQ(w.ego().position, path[3]);
  EXPECT_EQ(w.ego().speed_mps, 0.0);
}

TEST_F(WorldTest, TelemetryReportsTheQueueAndItsEnd) {
  World w = make_world(0);
  const auto path = core::round_like_wire(ahead(w, 50, 0.4));
  w.apply_path(path);
  w.step();
  w.step();
  const core::Telemetry t = w.telemetry();
  ASSERT_EQ(t.previous_path.size(), 48u);
  const core::FrenetPoint end = line_.to_frenet(t.previous_path.back());
  EXPECT_NEAR(t.end_path.s_m, end.s_m, 1e-3);
  EXPECT_NEAR(t.end_path.d_m, end.d_m, 1e-3);
  // The speed of the last step: from the first point to the second, over 0.02 s.
  EXPECT_NEAR(core::mps_to_mph(t.ego.speed_mps), core::mps_to_mph(core::distance(path[0], path[1]) / 0.02),
              1e-4);
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

TEST_F(WorldTest, AllTwelveCarsAreReportedWithTheirTrueFrenetPosition) {
  World w = make_world();
  w.apply_path(ahead(w, 1000, 0.4));
  for (int step = 0; step < 1500; ++step) {
    w.step();
    if (step % 50 != 0) continue;
    const core::Telemetry t = w.telemetry();
    ASSERT_EQ(t.cars.size(), 12u);
    for (std::size_t i = 0; i < t.cars.size(); ++i) {
      const auto& c = t.cars[i];
      EXPECT_EQ(c.id, static_cast<int>(i));
      const core::FrenetPoint f = line_.to_frenet(c.position, c.s_m);
      EXPECT_LT(std::abs(line_.s_ahead(f.s_m, c.s_m)), 0.01) << "car " << i;
      EXPECT_NEAR(f.d_m, c.d_m, 0.01) << "car " << i;
    }
  }
}

TEST_F(WorldTest, CarsAcrossTheLapWrapReportWrappedS) {
  // Start the ego just before the end of the loop so that traffic straddles the wrap.
  WorldParams p;
  p.ego.start_s_m = line_.length_m() - 30.0;
  World w(map_, line_, p, TrafficProfile::faithful, 3);
  const core::Telemetry t = w.telemetry();
  bool some_after_wrap = false;
  for (const auto& c : t.cars) {
    EXPECT_GE(c.s_m, 0.0);
    EXPECT_LT(c.s_m, line_.length_m());
    if (c.s_m < 200.0) some_after_wrap = true;
    const core::FrenetPoint f = line_.to_frenet(c.position);
    EXPECT_LT(std::abs(line_.s_ahead(f.s_m, c.s_m)), 0.01);
  }
  EXPECT_TRUE(some_after_wrap);
}

TEST_F(WorldTest, DrivingIntoAParkedCarIsACollision) {
  World w = make_world(1);
  // Park the only car 20 m ahead in the ego's lane and drive through it.
  TrafficCar parked = w.traffic().cars()[0];
  parked.s_m = w.ego().frenet.s_m + 20.0;
  parked.d_m = 6.0;
  parked.speed_mps = 0.0;
  parked.cruise_mps = 0.0;
  parked.d_rate_mps = 0.0;
  parked.lane = 1;
  parked.wander_omega_rps = 0.0;
  parked.lane_offset_m = 0.0;
  w.traffic_for_testing().set_cars({parked});
  w.apply_path(ahead(w, 200, 0.3));
  for (int i = 0; i < 150; ++i) w.step();
  const auto counts = w.referee().counts();
  EXPECT_GE(counts[static_cast<std::size_t>(IncidentType::collision)], 1);
  EXPECT_EQ(w.referee().incidents().front().type, IncidentType::collision);
  EXPECT_EQ(w.referee().incidents().front().value, 0.0);  // the car's id
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
  EXPECT_NE(a.telemetry().cars, c.telemetry().cars);
}

}  // namespace
}  // namespace overtake::sim
