// Calm traffic's driving: IDM following (Treiber, Hennecke, Helbing 2000) with the ACC model's
// blend (Kesting, Treiber, Helbing 2010), MOBIL lane changes (Kesting, Treiber, Helbing 2007),
// and each car's motion along and across its lane.

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <optional>

#include "calm_internal.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/units.hpp"

namespace overtake::sim {
namespace {

constexpr double kTimeEpsilonS = 1e-9;
/// IDM's gap is never taken below this (avoids dividing by zero).
constexpr double kMinIdmGapM = 0.01;
constexpr double kMinDesiredSpeedMps = 0.1;
/// The ACC model's coolness factor (Kesting, Treiber, Helbing 2010).
constexpr double kCoolness = 0.99;

/// Minimum-jerk lateral profile: position fraction and its derivative in tau.
[[nodiscard]] constexpr double min_jerk(double tau) {
  return tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
}
[[nodiscard]] constexpr double min_jerk_rate(double tau) {
  return tau * tau * (30.0 + tau * (-60.0 + 30.0 * tau));
}

}  // namespace

void CalmImpl::build_vehicles(CalmTraffic& t, const EgoView& ego, double ego_s, double dt) {
  const std::size_t n = t.cars_.size();
  t.vehicles_.resize(n + 1);
  for (std::size_t i = 0; i < n; ++i) {
    const CalmCar& c = t.cars_[i];
    Vehicle& v = t.vehicles_[i];
    v.s_m = c.s_m;
    v.speed_mps = c.speed_mps;
    v.accel_mps2 = c.accel_mps2;
    v.now_lanes = now_lanes(t, c);
    v.follow_lanes = follow_lanes(t, c);
    v.car = static_cast<int>(i);
  }
  Vehicle& e = t.vehicles_[n];
  e.s_m = ego_s;
  e.speed_mps = ego.speed_mps;
  // The ego's acceleration, from its speed at the previous step (0 at the first).
  e.accel_mps2 = t.ego_prev_speed_mps_ >= 0.0 ? (ego.speed_mps - t.ego_prev_speed_mps_) / dt : 0.0;
  e.now_lanes = e.follow_lanes = ego_lanes(t, ego.frenet.d_m);
  e.car = -1;
}

CalmImpl::Nearest CalmImpl::leader(const CalmTraffic& t, int self, unsigned lanes, int skip) {
  Nearest best;
  const double s = t.vehicles_[static_cast<std::size_t>(self)].s_m;
  const int count = static_cast<int>(t.vehicles_.size());
  for (int j = 0; j < count; ++j) {
    const Vehicle& v = t.vehicles_[static_cast<std::size_t>(j)];
    if (j == self || j == skip || (v.follow_lanes & lanes) == 0) continue;
    const double gap = ahead(t, s, v.s_m);
    if (gap > 0.0 && gap < best.gap_m) best = {j, gap};
  }
  return best;
}

double CalmImpl::idm(const CalmTraffic& t, double v, double v0, double gap_m, double leader_speed) {
  const CalmTrafficParams& p = t.params_.calm;
  const double ratio = v / std::max(v0, kMinDesiredSpeedMps);
  const double free_term = p.accel_exponent == 4.0 ? (ratio * ratio) * (ratio * ratio)
                                                   : std::pow(ratio, p.accel_exponent);
  double interaction = 0.0;
  if (gap_m < kInf) {
    const double s = std::max(gap_m - t.car_.length_m, kMinIdmGapM);
    const double dynamic =
        v * p.time_headway_s +
        v * (v - leader_speed) / (2.0 * std::sqrt(p.max_accel_mps2 * p.comfort_decel_mps2));
    const double s_star = p.min_gap_m + std::max(0.0, dynamic);
    interaction = (s_star / s) * (s_star / s);
  }
  return p.max_accel_mps2 * (1.0 - free_term - interaction);
}

double CalmImpl::cah(const CalmTraffic& t, double v, double leader_speed, double leader_accel,
                     double bumper_gap_m) {
  const double a_l = std::min(leader_accel, t.params_.calm.max_accel_mps2);
  const double denom = leader_speed * leader_speed - 2.0 * bumper_gap_m * a_l;
  if (leader_speed * (v - leader_speed) <= -2.0 * bumper_gap_m * a_l && denom > 1e-9) {
    return v * v * a_l / denom;
  }
  const double closing = std::max(0.0, v - leader_speed);
  return a_l - closing * closing / (2.0 * bumper_gap_m);
}

double CalmImpl::applied_accel(const CalmTraffic& t, int self, int lead, double gap_m,
                               double a_idm) {
  const CalmTrafficParams& p = t.params_.calm;
  double a = a_idm;
  if (lead >= 0) {
    const Vehicle& sv = t.vehicles_[static_cast<std::size_t>(self)];
    const Vehicle& lv = t.vehicles_[static_cast<std::size_t>(lead)];
    const double s = std::max(gap_m - t.car_.length_m, kMinIdmGapM);
    const double a_cah = cah(t, sv.speed_mps, lv.speed_mps, lv.accel_mps2, s);
    if (a_idm < a_cah) {
      const double b = p.comfort_decel_mps2;
      a = (1.0 - kCoolness) * a_idm + kCoolness * (a_cah + b * std::tanh((a_idm - a_cah) / b));
    }
  }
  return std::max(a, -p.max_brake_mps2);
}

double CalmImpl::desired_speed(const CalmTraffic& t, const Vehicle& v) {
  return v.car >= 0 ? t.cars_[static_cast<std::size_t>(v.car)].cruise_mps : v.speed_mps;
}

double CalmImpl::idm_of(const CalmTraffic& t, int k, int lead, double gap_m) {
  const Vehicle& v = t.vehicles_[static_cast<std::size_t>(k)];
  if (lead < 0) return idm(t, v.speed_mps, desired_speed(t, v), kInf, 0.0);
  return idm(t, v.speed_mps, desired_speed(t, v), gap_m,
             t.vehicles_[static_cast<std::size_t>(lead)].speed_mps);
}

std::optional<double> CalmImpl::mobil(const CalmTraffic& t, int i, int lane, double best) {
  const CalmTrafficParams& p = t.params_.calm;
  const unsigned target = lane_bit(lane);
  const double s = t.vehicles_[static_cast<std::size_t>(i)].s_m;
  const double too_close = t.car_.length_m + p.min_gap_m;
  // One pass over the target lane: overlap, new leader, new follower.
  Nearest nl;
  Nearest nf;
  const int count = static_cast<int>(t.vehicles_.size());
  for (int j = 0; j < count; ++j) {
    const Vehicle& v = t.vehicles_[static_cast<std::size_t>(j)];
    if (j == i || (v.follow_lanes & target) == 0) continue;
    const double gap = ahead(t, s, v.s_m);
    if (std::abs(gap) < too_close) return std::nullopt;
    if (gap > 0.0) {
      if (gap < nl.gap_m) nl = {j, gap};
    } else if (-gap < nf.gap_m) {
      nf = {j, -gap};
    }
  }
  // Own advantage in the target lane.
  const double a_self_after = idm_of(t, i, nl.vehicle, nl.gap_m);
  if (a_self_after < -p.safe_decel_mps2) return std::nullopt;
  const double a_self = t.decisions_[static_cast<std::size_t>(i)].idm_mps2;
  // Old followers: the cars that follow i now, once i has gone.
  double of_gain = 0.0;
  const int n = static_cast<int>(t.cars_.size());
  for (int k = 0; k < n; ++k) {
    const Decision& kd = t.decisions_[static_cast<std::size_t>(k)];
    if (k == i || kd.leader != i) continue;
    const Nearest next = leader(t, k, t.vehicles_[static_cast<std::size_t>(k)].follow_lanes, i);
    of_gain += idm_of(t, k, next.vehicle, next.gap_m) - kd.idm_mps2;
  }
  // The new follower can only lose: without it, this bounds the incentive.
  if (a_self_after - a_self + p.politeness * of_gain <= best) return std::nullopt;
  double nf_gain = 0.0;
  if (nf.vehicle >= 0) {
    const Vehicle& fv = t.vehicles_[static_cast<std::size_t>(nf.vehicle)];
    const double a_behind_i = idm_of(t, nf.vehicle, i, nf.gap_m);
    double a_after = a_behind_i;
    if (fv.car >= 0) {
      // Whichever asks more of it: its present leader, or car i in front of it.
      const Decision& fd = t.decisions_[static_cast<std::size_t>(fv.car)];
      a_after = std::min(fd.idm_mps2, a_behind_i);
      nf_gain = a_after - fd.idm_mps2;
    }
    if (a_after < -p.safe_decel_mps2) return std::nullopt;
  }
  const double incentive = a_self_after - a_self + p.politeness * (nf_gain + of_gain);
  if (incentive <= best) return std::nullopt;
  return incentive;
}

bool CalmImpl::changes_conflict(const CalmTraffic& t, int i, int j) {
  const CalmTrafficParams& p = t.params_.calm;
  const double gap = ahead(t, t.vehicles_[static_cast<std::size_t>(i)].s_m,
                           t.vehicles_[static_cast<std::size_t>(j)].s_m);
  if (std::abs(gap) < t.car_.length_m + p.min_gap_m) return true;
  const int back = gap > 0.0 ? i : j;
  const int front = gap > 0.0 ? j : i;
  return idm_of(t, back, front, std::abs(gap)) < -p.safe_decel_mps2;
}

void CalmImpl::decide_calm(CalmTraffic& t, double dt) {
  const CalmTrafficParams& p = t.params_.calm;
  const int n = static_cast<int>(t.cars_.size());
  for (int i = 0; i < n; ++i) {
    CalmCar& c = t.cars_[static_cast<std::size_t>(i)];
    Decision& dec = t.decisions_[static_cast<std::size_t>(i)];
    dec = Decision{};
    // The nearest vehicle ahead in each lane it occupies (two during a lane change): the
    // one that asks for the lowest acceleration leads. (With one lane, simply the nearest;
    // with two, a slow car in one lane is not hidden by a nearer, faster one in the other.)
    dec.idm_mps2 = kInf;
    dec.accel_mps2 = kInf;
    const unsigned lanes = t.vehicles_[static_cast<std::size_t>(i)].follow_lanes;
    for (int lane = 0; lane < t.road_.lane_count; ++lane) {
      if ((lanes & lane_bit(lane)) == 0) continue;
      const Nearest lead = leader(t, i, lane_bit(lane));
      const double a_idm = idm_of(t, i, lead.vehicle, lead.gap_m);
      dec.accel_mps2 =
          std::min(dec.accel_mps2, applied_accel(t, i, lead.vehicle, lead.gap_m, a_idm));
      if (a_idm < dec.idm_mps2) {
        dec.idm_mps2 = a_idm;
        dec.leader = lead.vehicle;
        dec.leader_gap_m = lead.gap_m;
      }
    }
    dec.new_speed_mps = std::max(0.0, c.speed_mps + dec.accel_mps2 * dt);
    // Held up: a leader makes it accelerate less than the free road would.
    const bool react =
        dec.leader >= 0 && dec.idm_mps2 < idm(t, c.speed_mps, c.cruise_mps, kInf, 0.0) - 1e-9;
    c.held_up = react;
    c.since_held_up_s = react ? 0.0 : c.since_held_up_s + dt;
  }
  for (int i = 0; i < n; ++i) {
    const CalmCar& c = t.cars_[static_cast<std::size_t>(i)];
    if (c.manoeuvre || c.since_lane_change_s < p.lane_change_interval_s - kTimeEpsilonS) continue;
    double best = p.change_threshold_mps2;
    for (const int cand : {c.lane - 1, c.lane + 1}) {
      if (cand < 0 || cand >= t.road_.lane_count) continue;
      const std::optional<double> gain = mobil(t, i, cand, best);
      if (gain) {
        best = *gain;
        t.decisions_[static_cast<std::size_t>(i)].change_to_lane = cand;
      }
    }
  }
  // Two cars deciding in the same frame do not see each other's change: the later one
  // waits when both move into the same lane too close together.
  for (int j = 0; j < n; ++j) {
    Decision& dj = t.decisions_[static_cast<std::size_t>(j)];
    if (dj.change_to_lane < 0) continue;
    for (int i = 0; i < j; ++i) {
      const Decision& di = t.decisions_[static_cast<std::size_t>(i)];
      if (di.change_to_lane == dj.change_to_lane && changes_conflict(t, i, j)) {
        dj.change_to_lane = -1;
        break;
      }
    }
  }
}

double CalmImpl::lane_metres_per_s(const CalmTraffic& t, std::size_t i, double s, double d) {
  if (i < t.lane_scales_.size()) {
    const CalmTraffic::LaneScale& k = t.lane_scales_[i];
    if (k.valid && k.s_bits == std::bit_cast<std::uint64_t>(s) &&
        k.d_bits == std::bit_cast<std::uint64_t>(d)) {
      return k.metres_per_s;
    }
  }
  return t.line_.metres_per_s(t.line_.sample(s), d);
}

void CalmImpl::move(CalmTraffic& t, std::size_t i, const Decision& dec, double dt) {
  CalmCar& c = t.cars_[i];
  const TrafficParams& p = t.params_;
  const double d_before = c.d_m;
  c.accel_mps2 = (dec.new_speed_mps - c.speed_mps) / dt;
  c.speed_mps = dec.new_speed_mps;
  if (dec.change_to_lane >= 0) {
    c.manoeuvre =
        LaneManoeuvre{c.lane, dec.change_to_lane, c.d_m, 0.0, p.calm.lane_change_duration_s};
    c.lane = dec.change_to_lane;
    c.since_lane_change_s = 0.0;
    c.lane_offset_m = 0.0;
  } else {
    c.since_lane_change_s += dt;
  }
  const double pace = std::min(1.0, c.speed_mps / kFullLateralPaceMps);
  if (c.manoeuvre) {
    LaneManoeuvre& m = *c.manoeuvre;
    m.elapsed_s += dt * pace;
    const double to_d = core::lane_center_d(m.to_lane, t.road_);
    const double tau = m.duration_s > 0.0 ? std::min(1.0, m.elapsed_s / m.duration_s) : 1.0;
    if (tau >= 1.0) {
      // Arrived: wander resumes from phase 0 (offset 0), so d is continuous.
      c.d_m = to_d;
      c.d_rate_mps = 0.0;
      c.manoeuvre.reset();
      c.wander_phase_rad = 0.0;
      c.lane_offset_m = 0.0;
    } else {
      c.d_m = m.from_d_m + (to_d - m.from_d_m) * min_jerk(tau);
      c.d_rate_mps = (to_d - m.from_d_m) * min_jerk_rate(tau) / m.duration_s * pace;
    }
  } else {
    c.wander_phase_rad =
        std::fmod(c.wander_phase_rad + c.wander_omega_rps * pace * dt, 2.0 * core::kPi);
    c.lane_offset_m = p.calm.wander_amplitude_m * std::sin(c.wander_phase_rad);
    c.d_m = core::lane_center_d(c.lane, t.road_) + c.lane_offset_m;
    c.d_rate_mps =
        p.calm.wander_amplitude_m * c.wander_omega_rps * pace * std::cos(c.wander_phase_rad);
  }
  // line_.s_rate({c.s_m, d_before}, c.speed_mps), the scale most often cached.
  const double ds = c.speed_mps / lane_metres_per_s(t, i, c.s_m, d_before) * dt;
  c.s_m = t.line_.wrap_s(c.s_m + ds);
}

}  // namespace overtake::sim
