// Calm traffic (ours): placement and re-placement around the ego, safety, MOBIL and the
// ego, determinism and the lap wrap.

#include "overtake/sim/calm_traffic.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "overtake/core/road.hpp"
#include "overtake/core/units.hpp"
#include "sim/test_maps.hpp"

namespace overtake::sim {
namespace {

constexpr double kDt = 0.02;
constexpr double kSpeedTolMps = 1e-9;
constexpr double kCollisionCullM = 12.0;  // footprints farther apart along s cannot touch

bool sanitized() {
  const char* v = std::getenv("OVERTAKE_SANITIZED");
  return v != nullptr && std::string(v) == "1";
}

class TrafficTest : public ::testing::Test {
 protected:
  TrafficTest() : map_(test::circle_map()), line_(map_), chords_(map_) {}

  /// The ego at (s, d) driving along its lane at `speed_mps`.
  [[nodiscard]] EgoView ego_at(double s_m, double d_m, double speed_mps) const {
    EgoView e;
    e.frenet = {line_.wrap_s(s_m), d_m};
    e.body = {line_.to_cartesian(e.frenet), line_.frame(e.frenet.s_m).heading_rad, 4.7, 1.9};
    e.speed_mps = speed_mps;
    e.closest_waypoint = chords_.closest(e.body.center);
    e.map_frenet = chords_.to_frenet(e.body.center, e.closest_waypoint);
    return e;
  }

  [[nodiscard]] EgoView start_ego(double speed_mps = 0.0) const {
    const EgoParams e;
    return ego_at(e.start_s_m, e.start_d_m, speed_mps);
  }

  /// The ego driving along its lane at its speed.
  [[nodiscard]] EgoView advance(const EgoView& e) const {
    return ego_at(e.frenet.s_m + line_.s_rate(e.frenet, e.speed_mps) * kDt, e.frenet.d_m,
                  e.speed_mps);
  }

  /// A car on its lane centre without wander.
  [[nodiscard]] CalmCar car(double s_m, int lane, double speed_mps, double cruise_mps) const {
    CalmCar c;
    c.s_m = line_.wrap_s(s_m);
    c.lane = lane;
    c.d_m = core::lane_center_d(lane);
    c.speed_mps = speed_mps;
    c.cruise_mps = cruise_mps;
    return c;
  }

  [[nodiscard]] CalmTraffic traffic(std::uint64_t seed, const TrafficParams& params,
                                    const core::RoadParams& road) const {
    return CalmTraffic(map_, line_, chords_, params, road, car_, seed);
  }

  /// s of waypoint `i`, any integer, around the loop.
  [[nodiscard]] double waypoint_s(long i) const {
    const auto n = static_cast<long>(map_.waypoints.size());
    return map_.waypoints[static_cast<std::size_t>(((i % n) + n) % n)].s_m;
  }

  /// Index of the first waypoint strictly ahead of s.
  [[nodiscard]] long next_waypoint(double s) const {
    const auto& w = map_.waypoints;
    for (std::size_t i = 0; i < w.size(); ++i) {
      if (w[i].s_m > s) return static_cast<long>(i);
    }
    return 0;
  }

  /// Pairs of traffic cars whose footprints overlap now.
  [[nodiscard]] int overlaps(const CalmTraffic& t) const {
    const auto& cars = t.cars();
    int count = 0;
    for (std::size_t i = 0; i < cars.size(); ++i) {
      for (std::size_t j = i + 1; j < cars.size(); ++j) {
        if (core::distance(cars[i].position, cars[j].position) > kCollisionCullM) continue;
        if (core::boxes_overlap(box(cars[i]), box(cars[j]))) ++count;
      }
    }
    return count;
  }

  [[nodiscard]] core::OrientedBox box(const TrafficCar& c) const {
    return {c.position, c.heading_rad, car_.length_m, car_.width_m};
  }

