// The reference policy as a whole: its bookkeeping of its own path under latency, the C2
// joint, robustness to odd input, the lap wrap, and seeded drives in both traffic profiles.

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "overtake/core/map.hpp"
#include "overtake/core/track.hpp"
#include "overtake/core/units.hpp"
#include "overtake/planner/policy.hpp"
#include "overtake/planner/reference/reference_policy.hpp"
#include "overtake/sim/run.hpp"
#include "overtake/sim/world.hpp"
#include "planner/reference_support.hpp"

namespace overtake::planner::reference {
namespace {

class PolicyTest : public ::testing::Test {
 protected:
  PolicyTest() : map_(overtake::test::circle_map()), line_(map_) {}

  /// What the simulator reports after the car drove `k` points of `path` (trimmed as the
  /// simulator does: rounded, the first point kept).
  core::Telemetry after(const core::Telemetry& before, const std::vector<core::Vec2>& path,
                        std::size_t k) const {
    const auto sent = core::round_like_wire(path);
    core::Telemetry t = before;
    const core::Vec2 car = sent[k - 1];
    const core::Vec2 next = sent[k];
    const core::FrenetPoint f = line_.to_frenet(car, before.ego.s_m);
    const core::Vec2 before_car = k >= 2 ? sent[k - 2] : before.ego.position;
    t.ego = {car, std::atan2(next.y - car.y, next.x - car.x),
             core::distance(car, before_car) / 0.02, f.s_m, f.d_m};
    t.previous_path.assign(sent.begin() + static_cast<std::ptrdiff_t>(k), sent.end());
    t.end_path = line_.to_frenet(t.previous_path.back(), f.s_m);
    return core::round_like_wire(t);
  }

