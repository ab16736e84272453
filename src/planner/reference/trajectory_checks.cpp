// The checks of the trajectory layer over samples: collision with the predicted cars, and
// speed, acceleration and jerk in Cartesian space.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "overtake/core/units.hpp"
#include "overtake/planner/reference/behaviour.hpp"
#include "trajectory_internal.hpp"

namespace overtake::planner::reference {
namespace trajectory_detail {
namespace {

/// Slowest speed used when turning a lateral speed into a heading.
constexpr double kMinHeadingSpeedMps = 3.0;
/// Cars farther than this along the road are not considered.
constexpr double kRelevantM = 200.0;
/// A car speeding up harder than this is not taken to brake early for the ego.
constexpr double kSpeedingUpMps2 = 1.0;
/// A follower's sensor meets the ego once the ego's middle is this close sideways to its own.
constexpr double kSensorCoverM = 0.8;
/// Margin (m) of a bound on the lateral clearance needed, far beyond its rounding.
constexpr double kClearSidewaysM = 1e-6;

}  // namespace

std::vector<CarSamples> sample_cars(const std::vector<CarPrediction>& cars, double delay, double s0,
                                    const Grid& g, SpareBuffers* spare) {
  std::vector<CarSamples> out;
  out.reserve(cars.size());
  for (const CarPrediction& c : cars) {
    if (std::abs(c.s_m - s0) > kRelevantM) continue;
    CarSamples cs;
    cs.id = c.id;
    cs.cap_mps = c.cap_mps;
    cs.speeding_up = c.observed_accel_mps2 > kSpeedingUpMps2;
    const auto n = static_cast<std::size_t>(g.n + 1);
    if (spare) cs.buffer = take_buffer(*spare);
    cs.resize(n);
    for (int k = 0; k <= g.n; ++k) {
      const double t = delay + g.t(k);
      const auto i = static_cast<std::size_t>(k);
      cs.s[i] = c.s_at(t);
      cs.s_dot[i] = c.s_dot_at(t);
    }
    if (c.changing) {
      for (int k = 0; k <= g.n; ++k) {
        const double t = delay + g.t(k);
        const auto i = static_cast<std::size_t>(k);
        cs.d[i] = c.d_at(t);
        cs.d_dot[i] = c.d_dot_at(t);
      }
    } else {
      // Keeping its lane: the same d (and no lateral speed) at every time.
      std::fill(cs.d.begin(), cs.d.end(), c.d_at(0.0));
      std::fill(cs.d_dot.begin(), cs.d_dot.end(), c.d_dot_at(0.0));
    }
    out.push_back(std::move(cs));
  }
  return out;
}

// A car behind the ego is the ego's concern only when the ego moves across its path: a
// follower reacts to one ray straight ahead from the middle of its front, so it does not
// react to the ego until the ego's middle is within kSensorCoverM of its own sideways. Until
// then it keeps going (and must not reach the ego); once it sees the ego within its reaction
// gap, it must have room to stop closing (rear_room).
CollisionReport collide(const Track1d& lon, const Track1d& lat, bool ego_changing, bool sideways,
                        const Grid& g, const std::vector<CarSamples>& cars, double m_per_unit_s,
                        const ReferenceParams& p, const core::CarFootprint& car) {
  const double length = car.length_m;
  const double lon_need = length + p.trajectory.lon_margin_m;
  const double lat_base = car.width_m + p.trajectory.lat_margin_m;
  const double react_gap = p.behaviour.follower_reaction_gap_m;
  const double guard_s = p.trajectory.unseen_guard_s;
  const double lat_need_per_mps = 0.5 * length / kMinHeadingSpeedMps;
  CollisionReport r;
  for (const CarSamples& c : cars) {
    bool seen = false;
    bool follower = false;
    for (int k = 0; k <= g.n; ++k) {
      const auto e = static_cast<std::size_t>(k + kBack);
      const auto i = static_cast<std::size_t>(k);
      const double t = g.t(k);
      if (t >= r.first_collision_s) break;
      const double side_gap = std::abs(lat.x[e] - c.d[i]);
      // Clear sideways by more than the most lat_need can be (both headings at their slowest
      // speed, and a margin far beyond rounding): no need to work it out.
      bool clear_sideways =
          side_gap >= lat_base + lat_need_per_mps * (std::abs(lat.v[e]) + std::abs(c.d_dot[i])) +
                          kClearSidewaysM;
      if (!clear_sideways) {
        const double ve = std::max(lon.v[e] * m_per_unit_s, kMinHeadingSpeedMps);
        const double vc = std::max(c.s_dot[i] * m_per_unit_s, kMinHeadingSpeedMps);
        const double lat_need =
            lat_base + 0.5 * length * (std::abs(lat.v[e]) / ve + std::abs(c.d_dot[i]) / vc);
        clear_sideways = side_gap >= lat_need;
      }
      if (clear_sideways) {
        if (follower) break;  // the ego has left its path
        continue;
      }
      double ahead = (c.s[i] - lon.x[e]) * m_per_unit_s;
      if (!follower) {
        if (ahead < 0.0 && (k == 0 || (!seen && ego_changing))) {
          // It follows the ego already and sees it (its business), or the ego moves in
          // front of it.
          if (k == 0 && !sideways) break;
          follower = true;
        } else {
          if (std::abs(ahead) < lon_need) {
            r = {false, t, c.id, ahead < 0.0};
            break;
          }
          seen = true;
          if (ahead < 0.0) break;  // from here on it follows the ego
          continue;
        }
      }
      // Against a follower the ego counts on no speed it has not got yet: plans change, and a
      // change of lanes already begun is hard to undo.
      const double steady_s = lon.x[kBack] + lon.v[kBack] * t;
      const double own_s = std::min(lon.x[e], steady_s);
      const double own_v = std::min(lon.v[e], lon.v[kBack]);
      ahead = (c.s[i] - own_s) * m_per_unit_s;
      const double closing = (c.s_dot[i] - own_v) * m_per_unit_s;
      // Once it sees the ego it reacts within 0.5 m * (its cap in mph - the ego's speed in
      // m/s), bumper to bumper; never later than the behaviour's follower reaction gap. One
      // speeding up hard is taken to react only that late.
      const double sees_at =
          c.speeding_up
              ? react_gap
              : std::max(react_gap, p.prediction.reaction_gain_m *
                                            (core::mps_to_mph(c.cap_mps) - own_v * m_per_unit_s) +
                                        length);
      if (side_gap < kSensorCoverM && -ahead <= sees_at) {
        if (rear_room(-ahead, closing, length, p.behaviour, sees_at) < 0.0)
          r = {false, t, c.id, true};
        break;
      }
      if (-ahead < lon_need) {
        r = {false, t, c.id, true};
        break;
      }
      // The plan ends with the ego across its path, unseen: it keeps coming.
      if (k == g.n && side_gap >= kSensorCoverM && closing > 0.0 &&
          -ahead - lon_need < closing * guard_s) {
        r = {false, t, c.id, true};
      }
    }
  }
  return r;
}

KinematicReport kinematics(const Track1d& lon, const Track1d& lat, const Grid& g,
                           const LaneFrame& line, const ReferenceTrajectoryParams& p,
                           bool stop_at_first, const std::vector<FrenetState>& history) {
  KinematicReport r;
  const double h2 = g.h * g.h;
  const double h3 = h2 * g.h;
  // Stopping at the first sample over a limit, a sample whose squared figures are well within
  // the limits squared (by far more than any rounding of the squares, norms and divisions) is
  // within them: its norms are left out. (So the peaks are those of the samples not left out.)
  // (A limit that is not positive leaves out nothing.)
  constexpr double kClearShare = 1.0 - 1e-9;
  const auto clear_below = [](double limit) {
    return limit > 0.0 ? limit * limit * kClearShare : 0.0;
  };
  const double speed_clear = clear_below(p.max_speed_mps);
  const double accel_clear = clear_below(p.max_accel_mps2 * h2);
  const double jerk_clear = clear_below(p.max_jerk_mps3 * h3);
  core::Vec2 back[4];  // positions k, k-1, k-2, k-3
  for (int k = -kBack; k <= g.n; ++k) {
    const auto e = static_cast<std::size_t>(k + kBack);
    const auto past = static_cast<std::size_t>(-k - 1);
    const bool driven = k < 0 && past < history.size();
    const RoadPoint at = driven ? road_point(line, history[past].s_m, history[past].d_m)
                                : road_point(line, lon.x[e], lat.x[e]);
    back[3] = back[2];
    back[2] = back[1];
    back[1] = back[0];
    back[0] = at.position;
    if (k < 0) continue;
    const double t = g.t(k);
    const double along = lon.v[e] * at.along_scale;
    const double across = lat.v[e] - at.offset_slope * lon.v[e];
    const core::Vec2 accel_h2 = back[0] - 2.0 * back[1] + back[2];
    const core::Vec2 jerk_h3 = back[0] - 3.0 * back[1] + 3.0 * back[2] - back[3];
    if (stop_at_first && along * along + across * across < speed_clear &&
        core::dot(accel_h2, accel_h2) < accel_clear && core::dot(jerk_h3, jerk_h3) < jerk_clear)
      continue;
    const double speed = std::hypot(along, across);
    const double accel = core::norm(accel_h2) / h2;
    const double jerk = core::norm(jerk_h3) / h3;
    r.peak_speed_mps = std::max(r.peak_speed_mps, speed);
    r.peak_accel_mps2 = std::max(r.peak_accel_mps2, accel);
    r.peak_jerk_mps3 = std::max(r.peak_jerk_mps3, jerk);
    if (speed > p.max_speed_mps || accel > p.max_accel_mps2 || jerk > p.max_jerk_mps3) {
      if (r.ok) r.first_violation_s = t;
      r.ok = false;
      if (stop_at_first) return r;
    }
  }
  return r;
}

}  // namespace trajectory_detail

using namespace trajectory_detail;

KinematicReport check_kinematics(const Trajectory& t, const LaneFrame& line,
                                 const ReferenceTrajectoryParams& p) {
  const Grid g = grid_of(p);
  const Track1d lon = sample(g, LongitudinalSampler{t.longitudinal});
  const Track1d lat = sample(g, PolynomialSampler{t.lateral});
  return kinematics(lon, lat, g, line, p, false);
}

CollisionReport check_collisions(const Trajectory& t, const std::vector<CarPrediction>& cars,
                                 double start_delay_s, double m_per_unit_s,
                                 const ReferenceParams& p, const core::RoadParams& road,
                                 const core::CarFootprint& car) {
  const Grid g = grid_of(p.trajectory);
  const Track1d lon = sample(g, LongitudinalSampler{t.longitudinal});
  const Track1d lat = sample(g, PolynomialSampler{t.lateral});
  const double d0 = lat.x[kBack];
  const bool changing = core::lane_of(d0, road) != t.end_lane;
  const bool sideways =
      changing || std::abs(d0 - core::lane_center_d(core::lane_of(d0, road), road)) > kSidewaysM;
  return collide(lon, lat, changing, sideways, g, sample_cars(cars, start_delay_s, lon.x[kBack], g),
                 m_per_unit_s, p, car);
}

}  // namespace overtake::planner::reference
