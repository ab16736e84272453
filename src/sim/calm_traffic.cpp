#include "overtake/sim/calm_traffic.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>

#include "overtake/core/road.hpp"
#include "overtake/core/units.hpp"

namespace overtake::sim {
namespace {

constexpr std::uint64_t kSpawnStream = 0;
constexpr std::uint64_t kFirstCarStream = 100;
constexpr double kTimeEpsilonS = 1e-9;
/// Spawn room in a lane: car length + this + the braking distance.
constexpr double kSpawnMarginM = 1.0;
/// Last resort of the initial placement: ego + this + kFallbackStepM * k, lane k mod count.
constexpr double kFallbackAheadM = 150.0;
constexpr double kFallbackStepM = 10.0;
constexpr int kFallbackTries = 1000;
/// Lateral motion (lane changes, wander) runs at its full pace at this speed and above, and
/// slower below it in proportion, stopping when the car stands: a car does not move
/// sideways at a crawl. A 4 m change over 3 s peaks at 2.5 m/s sideways, so a car is never
/// more than ~20 degrees off its lane.
constexpr double kFullLateralPaceMps = 7.0;
/// Below this speed a footprint takes the road's heading instead of the velocity's.
constexpr double kStationaryMps = 0.1;
/// The ego counts in a lane when its d is within this of the lane's centre.
constexpr double kEgoLaneRadiusM = 3.0;
/// IDM's gap is never taken below this (avoids dividing by zero).
constexpr double kMinIdmGapM = 0.01;
constexpr double kMinDesiredSpeedMps = 0.1;
/// A car's body counts in a lane when it comes within this of it (sideways), beyond half
/// its width: room for its heading during a lane change.
constexpr double kBodyMarginM = 0.5;
/// The ACC model's coolness factor (Kesting, Treiber, Helbing 2010).
constexpr double kCoolness = 0.99;
constexpr double kInf = std::numeric_limits<double>::infinity();

[[nodiscard]] constexpr unsigned lane_bit(int lane) {
  return 1U << static_cast<unsigned>(lane);
}

/// Minimum-jerk lateral profile: position fraction and its derivative in tau.
[[nodiscard]] constexpr double min_jerk(double tau) {
  return tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
}
[[nodiscard]] constexpr double min_jerk_rate(double tau) {
  return tau * tau * (30.0 + tau * (-60.0 + 30.0 * tau));
}

}  // namespace

/// The implementation, as static helpers with access to CalmTraffic's state.
struct CalmImpl {
  using Vehicle = CalmTraffic::Vehicle;
  using Decision = CalmTraffic::Decision;

  struct Nearest {
    int vehicle = -1;  // index into vehicles_
    double gap_m = kInf;
  };

  struct Region {
    double lo_m = 0.0;  // along-road offset from the ego
    double hi_m = 0.0;
    double min_speed_mps = 0.0;
    double max_speed_mps = 0.0;
  };

  // ----- along-road geometry ---------------------------------------------------------------

  /// line.s_ahead for s values already wrapped (as every stored s is): the same result
  /// without the two fmods, since this runs for every pair of vehicles every step.
  [[nodiscard]] static double ahead(const CalmTraffic& t, double from_s, double to_s) {
    const double length = t.line_.length_m();
    double diff = to_s - from_s;
    if (diff > 0.5 * length) {
      diff -= length;
    } else if (diff <= -0.5 * length) {
      diff += length;
    }
    return diff;
  }

  /// Distance from `from_s` forward to `to_s`, in [0, length).
  [[nodiscard]] static double forward(const CalmTraffic& t, double from_s, double to_s) {
    const double length = t.line_.length_m();
    double r = std::fmod(to_s - from_s, length);
    if (r < 0.0) r += length;
    return r;
  }