  core::Map map_;
  core::ReferenceLine line_;
  PlannerParams params_;
};

TEST_F(PolicyTest, KeepsAShortPrefixAndKnowsWhereTheCarIs) {
  ReferencePolicy p(line_, params_);
  core::Telemetry t = test::ego_at(line_, 500.0, 6.0, 0.0);
  std::vector<core::Vec2> path = p.plan(t).path;
  ASSERT_EQ(path.size(), static_cast<std::size_t>(params_.reference.trajectory.path_points));
  for (int cycle = 0; cycle < 200; ++cycle) {
    const std::size_t k = 1 + static_cast<std::size_t>(cycle % 3);
    t = after(t, path, k);
    const std::vector<core::Vec2> next = p.plan(t).path;
    ASSERT_TRUE(p.last_synced()) << cycle;
    const auto keep = static_cast<std::size_t>(params_.reference.trajectory.keep_points);
    for (std::size_t i = 0; i < keep; ++i) EXPECT_EQ(next[i], t.previous_path[i]);
    path = next;
  }
  EXPECT_GT(t.ego.speed_mps, 5.0);  // it got going
}

TEST_F(PolicyTest, APolicyOnASharedGeometryPlansAsOneThatBuildsItsOwn) {
  const auto geometry = make_reference_geometry(line_, params_);
  ReferencePolicy own(line_, params_);
  ReferencePolicy first(line_, params_, geometry);
  ReferencePolicy second(line_, params_, geometry);
  core::Telemetry t = test::ego_at(line_, 500.0, 6.0, 0.0);
  std::vector<core::Vec2> path = own.plan(t).path;
  ASSERT_EQ(first.plan(t).path, path);
  ASSERT_EQ(second.plan(t).path, path);
  for (int cycle = 0; cycle < 300; ++cycle) {
    t = after(t, path, 1 + static_cast<std::size_t>(cycle % 3));
    path = own.plan(t).path;
    ASSERT_EQ(first.plan(t).path, path) << cycle;
    ASSERT_EQ(second.plan(t).path, path) << cycle;
  }
}

// Two policies planning in turn in buffers lent by the caller (as the learning environment's
// worlds on one thread do) plan as each does in its own: what one leaves there, the other
// never reads. The two are in different traffic, one among a file of cars, one alone.
TEST_F(PolicyTest, PoliciesPlanningInTurnInLentBuffersPlanAsInTheirOwn) {
  const auto geometry = make_reference_geometry(line_, params_);
  ReferencePolicy own_a(line_, params_, geometry);
  ReferencePolicy own_b(line_, params_, geometry);
  ReferencePolicy lent_a(line_, params_, geometry);
  ReferencePolicy lent_b(line_, params_, geometry);
  TrajectoryScratch scratch;
  core::Telemetry ta = test::ego_at(line_, 500.0, 6.0, 18.0);
  for (int k = 0; k < 4; ++k)
    ta.cars.push_back(
        test::observed_car(line_, 3 + k, 470.0 + 25.0 * k, 2.0 + 4.0 * (k % 2), 15.0));
  core::Telemetry tb = test::ego_at(line_, 1500.0, 2.0, 0.0);
  std::vector<core::Vec2> pa = own_a.plan(ta).path;
  std::vector<core::Vec2> pb = own_b.plan(tb).path;
  ASSERT_EQ(lent_a.plan(ta, scratch).path, pa);
  ASSERT_EQ(lent_b.plan(tb, scratch).path, pb);
  ASSERT_FALSE(scratch.spare.empty());  // the buffers came back to the lender
  for (int cycle = 0; cycle < 100; ++cycle) {
    const auto k = 1 + static_cast<std::size_t>(cycle % 3);
    ta = after(ta, pa, k);
    tb = after(tb, pb, k);
    pa = own_a.plan(ta).path;
    pb = own_b.plan(tb).path;
    ASSERT_EQ(lent_a.plan(ta, scratch).path, pa) << cycle;
    ASSERT_EQ(lent_b.plan(tb, scratch).path, pb) << cycle;
  }
}

TEST_F(PolicyTest, AGeometryOfAnotherLineSmoothingOrRoadIsRefused) {
  const auto geometry = make_reference_geometry(line_, params_);
  const core::ReferenceLine other(map_);
  EXPECT_THROW(ReferencePolicy(other, params_, geometry), std::invalid_argument);
  PlannerParams smoother = params_;
  smoother.reference.line_smoothing_m3 *= 2.0;
  EXPECT_THROW(ReferencePolicy(line_, smoother, geometry), std::invalid_argument);
  PlannerParams wider = params_;
  wider.road.lane_width_m += 0.5;
  EXPECT_THROW(ReferencePolicy(line_, wider, geometry), std::invalid_argument);
  EXPECT_THROW(ReferencePolicy(line_, params_, nullptr), std::invalid_argument);
}

// A lane change asked for (here by a command, as the learning environment asks) that the
// trajectory layer does not take is said in the cycle's answer: for safety with a file of
// cars alongside in that lane, not at all when the lane is free (the change is taken).
TEST_F(PolicyTest, ALaneChangeNotTakenIsSaidWithWhy) {
  const auto first_answer = [&](bool car_alongside) {
    ReferencePolicy p(line_, params_);
    p.set_command(DrivingCommand{0, 20.0});
    core::Telemetry t = test::ego_at(line_, 500.0, 6.0, 20.0);
    // A file of cars in that lane from 40 m behind to 40 m ahead, at the ego's speed.
    for (int k = 0; car_alongside && k < 9; ++k)
      t.cars.push_back(test::observed_car(line_, 3 + k, 460.0 + 10.0 * k, 2.0, 20.0));
    const core::PlanResult r = p.plan(t);
    return std::pair{r.change_declined, p.last_plan().trajectory.end_lane};
  };
  const auto [free_declined, free_end] = first_answer(false);
  EXPECT_EQ(free_declined, core::ChangeDeclined::no);
  EXPECT_EQ(free_end, 0);
  const auto [blocked_declined, blocked_end] = first_answer(true);
  EXPECT_EQ(blocked_declined, core::ChangeDeclined::for_safety);
  EXPECT_EQ(blocked_end, 1);
  // Keeping the lane declines nothing.
  ReferencePolicy keep(line_, params_);
  keep.set_command(DrivingCommand{1, 20.0});
  EXPECT_EQ(keep.plan(test::ego_at(line_, 500.0, 6.0, 20.0)).change_declined,
            core::ChangeDeclined::no);
}

TEST_F(PolicyTest, TheJointWithTheKeptPathIsSmooth) {
  // Drive a while, then look at second and third differences of the points across joints:
  // no spike beyond the limits (the strict figures' 0.1 s windows).
  ReferencePolicy p(line_, params_);
  core::Telemetry t = test::ego_at(line_, 500.0, 6.0, 0.0);
  std::vector<core::Vec2> path = p.plan(t).path;
  std::vector<core::Vec2> driven;
  for (int cycle = 0; cycle < 600; ++cycle) {
    const std::size_t k = 1 + static_cast<std::size_t>((cycle * 7) % 3);
    const auto sent = core::round_like_wire(path);
    for (std::size_t i = 0; i < k; ++i) driven.push_back(sent[i]);
    t = after(t, path, k);
    path = p.plan(t).path;
  }
  const int w = 5;
  const double h = 0.1;
  double peak_acc = 0.0, peak_jerk = 0.0;
  for (std::size_t i = 3 * w; i < driven.size(); ++i) {
    const core::Vec2 p0 = driven[i], p1 = driven[i - w], p2 = driven[i - 2 * w],
                     p3 = driven[i - 3 * w];
    peak_acc = std::max(peak_acc, core::norm(p0 - 2.0 * p1 + p2) / (h * h));
    peak_jerk = std::max(peak_jerk, core::norm(p0 - 3.0 * p1 + 3.0 * p2 - p3) / (h * h * h));
  }
  EXPECT_LT(peak_acc, params_.reference.trajectory.max_accel_mps2 + 0.5);
  EXPECT_LT(peak_jerk, params_.reference.trajectory.max_jerk_mps3 + 1.0);
}

// Where the coordinates pass 1000 m the wire keeps 1 mm, and a car braking to a stand behind
// a stopped one steps a few quanta at the end: facing its next point as read, it would face
// tens of degrees off its lane (the simulator's rule, as the original's). With points held
// (trajectory.crawl_max_lag_m) it stands facing along its lane, a few millimetres short.
TEST_F(PolicyTest, BrakingToAStandItFacesItsLaneWhenPointsAreHeld) {
  struct Stand {
    double worst_turn_rad = 0.0;  // off the road's heading, below 1 m/s
    double stand_s_m = 0.0;
  };
  const auto brake_behind_a_stopped_car = [&](double max_lag_m) {
    PlannerParams params = params_;
    params.reference.trajectory.crawl_max_lag_m = max_lag_m;
    ReferencePolicy p(line_, params);
    // s 300 to 340 lies where x and y are past 1000 m (the circle's first quarter).
    core::Telemetry t = test::ego_at(line_, 300.0, 6.0, 8.0);
    // A stopped car in each lane: nowhere to go but to a stand.
    const std::vector<core::CarObservation> stopped = {
        test::observed_car(line_, 7, 340.0, 2.0, 0.0),
        test::observed_car(line_, 8, 340.0, 6.0, 0.0),
        test::observed_car(line_, 9, 340.0, 10.0, 0.0)};
    t.cars = stopped;
    std::vector<core::Vec2> path = p.plan(t).path;
    Stand out;
    double heading = t.ego.yaw_rad;
    for (int cycle = 0; cycle < 400; ++cycle) {
      const std::size_t k = 1 + static_cast<std::size_t>(cycle % 3);
      const auto sent = core::round_like_wire(path);
      for (std::size_t i = 0; i < k; ++i) {
        // The simulator's rule: onto point i, facing the next unless it is the same point.
        if (!(sent[i + 1] == sent[i])) {
          heading = std::atan2(sent[i + 1].y - sent[i].y, sent[i + 1].x - sent[i].x);
        }
        const double step_mps =
            core::distance(sent[i], i == 0 ? t.ego.position : sent[i - 1]) / params.step_s;
        const double road = line_.frame(line_.to_frenet(sent[i], t.ego.s_m).s_m).heading_rad;
        if (step_mps < 1.0) {
          out.worst_turn_rad = std::max(out.worst_turn_rad,
                                        std::abs(std::remainder(heading - road, 2.0 * core::kPi)));
        }
      }
      t = after(t, path, k);
      t.cars = stopped;
      path = p.plan(t).path;
    }
    out.stand_s_m = t.ego.s_m;
    return out;
  };
  const Stand creeping = brake_behind_a_stopped_car(0.0);
  const Stand held = brake_behind_a_stopped_car(0.006);
  EXPECT_GT(creeping.worst_turn_rad, 0.4);  // 28 degrees: what the hold is for
  EXPECT_LE(held.worst_turn_rad, params_.reference.trajectory.crawl_heading_tolerance_rad);
  EXPECT_LT(held.stand_s_m, 340.0 - 4.7);                 // behind the stopped car ...
  EXPECT_NEAR(held.stand_s_m, creeping.stand_s_m, 0.01);  // ... where it stood before, or near
}

TEST_F(PolicyTest, OddInputNeverThrowsAndAlwaysGivesAPath) {
  ReferencePolicy p(line_, params_);
  core::Telemetry empty;  // all zero: the ego at the map's origin, far off the road
  EXPECT_NO_THROW({ EXPECT_FALSE(p.plan(empty).path.empty()); });
  core::Telemetry off_road = test::ego_at(line_, 300.0, 30.0, 10.0);
  EXPECT_NO_THROW({ EXPECT_FALSE(p.plan(off_road).path.empty()); });
  core::Telemetry junk = test::ego_at(line_, 300.0, 6.0, 10.0);
  junk.previous_path = {{1.0, 2.0}, {3.0, 4.0}, {5.0, 6.0}};  // not ours: it starts afresh
  EXPECT_NO_THROW({ EXPECT_FALSE(p.plan(junk).path.empty()); });
  EXPECT_FALSE(p.last_synced());
  core::Telemetry one = test::ego_at(line_, 300.0, 6.0, 10.0);
  one.previous_path = {one.ego.position};
  EXPECT_NO_THROW({ EXPECT_FALSE(p.plan(one).path.empty()); });
  core::Telemetry crowded = test::ego_at(line_, 300.0, 6.0, 0.0);
  for (int i = 0; i < 12; ++i)
    crowded.cars.push_back(
        test::observed_car(line_, i, 300.0 + 5.0 * (i - 6), 2.0 + 4.0 * (i % 3), 0.0));
  EXPECT_NO_THROW({ EXPECT_FALSE(p.plan(crowded).path.empty()); });
}

TEST_F(PolicyTest, DrivesAcrossTheLapWrapWithoutAJump) {
  sim::WorldParams wp;
  wp.traffic.car_count = 0;
  wp.ego.start_s_m = line_.start_s_m() + line_.length_m() - 150.0;
  sim::World world(map_, line_, wp, sim::TrafficProfile::faithful, 1);
  auto policy = make_policy("reference", line_, params_);
  sim::RunOptions opts;
  opts.duration_s = 25.0;
  const auto r = sim::run_drive(
      world, [&](const core::Telemetry& t) { return policy->plan(t); }, opts);
  EXPECT_TRUE(r.incidents.empty());
  EXPECT_GT(r.distance_m, 300.0);  // crossed the wrap
  EXPECT_LT(r.peak.strict_jerk_mps3, 10.0);
  EXPECT_LT(r.peak.strict_acceleration_mps2, 10.0);
}

TEST_F(PolicyTest, IsTheFirstPolicyListed) {
  const auto policies = list_policies();
  ASSERT_FALSE(policies.empty());
  EXPECT_EQ(policies.front().name, "reference");
  EXPECT_NE(make_policy("reference", line_, params_), nullptr);
}

/// Seeded drives on the default-like test loop: several seeds x minutes, both profiles;
/// zero incidents, strict figures under the limits, and a mean speed floor.
class SeededDrives : public ::testing::TestWithParam<sim::TrafficProfile> {};

TEST_P(SeededDrives, NoIncidentsAndAMeanSpeedFloor) {
  const core::Map map = overtake::test::circle_map(1100.0, 38.0);
  const core::ReferenceLine line(map);
  const PlannerParams params;
  const bool small = test::sanitized();
  const int seeds = small ? 1 : 4;
  const double minutes = small ? 1.0 : 3.0;
  double metres = 0.0, seconds = 0.0;
  for (int seed = 1; seed <= seeds; ++seed) {
    sim::World world(map, line, sim::WorldParams{}, GetParam(), static_cast<std::uint64_t>(seed));
    auto policy = make_policy("reference", line, params);
    sim::RunOptions opts;
    opts.duration_s = minutes * 60.0;
    opts.seed = static_cast<std::uint64_t>(seed);
    const auto r = sim::run_drive(
        world, [&](const core::Telemetry& t) { return policy->plan(t); }, opts);
    EXPECT_TRUE(r.incidents.empty())
        << "seed " << seed << ": " << r.incidents.size()
        << " incidents, first at t = " << (r.incidents.empty() ? 0.0 : r.incidents.front().t_s);
    EXPECT_LT(r.peak.strict_acceleration_mps2, 10.0) << "seed " << seed;
    EXPECT_LT(r.peak.strict_jerk_mps3, 10.0) << "seed " << seed;
    EXPECT_LT(core::mps_to_mph(r.peak.speed_mps), 50.0) << "seed " << seed;
    metres += r.distance_m;
    seconds += r.duration_s;
  }
  // The start from rest costs ~0.5 mph over a minute; traffic a few more.
  EXPECT_GT(core::mps_to_mph(metres / seconds), small ? 40.0 : 45.0);
}

TEST_P(SeededDrives, WaypointsUpTo90MetresApart) {
  // On a bend a chord between far-apart waypoints runs well inside the curve: the outer
  // lanes' centres read close to the road's edge there (this once stopped the car for good).
  core::TrackSpec spec;
  spec.seed = 4;
  spec.straight_spacing_m = 86.0;
  spec.min_spacing_m = 37.0;
  spec.max_spacing_m = 97.0;
  const core::Map map = core::parse_map(core::format_map(core::generate_track(spec)), "sparse");
  const core::ReferenceLine line(map);
  const PlannerParams params;
  const bool small = test::sanitized();
  const int seeds = small ? 1 : 3;
  const double minutes = small ? 1.0 : 4.0;
  double metres = 0.0, seconds = 0.0;
  for (int seed = 1; seed <= seeds; ++seed) {
    sim::World world(map, line, sim::WorldParams{}, GetParam(), static_cast<std::uint64_t>(seed));
    auto policy = make_policy("reference", line, params);
    sim::RunOptions opts;
    opts.duration_s = minutes * 60.0;
    opts.seed = static_cast<std::uint64_t>(seed);
    const auto r = sim::run_drive(
        world, [&](const core::Telemetry& t) { return policy->plan(t); }, opts);
    EXPECT_TRUE(r.incidents.empty())
        << "seed " << seed << ": " << r.incidents.size() << " incidents";
    EXPECT_LT(r.peak.strict_jerk_mps3, 10.0) << "seed " << seed;
    metres += r.distance_m;
    seconds += r.duration_s;
  }
  EXPECT_GT(core::mps_to_mph(metres / seconds), small ? 38.0 : 44.0);
}

INSTANTIATE_TEST_SUITE_P(BothProfiles, SeededDrives,
                         ::testing::Values(sim::TrafficProfile::faithful,
                                           sim::TrafficProfile::calm),
                         [](const auto& param_info) {
                           return std::string(sim::to_string(param_info.param));
                         });

}  // namespace
}  // namespace overtake::planner::reference