  core::Map map_;
  core::ReferenceLine line_;
  core::WaypointFrenet chords_;
  TrafficParams params_;
  core::RoadParams road_;
  core::CarFootprint car_;
};

TEST(TrafficProfileNames, RoundTrip) {
  for (const TrafficProfile p : {TrafficProfile::faithful, TrafficProfile::calm}) {
    EXPECT_EQ(parse_traffic_profile(to_string(p)), p);
  }
  EXPECT_FALSE(parse_traffic_profile("wild").has_value());
  EXPECT_FALSE(parse_traffic_profile("").has_value());
}

// 1. Initial placement: twelve cars, apart, in the two regions with their speed ranges,
// none behind the ego in its lane.
TEST_F(TrafficTest, InitialPlacementFollowsTheSpawnRule) {
  const EgoView ego = start_ego();
  const PlacementParams& pl = params_.placement;
  const long prev = (next_waypoint(ego.frenet.s_m) + static_cast<long>(map_.waypoints.size()) - 1) %
                    static_cast<long>(map_.waypoints.size());
  const double ahead_lo = line_.s_ahead(ego.frenet.s_m, waypoint_s(prev + pl.ahead_min_waypoints));
  const double ahead_hi = line_.s_ahead(ego.frenet.s_m, waypoint_s(prev + pl.ahead_max_waypoints));
  const double behind_lo =
      line_.s_ahead(ego.frenet.s_m, waypoint_s(prev - pl.behind_max_waypoints));
  const double behind_hi =
      line_.s_ahead(ego.frenet.s_m, waypoint_s(prev - pl.behind_min_waypoints));
  const int ego_lane = core::lane_of(ego.frenet.d_m);
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    CalmTraffic t = traffic(seed, params_, road_);
    t.start(ego);
    const auto& cars = t.calm_cars();
    ASSERT_EQ(cars.size(), 12u);
    for (std::size_t i = 0; i < cars.size(); ++i) {
      const CalmCar& c = cars[i];
      EXPECT_EQ(t.cars()[i].id, static_cast<int>(i));
      const core::Vec2 pos = t.cars()[i].position;
      EXPECT_GE(core::distance(pos, ego.body.center), pl.min_spawn_distance_m);
      for (std::size_t j = i + 1; j < cars.size(); ++j) {
        EXPECT_GE(core::distance(pos, t.cars()[j].position), pl.min_spawn_distance_m)
            << "cars " << i << " and " << j;
      }
      EXPECT_EQ(core::lane_of(c.d_m), c.lane);
      EXPECT_LE(std::abs(c.d_m - core::lane_center_d(c.lane)),
                params_.calm.wander_amplitude_m + 1e-9);
      EXPECT_EQ(c.speed_mps, c.cruise_mps);
      EXPECT_FALSE(c.manoeuvre.has_value());
      const double off = line_.s_ahead(ego.frenet.s_m, c.s_m);
      if (off > 0.0) {
        EXPECT_GE(off, ahead_lo - 1e-9);
        EXPECT_LE(off, ahead_hi + 1e-9);
        EXPECT_GE(c.cruise_mps, core::mph_to_mps(40.0) - kSpeedTolMps);
        EXPECT_LE(c.cruise_mps, core::mph_to_mps(50.0) + kSpeedTolMps);
      } else {
        EXPECT_GE(off, behind_lo - 1e-9);
        EXPECT_LE(off, behind_hi + 1e-9);
        EXPECT_GE(c.cruise_mps, core::mph_to_mps(50.0) - kSpeedTolMps);
        EXPECT_LE(c.cruise_mps, core::mph_to_mps(60.0) + kSpeedTolMps);
        EXPECT_NE(c.lane, ego_lane) << "behind the ego in its lane";
      }
    }
  }
}

// 2. A car farther than 200 m is placed again at the next batch; a batch places at most 3.
TEST_F(TrafficTest, FarCarsArePlacedAgainInBatches) {
  const PlacementParams& pl = params_.placement;
  for (const double ego_speed : {0.0, 20.0}) {
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
      SCOPED_TRACE("ego " + std::to_string(ego_speed) + " m/s, seed " + std::to_string(seed));
      EgoView ego = start_ego(ego_speed);
      CalmTraffic t = traffic(seed, params_, road_);
      t.start(ego);
      std::vector<CalmCar> cars = t.calm_cars();
      for (int k = 0; k < 5; ++k) {  // cars 0..4 far ahead, 300 m and beyond
        CalmCar& c = cars[static_cast<std::size_t>(k)];
        const core::Rng rng = c.rng;
        c = car(ego.frenet.s_m + 300.0 + 20.0 * k, k % 3, 20.0, 20.0);
        c.rng = rng;
      }
      t.set_cars(cars);
      int car0_back = -1;
      int max_batch = 0;
      for (int frame = 1; frame <= 400; ++frame) {
        std::vector<double> before;
        for (const CalmCar& c : t.calm_cars()) before.push_back(c.s_m);
        t.step(ego, kDt);
        ego = advance(ego);
        int jumped = 0;
        for (std::size_t i = 0; i < before.size(); ++i) {
          if (std::abs(line_.s_ahead(before[i], t.calm_cars()[i].s_m)) > 5.0) ++jumped;
        }
        max_batch = std::max(max_batch, jumped);
        if (car0_back < 0 &&
            std::abs(line_.s_ahead(ego.frenet.s_m, t.calm_cars()[0].s_m)) <= 200.0) {
          car0_back = frame;
        }
      }
      EXPECT_GT(car0_back, 0);
      EXPECT_LE(car0_back, pl.batch_max_frames + 1);
      EXPECT_GE(max_batch, 1);
      EXPECT_LE(max_batch, pl.batch_max_cars);
      for (std::size_t i = 0; i < t.calm_cars().size(); ++i) {
        EXPECT_LE(std::abs(line_.s_ahead(ego.frenet.s_m, t.calm_cars()[i].s_m)),
                  pl.despawn_distance_m + 30.0)
            << "car " << i;
      }
    }
  }
}

