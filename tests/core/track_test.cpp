// Generated loop tracks: every seed meets the spec, the generator is deterministic, the
// checker names the faults of bad maps, bad specs are rejected by field, and the reference
// line of a generated track converts Frenet <-> Cartesian both ways around the whole loop.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "overtake/core/geometry.hpp"
#include "overtake/core/map.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/track.hpp"
#include "overtake/core/units.hpp"

namespace overtake::core {
namespace {

using ::testing::HasSubstr;

constexpr double kRoundTripTolM = 0.01;

TrackSpec spec_with(std::uint64_t seed, double length_m = 7000.0) {
  TrackSpec spec;
  spec.seed = seed;
  spec.length_m = length_m;
  return spec;
}

// The map exactly as a user loads it.
Map load(const std::vector<Waypoint>& w, const std::string& name = "test track") {
  return parse_map(format_map(w), name);
}

std::string joined(const std::vector<std::string>& lines) {
  std::string out;
  for (const auto& l : lines) out += l + "\n";
  return out;
}

// ---- Hand-made loops for the checker ----

// A stretch of constant curvature (1/m, positive left).
struct Arc {
  double length_m;
  double curvature_1pm;
};

struct Pose {
  Vec2 position;
  double heading_rad;
};

// Pose at arc length `s` along arcs laid end to end from `start`.
Pose walk(const std::vector<Arc>& arcs, Pose start, double s) {
  Pose p = start;
  for (const Arc& a : arcs) {
    const double u = std::min(s, a.length_m);
    if (a.curvature_1pm == 0.0) {
      p.position = p.position + u * Vec2{std::cos(p.heading_rad), std::sin(p.heading_rad)};
    } else {
      const double h1 = p.heading_rad + a.curvature_1pm * u;
      p.position =
          p.position + (1.0 / a.curvature_1pm) * Vec2{std::sin(h1) - std::sin(p.heading_rad),
                                                      std::cos(p.heading_rad) - std::cos(h1)};
      p.heading_rad = h1;
    }
    s -= u;
    if (s <= 0.0) break;
  }
  return p;
}

// Waypoints every ~`spacing_m` along a closed path given as poses by arc length; s is the
// summed straight-line distance and the normals point right of travel.
template <typename PoseAt>
std::vector<Waypoint> sample_loop(PoseAt pose_at, double length_m, double spacing_m) {
  const int n = static_cast<int>(std::lround(length_m / spacing_m));
  std::vector<Waypoint> w;
  double s = 0.0;
  for (int i = 0; i < n; ++i) {
    const Pose p = pose_at(length_m * i / n);
    if (!w.empty()) s += std::hypot(p.position.x - w.back().x_m, p.position.y - w.back().y_m);
    w.push_back({p.position.x, p.position.y, s, std::sin(p.heading_rad), -std::cos(p.heading_rad)});
  }
  return w;
}

// A counter-clockwise rounded rectangle, `width_m` by `height_m`, centred on the origin, with
// corner radii starting at the bottom right.
std::vector<Waypoint> rounded_rectangle(double width_m, double height_m,
                                        const std::array<double, 4>& r, double spacing_m) {
  const double q = 0.5 * kPi;
  const std::vector<Arc> arcs{
      {0.5 * width_m - r[0], 0.0},   {q * r[0], 1.0 / r[0]},       {height_m - r[0] - r[1], 0.0},
      {q * r[1], 1.0 / r[1]},        {width_m - r[1] - r[2], 0.0}, {q * r[2], 1.0 / r[2]},
      {height_m - r[2] - r[3], 0.0}, {q * r[3], 1.0 / r[3]},       {0.5 * width_m - r[3], 0.0}};
  double length = 0.0;
  for (const Arc& a : arcs) length += a.length_m;
  const Pose start{{0.0, -0.5 * height_m}, 0.0};
  return sample_loop([&](double s) { return walk(arcs, start, s); }, length, spacing_m);
}

// ---- Generated tracks meet the spec ----

TEST(TrackGenerate, SeedsOneToTenMeetTheSpec) {
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const TrackSpec spec = spec_with(seed);
    const std::vector<Waypoint> w = generate_track(spec);
    const Map map = load(w);
    const TrackReport r = check_track(map, spec);
    EXPECT_TRUE(r.ok()) << joined(r.problems);
    EXPECT_NEAR(r.length_m, 7000.0, 0.02 * 7000.0);
    EXPECT_GE(r.min_radius_m, 150.0);
    EXPECT_GE(r.min_spacing_m, 20.0);
    EXPECT_LE(r.max_spacing_m, 90.0);
    EXPECT_GT(r.mean_spacing_m, 30.0);
    EXPECT_LT(r.mean_spacing_m, 45.0);
    EXPECT_TRUE(r.bends_left);
    EXPECT_TRUE(r.bends_right);
    EXPECT_FALSE(r.self_intersecting);
    EXPECT_TRUE(r.counter_clockwise);
    EXPECT_GE(r.min_clearance_m, 40.0);
    EXPECT_GE(r.start_straight_m, 300.0);
    EXPECT_LT(r.max_abs_coordinate_m, 1000.0);
    for (const Waypoint& p : w) {
      ASSERT_LT(std::abs(p.x_m), 1000.0);
      ASSERT_LT(std::abs(p.y_m), 1000.0);
    }
    // The whole road, outer edge included, stays inside the box too.
    const ReferenceLine line(map);
    for (double s = 0.0; s < line.length_m(); s += 5.0) {
      const Vec2 edge = line.to_cartesian({s, 13.0});
      ASSERT_LT(std::max(std::abs(edge.x), std::abs(edge.y)), 1000.0) << "s " << s;
    }
  }
}

TEST(TrackGenerate, FirstWaypointAtZeroAndSIsTheSummedDistance) {
  const std::vector<Waypoint> w = generate_track(spec_with(3));
  ASSERT_GT(w.size(), 100u);
  EXPECT_EQ(w.front().s_m, 0.0);
  double along = 0.0;
  for (std::size_t i = 1; i < w.size(); ++i) {
    along += std::hypot(w[i].x_m - w[i - 1].x_m, w[i].y_m - w[i - 1].y_m);
    ASSERT_NEAR(w[i].s_m, along, 1e-3) << "waypoint " << i;
  }
  // The returned waypoints are exactly what the file gives back.
  EXPECT_EQ(load(w).waypoints, w);
}

TEST(TrackGenerate, DividerInsideNormalsPointRightOfTravel) {
  const std::vector<Waypoint> w = generate_track(spec_with(4));
  const std::size_t n = w.size();
  double area_divider = 0.0;
  double area_edge = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const Waypoint& a = w[i];
    const Waypoint& b = w[(i + 1) % n];
    ASSERT_NEAR(std::hypot(a.dx, a.dy), 1.0, 1e-6);
    const Vec2 travel{b.x_m - a.x_m, b.y_m - a.y_m};
    EXPECT_GT(dot(right_of((1.0 / norm(travel)) * travel), {a.dx, a.dy}), 0.99) << i;
    area_divider += a.x_m * b.y_m - b.x_m * a.y_m;
    area_edge += (a.x_m + 12.0 * a.dx) * (b.y_m + 12.0 * b.dy) -
                 (b.x_m + 12.0 * b.dx) * (a.y_m + 12.0 * a.dy);
  }
  EXPECT_GT(area_divider, 0.0);        // counter-clockwise
  EXPECT_GT(area_edge, area_divider);  // the lanes lie outside the divider
}

