// Scripted scenarios in the world: start state, scripted cars and timed events.

#include <gtest/gtest.h>

#include "overtake/sim/calm_traffic.hpp"
#include "overtake/sim/world.hpp"
#include "sim/test_maps.hpp"

namespace overtake::sim {
namespace {

class ScenarioWorldTest : public ::testing::Test {
 protected:
  ScenarioWorldTest() : map_(test::circle_map()), line_(map_) {}
  core::Map map_;
  core::ReferenceLine line_;
};

TEST_F(ScenarioWorldTest, EgoStartsWhereAndAsFastAsTheScriptSays) {
  Scenario sc;
  sc.ego_s_m = 300.0;
  sc.ego_d_m = 2.0;
  sc.ego_speed_mps = 20.0;
  World w(map_, line_, WorldParams{}, sc);
  // As the original measures s and d (on the waypoint chords), to the centimetre.
  EXPECT_NEAR(w.ego().map_frenet.s_m, 300.0, 0.01);
  EXPECT_NEAR(w.ego().map_frenet.d_m, 2.0, 0.01);
  EXPECT_EQ(w.ego().speed_mps, 20.0);
  EXPECT_EQ(w.queue().size(), 50u);  // one second of path at that speed
  EXPECT_TRUE(w.traffic().cars().empty());
  for (int i = 0; i < 10; ++i) w.step();
  EXPECT_NEAR(w.ego().speed_mps, 20.0, 0.05);
}

/// A scripted car in its own (Frenet) coordinates.
const CalmCar& scripted(const World& w, std::size_t i) {
  return static_cast<const CalmTraffic&>(w.traffic().model()).calm_cars()[i];
}

TEST_F(ScenarioWorldTest, ScriptedCarsKeepLaneAndSpeedAndFollowEvents) {
  Scenario sc;
  sc.ego_s_m = 100.0;
  sc.cars = {{150.0, 0, 18.0}, {200.0, 2, 25.0}};
  sc.events = {{2.0, 0, ScenarioAction::change_lane, 1, 0.0, 0.0, 0.0},
               {1.0, 1, ScenarioAction::brake, 0, 0.0, 6.0, 2.0},
               {5.0, 1, ScenarioAction::set_speed, 0, 20.0, 2.0, 0.0}};
  std::stable_sort(sc.events.begin(), sc.events.end(),
                   [](const ScenarioEvent& a, const ScenarioEvent& b) { return a.t_s < b.t_s; });
  World w(map_, line_, WorldParams{}, sc);
  ASSERT_EQ(w.traffic().cars().size(), 2u);
  EXPECT_TRUE(w.traffic().scripted());
  auto run_to = [&](double t) {
    while (w.time_s() < t - 1e-9) w.step();
  };
  run_to(1.0);
  EXPECT_NEAR(w.traffic().cars()[0].speed_mps, 18.0, 1e-9);
  EXPECT_NEAR(scripted(w, 0).d_m, 2.0, 1e-9);  // no wander for scripted cars
  EXPECT_NEAR(w.traffic().cars()[1].speed_mps, 25.0, 1e-9);
  run_to(3.0);
  EXPECT_NEAR(w.traffic().cars()[1].speed_mps, 25.0 - 6.0 * 2.0, 0.07);  // braked for 2 s
  EXPECT_EQ(w.traffic().cars()[0].lane, 1);                              // changing since t = 2
  EXPECT_GT(scripted(w, 0).d_m, 2.0);
  run_to(4.9);
  EXPECT_NEAR(w.traffic().cars()[1].speed_mps, 13.0, 0.07);  // holds the speed it reached
  run_to(5.2);
  EXPECT_NEAR(scripted(w, 0).d_m, 6.0, 1e-9);  // arrived (a 3 s change from t = 2)
  run_to(9.5);
  EXPECT_NEAR(w.traffic().cars()[1].speed_mps, 20.0, 1e-9);  // 13 -> 20 at 2 m/s^2 by t = 8.5
}

TEST_F(ScenarioWorldTest, NoCarIsEverPlacedAgain) {
  Scenario sc;
  sc.ego_s_m = 100.0;
  sc.cars = {{900.0, 1, 10.0}};  // far beyond the 200 m that re-places random traffic
  World w(map_, line_, WorldParams{}, sc);
  for (int i = 0; i < 500; ++i) w.step();
  EXPECT_NEAR(scripted(w, 0).s_m, 900.0 + 10.0 * 10.0, 1.0);
}

}  // namespace
}  // namespace overtake::sim