  /// Index of the first waypoint ahead of s (strictly), wrapping to 0 past the last.
  [[nodiscard]] static std::size_t next_waypoint(const CalmTraffic& t, double s_wrapped) {
    const auto& w = t.map_.waypoints;
    const auto it = std::upper_bound(w.begin(), w.end(), s_wrapped,
                                     [](double s, const core::Waypoint& p) { return s < p.s_m; });
    return it == w.end() ? 0 : static_cast<std::size_t>(it - w.begin());
  }

  [[nodiscard]] static double waypoint_s(const CalmTraffic& t, long index) {
    const auto n = static_cast<long>(t.map_.waypoints.size());
    return t.map_.waypoints[static_cast<std::size_t>(((index % n) + n) % n)].s_m;
  }

  // ----- lanes -----------------------------------------------------------------------------

  [[nodiscard]] static unsigned ego_lanes(const CalmTraffic& t, double ego_d) {
    unsigned mask = 0;
    for (int k = 0; k < t.road_.lane_count; ++k) {
      if (std::abs(ego_d - core::lane_center_d(k, t.road_)) <
          kEgoLaneRadiusM) {
        mask |= lane_bit(k);
      }
    }
    return mask;
  }

  [[nodiscard]] static unsigned now_lanes(const CalmTraffic& t, const CalmCar& c) {
    return lane_bit(core::lane_of(c.d_m, t.road_));
  }

  /// Lanes a car occupies for following: every lane its body reaches into (half its width
  /// plus a margin either side of d), so that a car that has crossed a lane line keeps
  /// counting in the lane it is leaving; also the target lane of a lane change.
  [[nodiscard]] static unsigned follow_lanes(const CalmTraffic& t, const CalmCar& c) {
    unsigned mask = now_lanes(t, c);
    const double half = 0.5 * t.car_.width_m + kBodyMarginM;
    const int lo = core::lane_of(c.d_m - half, t.road_);
    const int hi = core::lane_of(c.d_m + half, t.road_);
    for (int k = lo; k <= hi; ++k) mask |= lane_bit(k);
    if (c.manoeuvre) mask |= lane_bit(c.manoeuvre->to_lane);
    return mask;
  }

  /// Fills vehicles_: the cars in order, then the ego.
  static void build_vehicles(CalmTraffic& t, const EgoView& ego, double ego_s, double dt) {
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
    e.accel_mps2 =
        t.ego_prev_speed_mps_ >= 0.0 ? (ego.speed_mps - t.ego_prev_speed_mps_) / dt : 0.0;
    e.now_lanes = e.follow_lanes = ego_lanes(t, ego.frenet.d_m);
    e.car = -1;
  }