TEST(TrackGenerate, EgoStartsOnAStraightInTheMiddleLane) {
  const Map map = load(generate_track(spec_with(5)));
  const ReferenceLine line(map);
  for (double s = 0.0; s <= 300.0; s += 5.0) {
    EXPECT_LT(std::abs(line.curvature_at(s, lane_center_d(1))), 1.0 / 2000.0) << "s " << s;
  }
}

TEST(TrackGenerate, SameSeedSameTextOtherSeedOtherText) {
  const std::string a = format_map(generate_track(spec_with(1)));
  const std::string b = format_map(generate_track(spec_with(1)));
  const std::string c = format_map(generate_track(spec_with(2)));
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
}

TEST(TrackGenerate, OtherLengthsWork) {
  for (const double length : {4000.0, 5000.0, 9000.0, 15000.0}) {
    SCOPED_TRACE("length " + std::to_string(length));
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      const TrackSpec spec = spec_with(seed, length);
      const Map map = load(generate_track(spec));
      const TrackReport r = check_track(map, spec);
      EXPECT_TRUE(r.ok()) << joined(r.problems);
      EXPECT_NEAR(r.length_m, length, 0.02 * length);
      EXPECT_LT(r.max_abs_coordinate_m, max_abs_coordinate_for(spec));
    }
  }
}