// 3. The calm profile never collides with itself.
TEST_F(TrafficTest, CalmProfileNeverCollidesWithItself) {
  const int steps = sanitized() ? 15'000 : 90'000;  // 5 or 30 minutes
  EgoView ego = ego_at(EgoParams{}.start_s_m, core::lane_center_d(1), 21.0);
  CalmTraffic t = traffic(11, params_, road_);
  t.start(ego);
  int overlap_steps = 0;
  int lane_changes = 0;
  double min_speed = 1e9;
  for (int k = 0; k < steps; ++k) {
    t.step(ego, kDt);
    ego = advance(ego);
    for (const CalmCar& c : t.calm_cars()) {
      if (c.manoeuvre && c.manoeuvre->elapsed_s <= kDt + 1e-12) ++lane_changes;
      min_speed = std::min(min_speed, c.speed_mps);
    }
    const int o = overlaps(t);
    if (o > 0) {
      ++overlap_steps;
      ADD_FAILURE() << "overlap at step " << k;
      if (overlap_steps > 5) break;
    }
  }
  EXPECT_EQ(overlap_steps, 0);
  EXPECT_GT(lane_changes, 0);
  std::cout << "[ calm     ] " << steps << " steps: " << lane_changes << " lane changes, "
            << overlap_steps << " steps with overlaps, min speed " << min_speed << " m/s\n";
  RecordProperty("calm_lane_changes", lane_changes);
}

// Calm: MOBIL counts the ego as the new follower. A car held up by a slow car does not
// move in 8 m ahead of the ego; with the ego 60 m back it does.
TEST_F(TrafficTest, CalmCarDoesNotCutInCloseAheadOfTheEgo) {
  core::RoadParams two_lanes;
  two_lanes.lane_count = 2;
  const double s0 = 2000.0;
  TrafficParams selfish = params_;
  selfish.calm.politeness = 0.0;  // else the slow car politely moves over itself
  CalmTraffic t = traffic(9, selfish, two_lanes);
  t.set_cars({car(s0, 1, 20.0, 25.0), car(s0 + 30.0, 1, 12.0, 12.0)});
  auto ego_behind = [&](double back_m) {
    const CalmCar& a = t.calm_cars()[0];
    return ego_at(a.s_m - back_m, core::lane_center_d(0), a.speed_mps);
  };
  for (int k = 0; k < 500; ++k) {  // 10 s
    t.step(ego_behind(8.0), kDt);
    ASSERT_FALSE(t.calm_cars()[0].manoeuvre.has_value()) << "cut in on the ego at step " << k;
  }
  EXPECT_TRUE(t.calm_cars()[0].held_up);
  int started = -1;
  for (int k = 0; k < 500 && started < 0; ++k) {
    t.step(ego_behind(60.0), kDt);
    if (t.calm_cars()[0].manoeuvre) started = k;
  }
  ASSERT_GE(started, 0);
  EXPECT_EQ(t.calm_cars()[0].manoeuvre->to_lane, 0);
}

