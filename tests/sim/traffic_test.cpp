// Traffic: placement and re-placement around the ego, faithful lane changes, the calm
// profile's safety, determinism and the lap wrap.

#include "overtake/sim/traffic.hpp"

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
  TrafficTest() : map_(test::circle_map()), line_(map_) {}

  [[nodiscard]] EgoView start_ego(double speed_mps = 0.0) const {
    const EgoParams e;
    return {line_.wrap_s(e.start_s_m), e.start_d_m, speed_mps};
  }

  /// The ego driving along its lane at its speed.
  [[nodiscard]] EgoView advance(EgoView e) const {
    e.s_m = line_.wrap_s(e.s_m + line_.s_rate({e.s_m, e.d_m}, e.speed_mps) * kDt);
    return e;
  }

  /// A car on its lane centre without wander.
  [[nodiscard]] TrafficCar car(double s_m, int lane, double speed_mps, double cruise_mps) const {
    TrafficCar c;
    c.s_m = line_.wrap_s(s_m);
    c.lane = lane;
    c.d_m = core::lane_center_d(lane);
    c.speed_mps = speed_mps;
    c.cruise_mps = cruise_mps;
    return c;
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

  [[nodiscard]] double to_next_waypoint(double s) const {
    double d = std::fmod(waypoint_s(next_waypoint(s)) - s, line_.length_m());
    if (d < 0.0) d += line_.length_m();
    return d;
  }

  /// Pairs of traffic cars whose footprints overlap now.
  [[nodiscard]] int overlaps(const Traffic& t) const {
    const auto& cars = t.cars();
    int count = 0;
    for (std::size_t i = 0; i < cars.size(); ++i) {
      for (std::size_t j = i + 1; j < cars.size(); ++j) {
        if (std::abs(line_.s_ahead(cars[i].s_m, cars[j].s_m)) > kCollisionCullM) continue;
        if (core::boxes_overlap(t.footprint(cars[i]), t.footprint(cars[j]))) ++count;
      }
    }
    return count;
  }

  core::Map map_;
  core::ReferenceLine line_;
  TrafficParams params_;
  core::RoadParams road_;
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
  const core::Vec2 ego_pos = line_.to_cartesian({ego.s_m, ego.d_m});
  const long prev = (next_waypoint(ego.s_m) + static_cast<long>(map_.waypoints.size()) - 1) %
                    static_cast<long>(map_.waypoints.size());
  const double ahead_lo = line_.s_ahead(ego.s_m, waypoint_s(prev + params_.ahead_min_waypoints));
  const double ahead_hi = line_.s_ahead(ego.s_m, waypoint_s(prev + params_.ahead_max_waypoints));
  const double behind_lo = line_.s_ahead(ego.s_m, waypoint_s(prev - params_.behind_max_waypoints));
  const double behind_hi = line_.s_ahead(ego.s_m, waypoint_s(prev - params_.behind_min_waypoints));
  const int ego_lane = core::lane_of(ego.d_m);
  for (const TrafficProfile profile : {TrafficProfile::faithful, TrafficProfile::calm}) {
    for (std::uint64_t seed = 1; seed <= 20; ++seed) {
      SCOPED_TRACE(std::string(to_string(profile)) + " seed " + std::to_string(seed));
      Traffic t(map_, line_, params_, road_, profile, seed);
      t.place_initial(ego);
      const auto& cars = t.cars();
      ASSERT_EQ(cars.size(), 12u);
      for (std::size_t i = 0; i < cars.size(); ++i) {
        const TrafficCar& c = cars[i];
        EXPECT_EQ(c.id, static_cast<int>(i));
        const core::Vec2 pos = t.observe(c).position;
        EXPECT_GE(core::distance(pos, ego_pos), params_.min_spawn_distance_m);
        for (std::size_t j = i + 1; j < cars.size(); ++j) {
          EXPECT_GE(core::distance(pos, t.observe(cars[j]).position), params_.min_spawn_distance_m)
              << "cars " << i << " and " << j;
        }
        EXPECT_EQ(core::lane_of(c.d_m), c.lane);
        EXPECT_LE(std::abs(c.d_m - core::lane_center_d(c.lane)), params_.wander_amplitude_m + 1e-9);
        EXPECT_EQ(c.speed_mps, c.cruise_mps);
        EXPECT_FALSE(c.manoeuvre.has_value());
        const double off = line_.s_ahead(ego.s_m, c.s_m);
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
}

// 2. A car farther than 200 m is placed again at the next batch; a batch places at most 3.
TEST_F(TrafficTest, FarCarsArePlacedAgainInBatches) {
  for (const double ego_speed : {0.0, 20.0}) {
    for (std::uint64_t seed = 1; seed <= 10; ++seed) {
      SCOPED_TRACE("ego " + std::to_string(ego_speed) + " m/s, seed " + std::to_string(seed));
      EgoView ego = start_ego(ego_speed);
      Traffic t(map_, line_, params_, road_, TrafficProfile::faithful, seed);
      t.place_initial(ego);
      std::vector<TrafficCar> cars = t.cars();
      for (int k = 0; k < 5; ++k) {  // cars 0..4 far ahead, 300 m and beyond
        TrafficCar& c = cars[static_cast<std::size_t>(k)];
        c = car(ego.s_m + 300.0 + 20.0 * k, k % 3, 20.0, 20.0);
        c.rng = t.cars()[static_cast<std::size_t>(k)].rng;
      }
      t.set_cars(cars);
      int car0_back = -1;
      int max_batch = 0;
      for (int frame = 1; frame <= 400; ++frame) {
        std::vector<double> before;
        for (const TrafficCar& c : t.cars()) before.push_back(c.s_m);
        t.step(ego, kDt);
        ego = advance(ego);
        int jumped = 0;
        for (std::size_t i = 0; i < before.size(); ++i) {
          if (std::abs(line_.s_ahead(before[i], t.cars()[i].s_m)) > 5.0) ++jumped;
        }
        max_batch = std::max(max_batch, jumped);
        if (car0_back < 0 && std::abs(line_.s_ahead(ego.s_m, t.cars()[0].s_m)) <= 200.0) {
          car0_back = frame;
        }
      }
      EXPECT_GT(car0_back, 0);
      EXPECT_LE(car0_back, params_.batch_max_frames + 1);
      EXPECT_GE(max_batch, 1);
      EXPECT_LE(max_batch, params_.batch_max_cars);
      for (const TrafficCar& c : t.cars()) {
        EXPECT_LE(std::abs(line_.s_ahead(ego.s_m, c.s_m)), params_.despawn_distance_m + 30.0)
            << "car " << c.id;
      }
    }
  }
}

// 3. Faithful: a blocked car changes lane only into a gap of more than 20 m that has held
// for more than 50 steps, and only near a waypoint.
TEST_F(TrafficTest, BlockedCarChangesLaneOnlyIntoAGapHeldForOneSecond) {
  const double s0 = waypoint_s(20) + 2.0;  // 36 m before the next waypoint
  const double slow = 15.0;
  const double fast = core::mph_to_mps(50.0);
  EgoView ego{line_.wrap_s(s0 - 60.0), core::lane_center_d(1), slow};
  Traffic t(map_, line_, params_, road_, TrafficProfile::faithful, 7);
  t.set_cars({car(s0, 1, slow, fast),          // 0: held up behind 1
              car(s0 + 17.0, 1, slow, slow),   // 1: the slow car
              car(s0 + 3.0, 0, slow, slow),    // 2: beside it in lane 0
              car(s0 + 3.0, 2, slow, slow)});  // 3: beside it in lane 2
  bool candidate_seen = false;
  for (int k = 0; k < 500; ++k) {  // 10 s
    const TrafficCar before = t.cars()[0];
    t.step(ego, kDt);
    ego = advance(ego);
    const TrafficCar& a = t.cars()[0];
    if (!before.candidate_lane && a.candidate_lane) {
      EXPECT_LE(to_next_waypoint(before.s_m), params_.faithful.waypoint_trigger_m + 1e-9);
      candidate_seen = true;
    }
    EXPECT_EQ(a.clear_steps, 0);
    for (const TrafficCar& c : t.cars()) {
      ASSERT_FALSE(c.manoeuvre.has_value()) << "car " << c.id << " changed lane at step " << k;
    }
  }
  EXPECT_TRUE(candidate_seen);
  ASSERT_TRUE(t.cars()[0].candidate_lane.has_value());
  EXPECT_EQ(*t.cars()[0].candidate_lane, 0);  // neither clear: lane 0

  // The lane-0 car drives away: 40 m ahead, same speed. The held-up car keeps its candidate
  // and moves over after the 51st consecutive clear step.
  std::vector<TrafficCar> cars = t.cars();
  cars[2].s_m = line_.wrap_s(cars[2].s_m + 40.0);
  t.set_cars(cars);
  for (int k = 1; k <= params_.faithful.clear_steps; ++k) {
    t.step(ego, kDt);
    ego = advance(ego);
    ASSERT_FALSE(t.cars()[0].manoeuvre.has_value()) << "started after " << k << " clear steps";
    ASSERT_TRUE(t.cars()[0].candidate_lane.has_value());
    EXPECT_EQ(t.cars()[0].clear_steps, k);
  }
  t.step(ego, kDt);
  ego = advance(ego);
  const TrafficCar& a = t.cars()[0];
  ASSERT_TRUE(a.manoeuvre.has_value());
  EXPECT_EQ(a.manoeuvre->from_lane, 1);
  EXPECT_EQ(a.manoeuvre->to_lane, 0);
  EXPECT_EQ(a.lane, 0);
  EXPECT_EQ(a.since_lane_change_s, 0.0);

  // It moves over smoothly in lane_change_duration_s and keeps lane 0.
  double prev_d = a.d_m;
  const int steps = static_cast<int>(std::lround(params_.lane_change_duration_s / kDt));
  for (int k = 0; k < steps + 10; ++k) {
    t.step(ego, kDt);
    ego = advance(ego);
    const double d = t.cars()[0].d_m;
    EXPECT_LE(d, prev_d + 1e-9);
    EXPECT_LT(std::abs(d - prev_d), 0.06);
    prev_d = d;
  }
  EXPECT_FALSE(t.cars()[0].manoeuvre.has_value());
  EXPECT_NEAR(t.cars()[0].d_m, core::lane_center_d(0), 1e-9);
  EXPECT_EQ(core::lane_of(t.cars()[0].d_m), 0);
}

// 3b. With the lane free, the candidate is picked only within 15 m of the next waypoint,
// and the change starts after the 51st clear step.
TEST_F(TrafficTest, LaneChangeWaitsForTheWaypointTrigger) {
  const double s0 = waypoint_s(40) + 2.0;
  ASSERT_GT(to_next_waypoint(s0), 30.0);
  const double slow = 15.0;
  EgoView ego{line_.wrap_s(s0 - 60.0), core::lane_center_d(1), slow};
  Traffic t(map_, line_, params_, road_, TrafficProfile::faithful, 3);
  t.set_cars({car(s0, 1, slow, core::mph_to_mps(50.0)), car(s0 + 17.0, 1, slow, slow)});
  int picked = -1;
  int started = -1;
  for (int k = 1; k <= 400 && started < 0; ++k) {
    const TrafficCar before = t.cars()[0];
    t.step(ego, kDt);
    ego = advance(ego);
    const TrafficCar& a = t.cars()[0];
    if (picked < 0 && a.candidate_lane) {
      picked = k;
      EXPECT_LE(to_next_waypoint(before.s_m), params_.faithful.waypoint_trigger_m + 1e-9);
      EXPECT_EQ(*a.candidate_lane, 0);  // from lane 1, lane 0 first
    }
    if (a.manoeuvre) started = k;
  }
  ASSERT_GT(picked, 1);
  EXPECT_EQ(started, picked + params_.faithful.clear_steps);
  EXPECT_EQ(t.cars()[0].manoeuvre->to_lane, 0);
}

// 4. The calm profile never collides with itself; the faithful one is measured.
TEST_F(TrafficTest, CalmProfileNeverCollidesWithItself) {
  const int steps = sanitized() ? 15'000 : 90'000;  // 5 or 30 minutes
  EgoView ego{line_.wrap_s(EgoParams{}.start_s_m), core::lane_center_d(1), 21.0};
  Traffic t(map_, line_, params_, road_, TrafficProfile::calm, 11);
  t.place_initial(ego);
  int overlap_steps = 0;
  int lane_changes = 0;
  double min_speed = 1e9;
  for (int k = 0; k < steps; ++k) {
    t.step(ego, kDt);
    ego = advance(ego);
    for (const TrafficCar& c : t.cars()) {
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

TEST_F(TrafficTest, FaithfulProfileOverlapsAreReported) {
  const int steps = sanitized() ? 3'000 : 15'000;  // 1 or 5 minutes
  int total_steps = 0;
  int total_overlap_steps = 0;
  int total_lane_changes = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    EgoView ego{line_.wrap_s(EgoParams{}.start_s_m), core::lane_center_d(1), 21.0};
    Traffic t(map_, line_, params_, road_, TrafficProfile::faithful, seed);
    t.place_initial(ego);
    int overlap_steps = 0;
    int episodes = 0;
    bool was = false;
    for (int k = 0; k < steps; ++k) {
      t.step(ego, kDt);
      ego = advance(ego);
      for (const TrafficCar& c : t.cars()) {
        if (c.manoeuvre && c.manoeuvre->elapsed_s <= kDt + 1e-12) ++total_lane_changes;
      }
      const bool now = overlaps(t) > 0;
      if (now) ++overlap_steps;
      if (now && !was) ++episodes;
      was = now;
    }
    std::cout << "[ faithful ] seed " << seed << ": " << steps << " steps, " << overlap_steps
              << " steps with overlapping traffic, " << episodes << " episodes\n";
    total_steps += steps;
    total_overlap_steps += overlap_steps;
  }
  std::cout << "[ faithful ] total " << total_steps << " steps, " << total_lane_changes
            << " lane changes, " << total_overlap_steps << " steps with overlaps\n";
  RecordProperty("faithful_overlap_steps", total_overlap_steps);
  EXPECT_GT(total_lane_changes, 0);
}

// Calm: MOBIL counts the ego as the new follower. A car held up by a slow car does not
// move in 8 m ahead of the ego; with the ego 60 m back it does.
TEST_F(TrafficTest, CalmCarDoesNotCutInCloseAheadOfTheEgo) {
  core::RoadParams two_lanes;
  two_lanes.lane_count = 2;
  const double s0 = 2000.0;
  TrafficParams selfish = params_;
  selfish.calm.politeness = 0.0;  // else the slow car politely moves over itself
  Traffic t(map_, line_, selfish, two_lanes, TrafficProfile::calm, 9);
  t.set_cars({car(s0, 1, 20.0, 25.0), car(s0 + 30.0, 1, 12.0, 12.0)});
  auto ego_behind = [&](double back_m) {
    const TrafficCar& a = t.cars()[0];
    return EgoView{line_.wrap_s(a.s_m - back_m), core::lane_center_d(0), a.speed_mps};
  };
  for (int k = 0; k < 500; ++k) {  // 10 s
    t.step(ego_behind(8.0), kDt);
    ASSERT_FALSE(t.cars()[0].manoeuvre.has_value()) << "cut in on the ego at step " << k;
  }
  EXPECT_TRUE(t.cars()[0].held_up);
  int started = -1;
  for (int k = 0; k < 500 && started < 0; ++k) {
    t.step(ego_behind(60.0), kDt);
    if (t.cars()[0].manoeuvre) started = k;
  }
  ASSERT_GE(started, 0);
  EXPECT_EQ(t.cars()[0].manoeuvre->to_lane, 0);
}

// 5. Same seed, same states bit for bit; another seed differs.
TEST_F(TrafficTest, SameSeedSameTraffic) {
  for (const TrafficProfile profile : {TrafficProfile::faithful, TrafficProfile::calm}) {
    SCOPED_TRACE(std::string(to_string(profile)));
    auto run = [&](std::uint64_t seed) {
      EgoView ego{line_.wrap_s(EgoParams{}.start_s_m), core::lane_center_d(1), 18.0};
      Traffic t(map_, line_, params_, road_, profile, seed);
      t.place_initial(ego);
      for (int k = 0; k < 3000; ++k) {
        t.step(ego, kDt);
        ego = advance(ego);
      }
      return t.cars();
    };
    const auto a = run(42);
    const auto b = run(42);
    const auto c = run(43);
    ASSERT_EQ(a.size(), b.size());
    bool differs = false;
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].id, b[i].id);
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
}

// 6. Across the end of the loop, s wraps and stays continuous.
TEST_F(TrafficTest, CarCrossesTheLapWrap) {
  const double end = line_.start_s_m() + line_.length_m();
  EgoView ego{line_.wrap_s(end - 40.0), core::lane_center_d(1), 20.0};
  Traffic t(map_, line_, params_, road_, TrafficProfile::faithful, 5);
  t.set_cars({car(end - 5.0, 1, 20.0, 20.0)});
  core::CarObservation prev = t.observe(t.cars()[0]);
  bool wrapped = false;
  for (int k = 0; k < 100; ++k) {
    t.step(ego, kDt);
    ego = advance(ego);
    const core::CarObservation o = t.observe(t.cars()[0]);
    EXPECT_GE(o.s_m, line_.start_s_m());
    EXPECT_LT(o.s_m, end);
    EXPECT_EQ(o.s_m, t.cars()[0].s_m);
    const double ds = line_.s_ahead(prev.s_m, o.s_m);
    EXPECT_GT(ds, 0.0);
    EXPECT_NEAR(ds, 20.0 * kDt, 0.02);
    EXPECT_NEAR(core::distance(prev.position, o.position), 20.0 * kDt, 0.01);
    if (o.s_m < prev.s_m) wrapped = true;
    prev = o;
  }
  EXPECT_TRUE(wrapped);
  EXPECT_NEAR(prev.s_m, line_.start_s_m() + 35.0, 0.5);
}

// Observations and footprints follow the car's motion.
TEST_F(TrafficTest, ObservationMatchesTheCarsMotion) {
  Traffic t(map_, line_, params_, road_, TrafficProfile::faithful, 1);
  TrafficCar c = car(1000.0, 2, 20.0, 20.0);
  c.d_rate_mps = 0.0;
  t.set_cars({c});
  const core::CarObservation o = t.observe(t.cars()[0]);
  const core::RoadFrame f = line_.frame(1000.0);
  EXPECT_NEAR(core::norm(o.velocity_mps), 20.0, 1e-9);
  EXPECT_NEAR(core::dot(o.velocity_mps, f.tangent), 20.0, 1e-9);
  EXPECT_NEAR(core::distance(o.position, f.position + core::lane_center_d(2) * f.normal), 0.0,
              1e-9);
  const core::OrientedBox box = t.footprint(t.cars()[0]);
  EXPECT_NEAR(core::wrap_angle_rad(box.heading_rad - f.heading_rad), 0.0, 1e-9);
  EXPECT_EQ(box.length_m, params_.car_length_m);
  EXPECT_EQ(box.width_m, params_.car_width_m);
  // Standing still: the road's heading.
  c.speed_mps = 0.0;
  t.set_cars({c});
  EXPECT_NEAR(core::wrap_angle_rad(t.footprint(t.cars()[0]).heading_rad - f.heading_rad), 0.0,
              1e-9);
}

}  // namespace
}  // namespace overtake::sim