TEST(TrackGenerate, TheLongestSmallLoopStillFitsTheBox) {
  const TrackSpec spec = spec_with(1, 7500.0);
  EXPECT_EQ(max_abs_coordinate_for(spec), 1000.0);
  const TrackReport r = check_track(load(generate_track(spec)), spec);
  EXPECT_TRUE(r.ok()) << joined(r.problems);
  EXPECT_LT(r.max_abs_coordinate_m, 1000.0);
}

TEST(TrackGenerate, OtherSpecFieldsAreHonoured) {
  TrackSpec spec = spec_with(7);
  spec.min_radius_m = 250.0;
  spec.min_spacing_m = 30.0;
  spec.max_spacing_m = 60.0;
  spec.road.lane_count = 4;
  const TrackReport r = check_track(load(generate_track(spec)), spec);
  EXPECT_TRUE(r.ok()) << joined(r.problems);
  EXPECT_GE(r.min_radius_m, 250.0);
  EXPECT_GE(r.min_spacing_m, 30.0);
  EXPECT_LE(r.max_spacing_m, 60.0);
}

TEST(TrackGenerate, WideStraightSpacingMakesASparseMap) {
  // Waypoints up to 90 m apart on the straights (bends keep closer ones).
  TrackSpec spec = spec_with(4);
  spec.straight_spacing_m = 86.0;
  spec.min_spacing_m = 37.0;
  spec.max_spacing_m = 97.0;
  const TrackReport r = check_track(load(generate_track(spec)), spec);
  EXPECT_TRUE(r.ok()) << joined(r.problems);
  EXPECT_GT(r.max_spacing_m, 85.0);
  EXPECT_LE(r.max_spacing_m, 90.0);
  EXPECT_GT(r.mean_spacing_m,
            1.4 * check_track(load(generate_track(spec_with(4))), spec_with(4)).mean_spacing_m);
}

// ---- The checker finds faults ----

TEST(TrackCheck, FindsAFigureEight) {
  // x = a sin t, y = a/2 sin 2t crosses itself at the origin.
  constexpr double a = 1000.0;
  constexpr int n = 200;
  std::vector<Waypoint> w;
  double s = 0.0;
  for (int i = 0; i < n; ++i) {
    const double t = 2.0 * kPi * (i + 0.3) / n;  // no waypoint on the crossing itself
    const Vec2 p{a * std::sin(t), 0.5 * a * std::sin(2.0 * t)};
    const Vec2 v{a * std::cos(t), a * std::cos(2.0 * t)};
    if (!w.empty()) s += std::hypot(p.x - w.back().x_m, p.y - w.back().y_m);
    const Vec2 nrm = right_of((1.0 / norm(v)) * v);
    w.push_back({p.x, p.y, s, nrm.x, nrm.y});
  }
  // parse_map refuses it (MapLimits tests); check_track is also given Maps built in code.
  EXPECT_THROW((void)load(w, "figure-eight"), MapError);
  Map map;
  map.waypoints = w;
  map.source = "figure-eight";
  map.loop_length_m = s + std::hypot(w.front().x_m - w.back().x_m, w.front().y_m - w.back().y_m);
  TrackSpec spec;
  spec.length_m = map.loop_length_m;
  const TrackReport r = check_track(map, spec);
  EXPECT_TRUE(r.self_intersecting);
  EXPECT_THAT(joined(r.problems), HasSubstr("self-intersecting"));
  EXPECT_LT(r.min_clearance_m, 0.0);
}