// 4. Same seed, same states bit for bit; another seed differs.
TEST_F(TrafficTest, SameSeedSameTraffic) {
  auto run = [&](std::uint64_t seed) {
    EgoView ego = ego_at(EgoParams{}.start_s_m, core::lane_center_d(1), 18.0);
    CalmTraffic t = traffic(seed, params_, road_);
    t.start(ego);
    for (int k = 0; k < 3000; ++k) {
      t.step(ego, kDt);
      ego = advance(ego);
    }
    return t.calm_cars();
  };
  const auto a = run(42);
  const auto b = run(42);
  const auto c = run(43);
  ASSERT_EQ(a.size(), b.size());
  bool differs = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].s_m, b[i].s_m);
    EXPECT_EQ(a[i].d_m, b[i].d_m);
    EXPECT_EQ(a[i].speed_mps, b[i].speed_mps);
    EXPECT_EQ(a[i].d_rate_mps, b[i].d_rate_mps);
    EXPECT_EQ(a[i].cruise_mps, b[i].cruise_mps);
    EXPECT_EQ(a[i].lane, b[i].lane);
    EXPECT_EQ(a[i].manoeuvre.has_value(), b[i].manoeuvre.has_value());
    EXPECT_EQ(a[i].wander_phase_rad, b[i].wander_phase_rad);
    if (a[i].s_m != c[i].s_m || a[i].d_m != c[i].d_m || a[i].speed_mps != c[i].speed_mps) {
      differs = true;
    }
  }
  EXPECT_TRUE(differs);
}

// 5. Across the end of the loop, s wraps and stays continuous.
TEST_F(TrafficTest, CarCrossesTheLapWrap) {
  const double end = line_.start_s_m() + line_.length_m();
  EgoView ego = ego_at(end - 40.0, core::lane_center_d(1), 20.0);
  CalmTraffic t = traffic(5, params_, road_);
  t.set_cars({car(end - 5.0, 1, 20.0, 20.0)});
  CalmCar prev = t.calm_cars()[0];
  core::Vec2 prev_pos = t.cars()[0].position;
  bool wrapped = false;
  for (int k = 0; k < 100; ++k) {
    t.step(ego, kDt);
    ego = advance(ego);
    const CalmCar& c = t.calm_cars()[0];
    EXPECT_GE(c.s_m, line_.start_s_m());
    EXPECT_LT(c.s_m, end);
    const double ds = line_.s_ahead(prev.s_m, c.s_m);
    EXPECT_GT(ds, 0.0);
    EXPECT_NEAR(ds, 20.0 * kDt, 0.02);
    EXPECT_NEAR(core::distance(prev_pos, t.cars()[0].position), 20.0 * kDt, 0.01);
    if (c.s_m < prev.s_m) wrapped = true;
    prev = c;
    prev_pos = t.cars()[0].position;
  }
  EXPECT_TRUE(wrapped);
  EXPECT_NEAR(prev.s_m, line_.start_s_m() + 35.0, 0.5);
}

// Bodies follow the car's motion; s and d are reported as the original measures them.
TEST_F(TrafficTest, BodiesMatchTheCarsMotion) {
  CalmTraffic t = traffic(1, params_, road_);
  CalmCar c = car(1000.0, 2, 20.0, 20.0);
  c.d_rate_mps = 0.0;
  t.set_cars({c});
  const TrafficCar& b = t.cars()[0];
  const core::RoadFrame f = line_.frame(1000.0);
  EXPECT_NEAR(core::norm(b.reported_velocity_mps), 20.0, 1e-9);
  EXPECT_NEAR(core::dot(b.reported_velocity_mps, f.tangent), 20.0, 1e-9);
  EXPECT_NEAR(core::distance(b.position, f.position + core::lane_center_d(2) * f.normal), 0.0,
              1e-9);
  EXPECT_NEAR(core::wrap_angle_rad(b.heading_rad - f.heading_rad), 0.0, 1e-9);
  const core::FrenetPoint chord = chords_.to_frenet(b.position);
  EXPECT_DOUBLE_EQ(b.map_frenet.s_m, chord.s_m);
  EXPECT_DOUBLE_EQ(b.map_frenet.d_m, chord.d_m);
  // Standing still: the road's heading.
  c.speed_mps = 0.0;
  t.set_cars({c});
  EXPECT_NEAR(core::wrap_angle_rad(t.cars()[0].heading_rad - f.heading_rad), 0.0, 1e-9);
}

}  // namespace
}  // namespace overtake::sim
