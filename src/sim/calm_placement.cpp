// Calm traffic's placement: cars are put between waypoints behind or ahead of the ego, as the
// original places them, where they have room to brake; all of them at the start, then in
// batches as they fall far behind or ahead.

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "calm_internal.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/units.hpp"

namespace overtake::sim {
namespace {

/// Spawn room in a lane: car length + this + the braking distance.
constexpr double kSpawnMarginM = 1.0;
/// Last resort of the initial placement: ego + this + kFallbackStepM * k, lane k mod count.
constexpr double kFallbackAheadM = 150.0;
constexpr double kFallbackStepM = 10.0;
constexpr int kFallbackTries = 1000;

}  // namespace

void CalmImpl::regions(const CalmTraffic& t, double ego_s, Region& behind, Region& ahead_region) {
  const TrafficParams& p = t.params_;
  const auto n = static_cast<long>(t.map_.waypoints.size());
  const long prev = (static_cast<long>(next_waypoint(t, ego_s)) + n - 1) % n;
  const double limit = 0.9 * p.placement.despawn_distance_m;
  auto clamp_pair = [limit](double a, double b, Region& r) {
    a = std::clamp(a, -limit, limit);
    b = std::clamp(b, -limit, limit);
    r.lo_m = std::min(a, b);
    r.hi_m = std::max(a, b);
  };
  clamp_pair(-forward(t, waypoint_s(t, prev - p.placement.behind_max_waypoints), ego_s),
             -forward(t, waypoint_s(t, prev - p.placement.behind_min_waypoints), ego_s), behind);
  behind.min_speed_mps = p.placement.behind_min_speed_mps;
  behind.max_speed_mps = p.placement.behind_max_speed_mps;
  clamp_pair(forward(t, ego_s, waypoint_s(t, prev + p.placement.ahead_min_waypoints)),
             forward(t, ego_s, waypoint_s(t, prev + p.placement.ahead_max_waypoints)),
             ahead_region);
  ahead_region.min_speed_mps = p.placement.ahead_min_speed_mps;
  ahead_region.max_speed_mps = p.placement.ahead_max_speed_mps;
}

double CalmImpl::worst_closing_m(double v_f, double v_l, double decel_l, double b) {
  double worst = 0.0;
  if (v_f > v_l && b > decel_l) {
    const double t_equal = (v_f - v_l) / (b - decel_l);
    if (decel_l <= 0.0 || t_equal <= v_l / decel_l) {
      worst = (v_f - v_l) * (v_f - v_l) / (2.0 * (b - decel_l));
    }
  }
  if (decel_l > 0.0) {
    worst = std::max(worst, v_f * v_f / (2.0 * b) - v_l * v_l / (2.0 * decel_l));
  }
  return worst;
}

bool CalmImpl::room_to_brake(const CalmTraffic& t, double s, double v, double other_s,
                             double other_v, double other_accel) {
  const double gap = ahead(t, s, other_s);
  const double b = t.params_.calm.spawn_brake_mps2;
  const double closing = gap >= 0.0 ? worst_closing_m(v, other_v, std::max(0.0, -other_accel), b)
                                    : worst_closing_m(other_v, v, 0.0, b);
  return std::abs(gap) >= t.car_.length_m + kSpawnMarginM + closing;
}

CalmImpl::EgoSpot CalmImpl::ego_spot(const CalmTraffic& t, const EgoView& ego) {
  EgoSpot e;
  e.s_m = t.line_.wrap_s(ego.frenet.s_m);
  e.position = t.line_.to_cartesian({e.s_m, ego.frenet.d_m});
  e.lanes = ego_lanes(t, ego.frenet.d_m);
  e.speed_mps = ego.speed_mps;
  // During a step the ego's last acceleration is known (the last vehicle); not before.
  e.accel_mps2 =
      !t.vehicles_.empty() && t.vehicles_.back().car < 0 ? t.vehicles_.back().accel_mps2 : 0.0;
  return e;
}

bool CalmImpl::spot_ok(const CalmTraffic& t, int i, int limit, double s, double d, int lane,
                       double speed, const EgoSpot& ego) {
  const TrafficParams& p = t.params_;
  const core::Vec2 pos = t.line_.to_cartesian({s, d});
  const double min_sq = p.placement.min_spawn_distance_m * p.placement.min_spawn_distance_m;
  if (core::distance_sq(pos, ego.position) < min_sq) return false;
  if ((ego.lanes & lane_bit(lane)) != 0 &&
      !room_to_brake(t, s, speed, ego.s_m, ego.speed_mps, ego.accel_mps2)) {
    return false;
  }
  for (int j = 0; j < limit; ++j) {
    if (j == i) continue;
    const CalmCar& o = t.cars_[static_cast<std::size_t>(j)];
    if (core::distance_sq(pos, t.positions_[static_cast<std::size_t>(j)]) < min_sq) return false;
    if ((follow_lanes(t, o) & lane_bit(lane)) != 0 &&
        !room_to_brake(t, s, speed, o.s_m, o.speed_mps, o.accel_mps2)) {
      return false;
    }
  }
  return true;
}

void CalmImpl::commit(CalmTraffic& t, CalmCar& c, double s, int lane, double cruise, double phase,
                      double omega) {
  const double amp = t.params_.calm.wander_amplitude_m;
  c.s_m = s;
  c.lane = lane;
  c.wander_phase_rad = phase;
  c.wander_omega_rps = omega;
  c.lane_offset_m = amp * std::sin(phase);
  c.d_m = core::lane_center_d(lane, t.road_) + c.lane_offset_m;
  c.d_rate_mps = amp * omega * std::min(1.0, cruise / kFullLateralPaceMps) * std::cos(phase);
  c.cruise_mps = cruise;
  c.speed_mps = cruise;
  c.accel_mps2 = 0.0;
  c.manoeuvre.reset();
  c.since_lane_change_s = 1e9;
  c.held_up = false;
  c.since_held_up_s = 1e9;
  c.far = false;
}

CalmImpl::Wander CalmImpl::draw_wander(const CalmTraffic& t, CalmCar& c) {
  const TrafficParams& p = t.params_;
  const double period = c.rng.uniform(p.calm.wander_min_period_s, p.calm.wander_max_period_s);
  Wander w;
  w.omega_rps = period > 0.0 ? 2.0 * core::kPi / period : 0.0;
  w.phase_rad = c.rng.uniform(0.0, 2.0 * core::kPi);
  return w;
}

void CalmImpl::cache_positions(CalmTraffic& t, int limit) {
  for (int j = 0; j < limit; ++j) {
    const CalmCar& o = t.cars_[static_cast<std::size_t>(j)];
    t.positions_[static_cast<std::size_t>(j)] = t.line_.to_cartesian({o.s_m, o.d_m});
  }
}

bool CalmImpl::try_place(CalmTraffic& t, int i, int limit, const EgoView& ego_view, bool initial,
                         Where where) {
  const TrafficParams& p = t.params_;
  CalmCar& c = t.cars_[static_cast<std::size_t>(i)];
  const EgoSpot ego = ego_spot(t, ego_view);
  cache_positions(t, limit);
  Region behind;
  Region ahead_region;
  regions(t, ego.s_m, behind, ahead_region);
  const Wander w = draw_wander(t, c);
  const double offset = p.calm.wander_amplitude_m * std::sin(w.phase_rad);
  for (int attempt = 0; attempt < p.placement.max_spawn_attempts; ++attempt) {
    const bool is_behind = where == Where::either
                               ? t.spawn_rng_.chance(p.placement.behind_probability)
                               : where == Where::behind;
    const Region& r = is_behind ? behind : ahead_region;
    const double off = t.spawn_rng_.uniform(r.lo_m, r.hi_m);
    const int lane = t.spawn_rng_.uniform_int(0, t.road_.lane_count - 1);
    const double cruise = t.spawn_rng_.uniform(r.min_speed_mps, r.max_speed_mps);
    if (initial && is_behind && (ego.lanes & lane_bit(lane)) != 0) continue;
    const double s = t.line_.wrap_s(ego.s_m + off);
    const double d = core::lane_center_d(lane, t.road_) + offset;
    if (!spot_ok(t, i, limit, s, d, lane, cruise, ego)) continue;
    commit(t, c, s, lane, cruise, w.phase_rad, w.omega_rps);
    return true;
  }
  return false;
}

void CalmImpl::place_fallback(CalmTraffic& t, int i, const EgoView& ego_view) {
  const TrafficParams& p = t.params_;
  CalmCar& c = t.cars_[static_cast<std::size_t>(i)];
  const EgoSpot ego = ego_spot(t, ego_view);
  cache_positions(t, i);
  const Wander w = draw_wander(t, c);
  const double offset = p.calm.wander_amplitude_m * std::sin(w.phase_rad);
  const double cruise =
      t.spawn_rng_.uniform(p.placement.ahead_min_speed_mps, p.placement.ahead_max_speed_mps);
  double s = ego.s_m;
  int lane = 0;
  for (int k = 0; k < kFallbackTries; ++k) {
    s = t.line_.wrap_s(ego.s_m + kFallbackAheadM + kFallbackStepM * k);
    lane = k % t.road_.lane_count;
    if (spot_ok(t, i, i, s, core::lane_center_d(lane, t.road_) + offset, lane, cruise, ego)) {
      break;
    }
  }
  commit(t, c, s, lane, cruise, w.phase_rad, w.omega_rps);
}

}  // namespace overtake::sim