TEST(TrackCheck, FindsATightBend) {
  const Map map = load(rounded_rectangle(1800.0, 1800.0, {400.0, 400.0, 400.0, 100.0}, 30.0));
  TrackSpec spec;
  spec.length_m = map.loop_length_m;
  const TrackReport r = check_track(map, spec);
  EXPECT_LT(r.min_radius_m, 101.0);  // the spline overshoots where the arc meets a straight
  EXPECT_GT(r.min_radius_m, 70.0);
  EXPECT_THAT(joined(r.problems), HasSubstr("min_radius_m"));
  EXPECT_FALSE(r.self_intersecting);
}

TEST(TrackCheck, FindsWideSpacing) {
  const Map map = load(rounded_rectangle(1800.0, 1800.0, {400.0, 400.0, 400.0, 400.0}, 150.0));
  TrackSpec spec;
  spec.length_m = map.loop_length_m;
  const TrackReport r = check_track(map, spec);
  EXPECT_NEAR(r.max_spacing_m, 150.0, 5.0);
  EXPECT_THAT(joined(r.problems), HasSubstr("max_spacing_m"));
}

TEST(TrackCheck, FindsAWrongLengthAndNoRightBend) {
  const Map map = load(rounded_rectangle(1800.0, 1800.0, {400.0, 400.0, 400.0, 400.0}, 35.0));
  const TrackReport r = check_track(map, TrackSpec{});  // 7000 m wanted; this is ~6500 m
  EXPECT_THAT(joined(r.problems), HasSubstr("length_m"));
  EXPECT_TRUE(r.bends_left);
  EXPECT_FALSE(r.bends_right);
  EXPECT_THAT(joined(r.problems), HasSubstr("no right bend"));
}

TEST(TrackCheck, FindsAClockwiseLoop) {
  // The same road driven the other way: reversed order, normals still right of travel.
  const std::vector<Waypoint> w = generate_track(spec_with(1));
  std::vector<Waypoint> rev;
  double s = 0.0;
  for (auto it = w.rbegin(); it != w.rend(); ++it) {
    if (!rev.empty()) s += std::hypot(it->x_m - rev.back().x_m, it->y_m - rev.back().y_m);
    rev.push_back({it->x_m, it->y_m, s, -it->dx, -it->dy});
  }
  const TrackReport r = check_track(load(rev), spec_with(1));
  EXPECT_FALSE(r.counter_clockwise);
  EXPECT_THAT(joined(r.problems), HasSubstr("direction"));
}

TEST(TrackCheck, FindsNormalsTowardsTheDivider) {
  std::vector<Waypoint> w = generate_track(spec_with(1));
  for (Waypoint& p : w) {
    p.dx = -p.dx;
    p.dy = -p.dy;
  }
  const TrackReport r = check_track(load(w), spec_with(1));
  EXPECT_THAT(joined(r.problems), HasSubstr("normals"));
}

TEST(TrackCheck, ReportsAnUnusableMapInsteadOfThrowing) {
  Map map;
  map.source = "tiny";
  map.waypoints = {{0, 0, 0, 0, -1}, {10, 0, 10, 0, -1}};
  map.loop_length_m = 20.0;
  TrackReport r;
  EXPECT_NO_THROW(r = check_track(map, TrackSpec{}));
  EXPECT_FALSE(r.ok());
}

// ---- Bad specs ----