  /// Nearest vehicle ahead (smallest positive gap) among those occupying any of `lanes`,
  /// other than `self` and `skip`.
  [[nodiscard]] static Nearest leader(const CalmTraffic& t, int self, unsigned lanes, int skip = -1) {
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

  // ----- calm profile ----------------------------------------------------------------------

  /// IDM acceleration (Treiber, Hennecke, Helbing 2000) of a vehicle at speed v wanting v0,
  /// `gap_m` centre to centre behind a leader at `leader_speed` (gap infinite: free road).
  /// Not clamped: MOBIL compares these, and a clamp would make every emergency look alike.
  [[nodiscard]] static double idm(const CalmTraffic& t, double v, double v0, double gap_m,
                                  double leader_speed) {
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

  /// The constant-acceleration heuristic of the ACC model (Kesting, Treiber, Helbing 2010):
  /// the deceleration that just avoids a collision if the leader keeps its acceleration.
  [[nodiscard]] static double cah(const CalmTraffic& t, double v, double leader_speed,
                                  double leader_accel, double bumper_gap_m) {
    const double a_l = std::min(leader_accel, t.params_.calm.max_accel_mps2);
    const double denom = leader_speed * leader_speed - 2.0 * bumper_gap_m * a_l;
    if (leader_speed * (v - leader_speed) <= -2.0 * bumper_gap_m * a_l && denom > 1e-9) {
      return v * v * a_l / denom;
    }
    const double closing = std::max(0.0, v - leader_speed);
    return a_l - closing * closing / (2.0 * bumper_gap_m);
  }

  /// The acceleration a calm car applies: IDM, except where IDM brakes harder than the
  /// situation needs (a gap far below the desired one, but not closing), where the ACC
  /// model's blend with the CAH takes over; then the physical braking limit. Without this,
  /// cars spawned ~6 m apart all brake at the limit at once and the faster ones run into
  /// the slower ones ahead.
  [[nodiscard]] static double applied_accel(const CalmTraffic& t, int self, int lead, double gap_m,
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

  /// Desired speed of a vehicle for IDM: a car's cruise speed; for the ego (whose wishes are
  /// unknown) its own speed, so that only the interaction term counts.
  [[nodiscard]] static double desired_speed(const CalmTraffic& t, const Vehicle& v) {
    return v.car >= 0 ? t.cars_[static_cast<std::size_t>(v.car)].cruise_mps : v.speed_mps;
  }

  /// IDM acceleration of vehicle `k` behind `lead` (-1: free road) at `gap_m`.
  [[nodiscard]] static double idm_of(const CalmTraffic& t, int k, int lead, double gap_m) {
    const Vehicle& v = t.vehicles_[static_cast<std::size_t>(k)];
    if (lead < 0) return idm(t, v.speed_mps, desired_speed(t, v), kInf, 0.0);
    return idm(t, v.speed_mps, desired_speed(t, v), gap_m,
               t.vehicles_[static_cast<std::size_t>(lead)].speed_mps);
  }

  /// MOBIL (Kesting, Treiber, Helbing 2007) for car i into `lane`, on IDM accelerations:
  /// the incentive when the change is safe and its incentive beats `best`, else nullopt.
  /// Safe: no vehicle in the target lane within car length + s0; the new follower (the
  /// ego included) need not brake harder than safe_decel; (ours) nor need the car itself.
  [[nodiscard]] static std::optional<double> mobil(const CalmTraffic& t, int i, int lane, double best) {
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

  /// Whether car j's change into a lane conflicts with car i's change into the same lane.
  [[nodiscard]] static bool changes_conflict(const CalmTraffic& t, int i, int j) {
    const CalmTrafficParams& p = t.params_.calm;
    const double gap = ahead(t, t.vehicles_[static_cast<std::size_t>(i)].s_m,
                             t.vehicles_[static_cast<std::size_t>(j)].s_m);
    if (std::abs(gap) < t.car_.length_m + p.min_gap_m) return true;
    const int back = gap > 0.0 ? i : j;
    const int front = gap > 0.0 ? j : i;
    return idm_of(t, back, front, std::abs(gap)) < -p.safe_decel_mps2;
  }

  static void decide_calm(CalmTraffic& t, double dt) {
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

  // ----- motion ----------------------------------------------------------------------------

  static void move(CalmTraffic& t, CalmCar& c, const Decision& dec, double dt) {
    const TrafficParams& p = t.params_;
    const double d_before = c.d_m;
    c.accel_mps2 = (dec.new_speed_mps - c.speed_mps) / dt;
    c.speed_mps = dec.new_speed_mps;
    if (dec.change_to_lane >= 0) {
      c.manoeuvre = LaneManoeuvre{c.lane, dec.change_to_lane, c.d_m, 0.0, p.calm.lane_change_duration_s};
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
    const double ds = t.line_.s_rate({c.s_m, d_before}, c.speed_mps) * dt;
    c.s_m = t.line_.wrap_s(c.s_m + ds);
  }

  // ----- placement -------------------------------------------------------------------------

  /// The behind and ahead regions around the ego's previous waypoint, as offsets from the ego.
  static void regions(const CalmTraffic& t, double ego_s, Region& behind, Region& ahead_region) {
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
               forward(t, ego_s, waypoint_s(t, prev + p.placement.ahead_max_waypoints)), ahead_region);
    ahead_region.min_speed_mps = p.placement.ahead_min_speed_mps;
    ahead_region.max_speed_mps = p.placement.ahead_max_speed_mps;
  }

  /// How much the gap between two vehicles in one lane can shrink at most when the one
  /// behind (speed v_f) brakes at b while the one ahead (v_l) keeps braking at decel_l >= 0
  /// until it stands: the spawn rule's dv^2 / (2 b) when the leader holds its speed.
  [[nodiscard]] static double worst_closing_m(double v_f, double v_l, double decel_l, double b) {
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

  /// (ours) In one lane, the vehicle behind must be able to brake in time for the one ahead
  /// (which keeps its present deceleration, if it is braking) at spawn_brake_mps2.
  [[nodiscard]] static bool room_to_brake(const CalmTraffic& t, double s, double v, double other_s,
                                          double other_v, double other_accel) {
    const double gap = ahead(t, s, other_s);
    const double b = t.params_.calm.spawn_brake_mps2;
    const double closing = gap >= 0.0 ? worst_closing_m(v, other_v, std::max(0.0, -other_accel), b)
                                      : worst_closing_m(other_v, v, 0.0, b);
    return std::abs(gap) >= t.car_.length_m + kSpawnMarginM + closing;
  }

  /// The ego as placement sees it.
  struct EgoSpot {
    double s_m = 0.0;  // wrapped
    core::Vec2 position;
    unsigned lanes = 0;
    double speed_mps = 0.0;
    double accel_mps2 = 0.0;
  };

  [[nodiscard]] static EgoSpot ego_spot(const CalmTraffic& t, const EgoView& ego) {
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

  /// Whether car i may be put at (s, d) in `lane` at `speed`, given the cars [0, limit)
  /// other than i (positions in positions_) and the ego.
  [[nodiscard]] static bool spot_ok(const CalmTraffic& t, int i, int limit, double s, double d,
                                    int lane, double speed, const EgoSpot& ego) {
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

  /// Puts car i at a spot and resets its state.
  static void commit(CalmTraffic& t, CalmCar& c, double s, int lane, double cruise, double phase,
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

  /// A car's wander, drawn from its own stream at each placement.
  struct Wander {
    double omega_rps = 0.0;
    double phase_rad = 0.0;
  };

  [[nodiscard]] static Wander draw_wander(const CalmTraffic& t, CalmCar& c) {
    const TrafficParams& p = t.params_;
    const double period = c.rng.uniform(p.calm.wander_min_period_s, p.calm.wander_max_period_s);
    Wander w;
    w.omega_rps = period > 0.0 ? 2.0 * core::kPi / period : 0.0;
    w.phase_rad = c.rng.uniform(0.0, 2.0 * core::kPi);
    return w;
  }

  /// Positions of the cars [0, limit), for the spacing checks.
  static void cache_positions(CalmTraffic& t, int limit) {
    for (int j = 0; j < limit; ++j) {
      const CalmCar& o = t.cars_[static_cast<std::size_t>(j)];
      t.positions_[static_cast<std::size_t>(j)] = t.line_.to_cartesian({o.s_m, o.d_m});
    }
  }

  enum class Where { either, behind, ahead };

  /// Tries to place car i by the spawn rule (up to max_spawn_attempts draws) against the
  /// cars [0, limit). `initial`: not behind the ego in the ego's lane.
  static bool try_place(CalmTraffic& t, int i, int limit, const EgoView& ego_view, bool initial,
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
      const bool is_behind = where == Where::either ? t.spawn_rng_.chance(p.placement.behind_probability)
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

  /// Last resort of the initial placement: farther ahead, ego + 150 m + 10 m * k.
  static void place_fallback(CalmTraffic& t, int i, const EgoView& ego_view) {
    const TrafficParams& p = t.params_;
    CalmCar& c = t.cars_[static_cast<std::size_t>(i)];
    const EgoSpot ego = ego_spot(t, ego_view);
    cache_positions(t, i);
    const Wander w = draw_wander(t, c);
    const double offset = p.calm.wander_amplitude_m * std::sin(w.phase_rad);
    const double cruise = t.spawn_rng_.uniform(p.placement.ahead_min_speed_mps, p.placement.ahead_max_speed_mps);
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
};

CalmTraffic::CalmTraffic(const core::Map& map, const core::ReferenceLine& line,
                         const core::WaypointFrenet& chords, const TrafficParams& params,
                         const core::RoadParams& road, const core::CarFootprint& car,
                         std::uint64_t seed)
    : map_(map),
      line_(line),
      chords_(chords),
      params_(params),
      road_(road),
      car_(car),
      spawn_rng_(core::derive_seed(seed, kSpawnStream)) {
  assert(!map.waypoints.empty());
  assert(road.lane_count >= 1 && road.lane_count <= 32);
  const auto n = static_cast<std::size_t>(std::max(0, params.car_count));
  cars_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    cars_[i].rng = core::Rng(core::derive_seed(seed, kFirstCarStream + i));
  }
  vehicles_.reserve(n + 1);
  decisions_.reserve(n);
  positions_.resize(n);
  publish();
}

void CalmTraffic::start(const EgoView& ego) {
  using Where = CalmImpl::Where;
  positions_.resize(cars_.size());
  const int n = static_cast<int>(cars_.size());
  for (int i = 0; i < n; ++i) {
    if (CalmImpl::try_place(*this, i, i, ego, true, Where::either)) continue;
    if (CalmImpl::try_place(*this, i, i, ego, true, Where::ahead)) continue;
    if (CalmImpl::try_place(*this, i, i, ego, true, Where::behind)) continue;
    CalmImpl::place_fallback(*this, i, ego);
  }
  frames_to_batch_ =
      spawn_rng_.uniform_int(params_.placement.batch_min_frames, params_.placement.batch_max_frames);
  publish();
}

void CalmTraffic::step(const EgoView& ego, double dt_s) {
  assert(dt_s > 0.0);
  const std::size_t n = cars_.size();
  if (scripted_) {
    decisions_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      CalmCar& c = cars_[i];
      CalmCar::Script& m = *c.script;
      Decision& dec = decisions_[i];
      dec = {};
      const double v = c.speed_mps;
      if (m.brake_left_s > 0.0) {
        dec.new_speed_mps = std::max(0.0, v - m.brake_mps2 * dt_s);
        m.brake_left_s -= dt_s;
        if (m.brake_left_s <= 0.0) m.target_speed_mps = dec.new_speed_mps;  // then hold it
      } else if (v < m.target_speed_mps) {
        dec.new_speed_mps = std::min(m.target_speed_mps, v + m.rate_mps2 * dt_s);
      } else {
        dec.new_speed_mps = std::max(m.target_speed_mps, v - m.rate_mps2 * dt_s);
      }
      dec.change_to_lane = m.change_to_lane;
      m.change_to_lane = -1;
    }
    for (std::size_t i = 0; i < n; ++i) CalmImpl::move(*this, cars_[i], decisions_[i], dt_s);
    ego_prev_speed_mps_ = ego.speed_mps;
    publish();
    return;
  }
  const double ego_s = line_.wrap_s(ego.frenet.s_m);
  CalmImpl::build_vehicles(*this, ego, ego_s, dt_s);
  decisions_.resize(n);
  CalmImpl::decide_calm(*this, dt_s);
  for (std::size_t i = 0; i < n; ++i) CalmImpl::move(*this, cars_[i], decisions_[i], dt_s);
  ego_prev_speed_mps_ = ego.speed_mps;

  for (CalmCar& c : cars_) {
    c.far = std::abs(CalmImpl::ahead(*this, ego_s, c.s_m)) > params_.placement.despawn_distance_m;
  }
  if (--frames_to_batch_ <= 0) {
    const int batch =
        spawn_rng_.uniform_int(params_.placement.batch_min_cars, params_.placement.batch_max_cars);
    int tried = 0;
    for (std::size_t i = 0; i < n && tried < batch; ++i) {
      if (!cars_[i].far) continue;
      ++tried;
      (void)CalmImpl::try_place(*this, static_cast<int>(i), static_cast<int>(n), ego, false,
                                CalmImpl::Where::either);
    }
    frames_to_batch_ =
        spawn_rng_.uniform_int(params_.placement.batch_min_frames, params_.placement.batch_max_frames);
  }
  publish();
}

void CalmTraffic::publish() {
  bodies_.resize(cars_.size());
  for (std::size_t i = 0; i < cars_.size(); ++i) {
    const CalmCar& c = cars_[i];
    TrafficCar& b = bodies_[i];
    const core::FrenetPoint p{line_.wrap_s(c.s_m), c.d_m};
    const core::Vec2 v = line_.velocity(p, line_.s_rate(p, c.speed_mps), c.d_rate_mps);
    b.id = static_cast<int>(i);
    b.position = line_.to_cartesian(p);
    b.heading_rad =
        core::norm(v) < kStationaryMps ? line_.frame(p.s_m).heading_rad : std::atan2(v.y, v.x);
    b.speed_mps = c.speed_mps;
    b.reported_velocity_mps = v;
    b.closest_waypoint = chords_.closest(b.position, b.closest_waypoint);
    b.map_frenet = chords_.to_frenet(b.position, b.closest_waypoint);
    b.lane = c.lane;
    b.parked = false;
  }
}

void CalmTraffic::on_contact(std::size_t i, core::Vec2 shift_m, double speed_mps,
                             const core::OrientedBox& /*other*/) {
  CalmCar& c = cars_[i];
  const core::RoadFrame fr = line_.frame(line_.wrap_s(c.s_m));
  c.s_m = line_.wrap_s(c.s_m + core::dot(shift_m, fr.tangent) / fr.ds_scale);
  c.d_m += core::dot(shift_m, fr.normal);
  c.speed_mps = std::max(0.0, speed_mps);
  publish();
}

void CalmTraffic::set_cars(std::vector<CalmCar> cars) {
  cars_ = std::move(cars);
  for (CalmCar& c : cars_) c.s_m = line_.wrap_s(c.s_m);
  positions_.resize(cars_.size());
  publish();
}

void CalmTraffic::set_script(const std::vector<ScriptedCar>& cars) {
  std::vector<CalmCar> out;
  out.reserve(cars.size());
  for (const ScriptedCar& sc : cars) {
    CalmCar c;
    c.s_m = line_.wrap_s(sc.s_m);
    c.lane = sc.lane;
    c.d_m = core::lane_center_d(sc.lane, road_);
    c.speed_mps = sc.speed_mps;
    c.cruise_mps = sc.speed_mps;
    c.wander_omega_rps = 0.0;  // scripted cars keep to the lane centre
    c.script = CalmCar::Script{sc.speed_mps};
    out.push_back(std::move(c));
  }
  set_cars(std::move(out));
  scripted_ = true;
}

void CalmTraffic::apply_event(const ScenarioEvent& e) {
  if (e.car < 0 || static_cast<std::size_t>(e.car) >= cars_.size()) return;
  CalmCar& c = cars_[static_cast<std::size_t>(e.car)];
  if (!c.script) return;
  CalmCar::Script& m = *c.script;
  switch (e.action) {
    case ScenarioAction::change_lane:
      if (e.lane != c.lane && e.lane >= 0 && e.lane < road_.lane_count) m.change_to_lane = e.lane;
      break;
    case ScenarioAction::brake:
      m.brake_mps2 = e.rate_mps2;
      m.brake_left_s = e.duration_s;
      break;
    case ScenarioAction::set_speed:
      m.brake_left_s = 0.0;
      m.target_speed_mps = e.speed_mps;
      m.rate_mps2 = e.rate_mps2;
      break;
  }
}

}  // namespace overtake::sim