std::string spec_error(const TrackSpec& spec) {
  try {
    (void)generate_track(spec);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(no std::invalid_argument)";
}

TEST(TrackSpecValidation, ImpossibleSpecsThrowNamingTheField) {
  TrackSpec s;
  s.length_m = 500.0;
  EXPECT_THAT(spec_error(s), HasSubstr("length_m"));
  s = {};
  s.length_m = std::nan("");
  EXPECT_THAT(spec_error(s), HasSubstr("length_m"));
  s = {};
  s.length_m = 2500.0;  // no room for bends of 150 m
  EXPECT_THAT(spec_error(s), HasSubstr("length_m"));
  s = {};
  s.min_spacing_m = 100.0;
  EXPECT_THAT(spec_error(s), HasSubstr("min_spacing_m"));
  s = {};
  s.min_radius_m = std::numeric_limits<double>::infinity();
  EXPECT_THAT(spec_error(s), HasSubstr("min_radius_m"));
  s = {};
  s.min_radius_m = -1.0;
  EXPECT_THAT(spec_error(s), HasSubstr("min_radius_m"));
  s = {};
  s.max_spacing_m = std::nan("");
  EXPECT_THAT(spec_error(s), HasSubstr("max_spacing_m"));
  s = {};
  s.min_clearance_m = -5.0;
  EXPECT_THAT(spec_error(s), HasSubstr("min_clearance_m"));
  s = {};
  s.road.lane_count = 0;
  EXPECT_THAT(spec_error(s), HasSubstr("road.lane_count"));
  s = {};
  s.straight_spacing_m = 0.0;
  EXPECT_THAT(spec_error(s), HasSubstr("straight_spacing_m"));
  s = {};
  s.max_abs_coordinate_m = 500.0;  // a 7 km loop does not fit a 1 km box
  EXPECT_THAT(spec_error(s), HasSubstr("max_abs_coordinate_m"));
}

TEST(TrackSpecValidation, CheckingRejectsAMalformedSpec) {
  TrackSpec s;
  s.max_spacing_m = 10.0;
  const Map map = load(rounded_rectangle(1800.0, 1800.0, {400.0, 400.0, 400.0, 400.0}, 35.0));
  EXPECT_THROW((void)check_track(map, s), std::invalid_argument);
}

// ---- The reference line of a generated track ----

TEST(TrackReferenceLineRoundTrip, FrenetToCartesianAndBackAroundTheWholeLoop) {
  const Map map = load(generate_track(spec_with(1)));
  const ReferenceLine line(map);
  const double length = line.length_m();
  const int steps = static_cast<int>(std::lround((length + 100.0) / 20.0));
  const double ds = (length + 100.0) / steps;
  int checked = 0;
  for (int i = 0; i <= steps; ++i) {
    const double s = -50.0 + ds * i;  // 50 m either side of the wrap
    for (double d = -1.0; d <= 13.0; d += 1.0) {
      const Vec2 p = line.to_cartesian({s, d});
      const std::optional<double> hints[] = {std::nullopt, s, s + 7.0, s - 7.0};
      for (const auto& hint : hints) {
        const FrenetPoint f = line.to_frenet(p, hint);
        ASSERT_NEAR(line.s_ahead(s, f.s_m), 0.0, kRoundTripTolM)
            << "s " << s << " d " << d << (hint ? " hint " + std::to_string(*hint) : "");
        ASSERT_NEAR(f.d_m, d, kRoundTripTolM) << "s " << s << " d " << d;
        ASSERT_LT(distance(line.to_cartesian(f), p), kRoundTripTolM) << "s " << s << " d " << d;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 20000);
}

TEST(TrackGenerate, TheCheckedTrackIsItsTextReadBackAndPassesItsCheck) {
  const TrackSpec spec = spec_with(6);
  const GeneratedTrack t = generate_checked_track(spec, "gen.csv");
  EXPECT_EQ(t.text, format_map(generate_track(spec)));
  EXPECT_EQ(t.map.waypoints.size(), generate_track(spec).size());
  EXPECT_EQ(t.map.source, "gen.csv");
  EXPECT_TRUE(t.check.problems.empty());
  EXPECT_GT(t.check.min_radius_m, 0.0);
}

}  // namespace
}  // namespace overtake::core
