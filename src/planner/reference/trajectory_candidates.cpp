// The candidates of the trajectory layer: the lanes in play, the along-road scale, the cars
// per lane, the lateral and longitudinal candidates with their costs, and the soft lane costs.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>
#include <vector>

#include "overtake/planner/reference/behaviour.hpp"
#include "trajectory_internal.hpp"

namespace overtake::planner::reference {

bool in_line_band(double d_m, double half_width_m, const core::RoadParams& road) {
  if (road.lane_count < 2) return false;
  const double k = std::clamp(std::round(d_m / road.lane_width_m), 1.0,
                              static_cast<double>(road.lane_count - 1));
  return std::abs(d_m - k * road.lane_width_m) <= half_width_m;
}

namespace trajectory_detail {
namespace {

/// Lateral distances below this need no manoeuvre.
constexpr double kHoldLateralM = 0.02;
/// Spacing of the samples that find a lane's largest along-road scale ahead.
constexpr double kScaleSampleM = 10.0;
/// A follower's shortfall of room to brake is costed in units of this; one farther than five
/// of them beyond the reaction gap is not costed.
constexpr double kRearRoomScaleM = 3.0;
/// Of two lateral motions that overstay on a lane line as soon, the shorter stay counts as
/// later by this share of its length.
constexpr double kOverstayTieBreak = 0.01;
/// Levelling-off candidates are added from accelerations beyond this.
constexpr double kLevelOffMps2 = 1.0;
/// Beyond an outer lane's centre a lateral motion may overshoot this far where that centre
/// itself reads closer to the edge than the road margin.
constexpr double kOvershootM = 0.2;

/// A car ahead in a lane, with how far it goes braking as hard as it can from each of its
/// samples (rss_front_reach, in metres of road).
struct AheadCar {
  const CarSamples* car = nullptr;
  std::vector<double> reach_m;
};

/// rss_rear_reach for one set of parameters, with the parts that do not depend on the speed
/// (the ramp's time, speed lost and the jerk's share of its distance, each a division) worked
/// out once: the same expressions on the same numbers as jerk_limited_stop_distance, so the
/// same reach to the bit.
class RearReach {
 public:
  explicit RearReach(const ReferenceBehaviourParams& p)
      : response_s_(p.response_time_s),
        brake_(p.ego_brake_mps2),
        jerk_(p.ego_brake_jerk_mps3),
        ramp_t_(brake_ / jerk_),
        ramp_dv_(0.5 * brake_ * ramp_t_),
        ramp_jerk_m_(jerk_ * ramp_t_ * ramp_t_ * ramp_t_ / 6.0) {}

  [[nodiscard]] double operator()(double rear_mps) const {
    const double rear = std::max(0.0, rear_mps);
    return rear * response_s_ + stop_distance(rear);
  }

 private:
  [[nodiscard]] double stop_distance(double v) const {
    if (!(v > 0.0)) return 0.0;
    if (v <= ramp_dv_) {
      const double t = std::sqrt(2.0 * v / jerk_);
      return v * t - jerk_ * t * t * t / 6.0;
    }
    const double ramp_d = v * ramp_t_ - ramp_jerk_m_;
    const double rest = v - ramp_dv_;
    return ramp_d + rest * rest / (2.0 * brake_);
  }

  double response_s_;
  double brake_;
  double jerk_;
  double ramp_t_;
  double ramp_dv_;
  double ramp_jerk_m_;
};

/// The soft costs of longitudinal samples `lon` in a lane with cars `ahead` and `behind`;
/// `rear_reach_m[k]` is rss_rear_reach of the ego's speed at sample k, so that the RSS gap
/// wanted behind each car is rss_gap_of the two reaches (rss_front_gap's number, worked out
/// once per sample instead of once per car and lane). `steps` is scratch of g.n + 1.
///
/// Each step's terms are added car by car over all samples, then the rear term: per sample
/// the same additions in the same order as car by car within one sample, but the loop over
/// the samples of one car has no dependence between samples and is vectorised (two samples
/// per division). The steps are then summed in sample order as before.
LaneCost lane_cost(const Track1d& lon, const std::vector<double>& rear_reach_m, const Grid& g,
                   const std::vector<AheadCar>& ahead, const CarSamples* behind,
                   double m_per_unit_s, const ReferenceParams& p,
                   const core::CarFootprint& footprint, std::vector<double>& steps) {
  const auto& b = p.behaviour;
  const auto& tp = p.trajectory;
  // Without cars every step is 0, and adding 0 to the sums (from +0) leaves them 0.
  if (ahead.empty() && !behind) return {};
  const auto n = static_cast<std::size_t>(g.n + 1);
  const double* const x = lon.x.data() + kBack;
  const double* const v = lon.v.data() + kBack;
  const double* const rear = rear_reach_m.data();
  double* const step = steps.data();
  std::fill_n(step, n, 0.0);
  for (const AheadCar& a : ahead) {
    const double* const car_s = a.car->s.data();
    const double* const front = a.reach_m.data();
    for (std::size_t i = 0; i < n; ++i) {
      const double gap = (car_s[i] - x[i]) * m_per_unit_s - footprint.length_m;
      const double want = rss_gap_of(rear[i], front[i], b);
      const double short_by = std::max(0.0, want - gap) / want;
      step[i] += tp.proximity_weight * short_by * short_by;
    }
  }
  if (behind) {
    for (std::size_t i = 0; i < n; ++i) {
      const double centre_gap = (x[i] - behind->s[i]) * m_per_unit_s;
      if (centre_gap < b.follower_reaction_gap_m + kRearRoomScaleM * 5.0) {
        const double closing = (behind->s_dot[i] - v[i]) * m_per_unit_s;
        const double room = rear_room(b.follower_reaction_gap_m, closing, footprint.length_m, b);
        const double short_by = std::max(0.0, -room) / kRearRoomScaleM;
        step[i] += tp.rear_weight * short_by * short_by;
      }
    }
  }
  double full = 0.0;
  double early = 0.0;
  const int early_n = static_cast<int>(std::lround(tp.change_early_window_s / g.h));
  for (int k = 0; k <= g.n; ++k) {
    const double term = step[static_cast<std::size_t>(k)] * g.h;
    full += term;
    if (k <= early_n) early += term;
  }
  return {full, early};
}

/// What the lateral candidates' checks read along a steady motion from the start (s at grid
/// time t: x0.s + x0.s_dot t): the original's reading of d there, and the bounds on_road
/// keeps the ego's middle within. The same for every lateral candidate, so read once.
struct SteadyReadings {
  std::vector<LaneFrame::Reading> at;  // k = 0 .. n
  std::vector<double> lo, hi;          // on_road's bounds on the original's d
};

SteadyReadings steady_readings(const Grid& g, const LaneFrame& frame, const FrenetState& x0,
                               const ReferenceTrajectoryParams& tp, const core::RoadParams& road) {
  const double first = core::lane_center_d(0, road);
  const double last = core::lane_center_d(road.lane_count - 1, road);
  const auto n = static_cast<std::size_t>(g.n + 1);
  SteadyReadings r;
  r.at.resize(n);
  r.lo.resize(n);
  r.hi.resize(n);
  for (int k = 0; k <= g.n; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const double s = x0.s_m + x0.s_dot * g.t(k);
    r.at[i] = frame.reading(s);
    r.lo[i] = std::min(tp.road_edge_margin_m, LaneFrame::original_d(r.at[i], first) - kOvershootM);
    r.hi[i] = std::max(core::road_width_m(road) - tp.road_edge_margin_m,
                       LaneFrame::original_d(r.at[i], last) + kOvershootM);
  }
  return r;
}

/// A lateral motion's time in lane-line bands over the grid (the first stretch extended by
/// `already_s`), d read as the original reads it, at s along a steady motion from the start.
struct BandTime {
  double longest_s = 0.0;  ///< the longest stretch without a break
  double overstay_s = std::numeric_limits<double>::infinity();  ///< when one passes `limit_s`
};

BandTime band_time(const Track1d& lat, const Grid& g, double already_s, double half_width,
                   double limit_s, const SteadyReadings& steady, const core::RoadParams& road) {
  BandTime b;
  double run = already_s;
  for (int k = 0; k <= g.n; ++k) {
    const double d = LaneFrame::original_d(steady.at[static_cast<std::size_t>(k)],
                                           lat.x[static_cast<std::size_t>(k + kBack)]);
    if (in_line_band(d, half_width, road)) {
      run += k == 0 ? 0.0 : g.h;
      b.longest_s = std::max(b.longest_s, run);
      if (run > limit_s && b.overstay_s == kInf) b.overstay_s = g.t(k);
    } else {
      run = 0.0;
    }
  }
  return b;
}

/// Whether a lateral motion keeps the ego's middle on the road, as the original reads d,
/// with a margin (a slow lateral motion from a fast start overshoots). Where the waypoints
/// are far apart on a bend the outer lanes' centres themselves read close to the edge; there
/// the bound is the centre's reading less the overshoot allowed, so that keeping a lane is
/// never ruled out.
bool on_road(const Track1d& lat, const Grid& g, const SteadyReadings& steady) {
  for (int k = 0; k <= g.n; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const double d =
        LaneFrame::original_d(steady.at[i], lat.x[i + static_cast<std::size_t>(kBack)]);
    if (d < steady.lo[i] || d > steady.hi[i]) return false;
  }
  return true;
}

}  // namespace

std::vector<int> lanes_in_play(const FrenetState& x0, int target_lane, double line_band_m,
                               const core::RoadParams& road) {
  std::vector<int> lanes{target_lane};
  const auto add_lane = [&](int l) {
    if (l >= 0 && l < road.lane_count && std::find(lanes.begin(), lanes.end(), l) == lanes.end())
      lanes.push_back(l);
  };
  add_lane(core::lane_of(x0.d_m, road));
  if (in_line_band(x0.d_m, line_band_m, road)) {
    add_lane(core::lane_of(x0.d_m - line_band_m, road));
    add_lane(core::lane_of(x0.d_m + line_band_m, road));
  }
  return lanes;
}

AlongRoadScale along_road_scale(const LaneFrame& line, const FrenetState& x0,
                                double wanted_speed_mps, const std::vector<int>& lanes,
                                const ReferenceTrajectoryParams& tp, const core::RoadParams& road) {
  // Over the stretch the wanted speed (or the present one) reaches within the horizon, every
  // kScaleSampleM or less, in each lane in play, and where the ego is. The line and the frame's
  // offset are read once per s for all of them.
  const double reach = std::max(x0.s_dot, wanted_speed_mps) * tp.horizon_s + kScaleSampleM;
  const double s0 = x0.s_m;
  const double s1 = x0.s_m + reach;
  const int n = std::max(1, static_cast<int>(std::ceil((s1 - s0) / kScaleSampleM)));
  double max_scale = 0.0;
  double m_per_unit_s = kInf;
  const auto take = [&](double k) {
    max_scale = std::max(max_scale, k);
    m_per_unit_s = std::min(m_per_unit_s, k);
  };
  for (int i = 0; i <= n; ++i) {
    const double s = s0 + (s1 - s0) * i / n;
    const core::RoadFrame f = line.line().frame_without_heading(s);
    const LaneFrame::OffsetSlope o = line.offset_slope(s);
    for (const int l : lanes) take(road_point(f, o, core::lane_center_d(l, road)).along_scale);
    if (i == 0) take(road_point(f, o, x0.d_m).along_scale);
  }
  AlongRoadScale out;
  out.m_per_unit_s = m_per_unit_s;
  out.s_dot_cap = std::min(wanted_speed_mps, tp.max_speed_mps) / max_scale;
  return out;
}

std::vector<LaneCars> cars_per_lane(const std::vector<int>& lanes,
                                    const std::vector<CarSamples>& samples,
                                    const std::vector<CarPrediction>& cars, double s0_m,
                                    const core::RoadParams& road) {
  std::vector<LaneCars> lane_cars(static_cast<std::size_t>(road.lane_count));
  for (const int l : lanes) {
    LaneCars& lc = lane_cars[static_cast<std::size_t>(l)];
    std::vector<std::pair<double, std::size_t>> ahead;
    double behind_gap = kInf;
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const CarSamples& c = samples[i];
      const auto pred = std::find_if(cars.begin(), cars.end(),
                                     [&](const CarPrediction& x) { return x.id == c.id; });
      if (!pred->occupies(l)) continue;
      const double gap = c.s[0] - s0_m;
      if (gap >= 0.0) {
        ahead.emplace_back(gap, i);
      } else if (-gap < behind_gap) {
        behind_gap = -gap;
        lc.behind = &c;
      }
    }
    std::sort(ahead.begin(), ahead.end());
    for (std::size_t i = 0; i < ahead.size() && i < 2; ++i)
      lc.ahead.push_back(&samples[ahead[i].second]);
    if (!ahead.empty()) {
      const int id = samples[ahead.front().second].id;
      lc.leader = &*std::find_if(cars.begin(), cars.end(),
                                 [&](const CarPrediction& x) { return x.id == id; });
    }
  }
  return lane_cars;
}

std::vector<const CarPrediction*> lane_leaders(const std::vector<int>& lanes,
                                               const std::vector<LaneCars>& lane_cars) {
  std::vector<const CarPrediction*> leaders;
  for (const int l : lanes) {
    const CarPrediction* lead = lane_cars[static_cast<std::size_t>(l)].leader;
    if (lead && std::find(leaders.begin(), leaders.end(), lead) == leaders.end())
      leaders.push_back(lead);
  }
  return leaders;
}

std::vector<LatCandidate> lateral_candidates(const std::vector<int>& lanes,
                                             const TrajectoryRequest& req, const Grid& g,
                                             const LaneFrame& line,
                                             const ReferenceTrajectoryParams& tp,
                                             const core::RoadParams& road, SpareBuffers& spare) {
  const FrenetState& x0 = req.start;
  std::vector<LatCandidate> lats;
  lats.reserve(lanes.size() * tp.lateral_time_factors.size());
  // A refused candidate's sample buffers serve the next one.
  Track1d scratch = take_track(spare);
  const SteadyReadings steady = steady_readings(g, line, x0, tp, road);
  for (const int l : lanes) {
    const double target = core::lane_center_d(l, road);
    const double dist = std::abs(target - x0.d_m);
    const bool hold = dist < kHoldLateralM && std::abs(x0.d_dot_mps) < kHoldLateralM;
    const double t_min =
        std::max(tp.min_lateral_time_s, std::cbrt(60.0 * dist / tp.lateral_jerk_mps3));
    for (const double f : tp.lateral_time_factors) {
      const Polynomial1d poly =
          quintic(x0.d_m, x0.d_dot_mps, x0.d_ddot_mps2, target, 0.0, 0.0, t_min * f);
      if (!sample_within(g, PolynomialSampler{poly}, tp.max_accel_mps2, tp.max_jerk_mps3, false,
                         scratch) ||
          !on_road(scratch, g, steady))
        continue;
      LatCandidate c;
      c.poly = poly;
      c.end_lane = l;
      c.samples = std::exchange(scratch, take_track(spare));
      c.terms.lateral_jerk = tp.lat_jerk_weight * c.poly.jerk_cost();
      c.terms.lateral_time = hold ? 0.0 : tp.lat_time_weight * c.poly.duration_s;
      c.terms.off_target_lane = tp.lane_weight * std::abs(l - req.target_lane);
      c.cost = c.terms.lateral_jerk + c.terms.lateral_time + c.terms.off_target_lane;
      // Longer than the budget on a lane line costs; as long as the original counts as an
      // incident is an incident.
      const BandTime band = band_time(c.samples, g, req.band_time_s, tp.line_band_m,
                                      tp.band_incident_s, steady, road);
      // (Of two that overstay as soon, the one that leaves the line sooner is less bad.)
      c.overstay_s = band.overstay_s - kOverstayTieBreak * band.longest_s;
      c.terms.linger = tp.linger_weight * std::max(0.0, band.longest_s - tp.max_band_time_s);
      c.cost += c.terms.linger;
      lats.push_back(std::move(c));
      if (hold) break;
    }
  }
  spare.push_back(std::move(scratch.x));
  spare.push_back(std::move(scratch.v));
  return lats;
}

Longitudinal fallback_braking(const FrenetState& x0, const ReferenceTrajectoryParams& tp,
                              double m_per_unit_s) {
  Longitudinal braking;
  braking.braking = true;
  braking.brake = BrakingProfile(x0.s_m, x0.s_dot, x0.s_ddot, tp.fallback_brake_mps2 / m_per_unit_s,
                                 tp.fallback_jerk_mps3 / m_per_unit_s);
  return braking;
}

std::vector<LonCandidate> longitudinal_candidates(const TrajectoryRequest& req,
                                                  const std::vector<const CarPrediction*>& leaders,
                                                  const AlongRoadScale& scale, const Grid& g,
                                                  const ReferenceParams& params,
                                                  const core::CarFootprint& car,
                                                  SpareBuffers& spare) {
  const auto& tp = params.trajectory;
  const auto& bp = params.behaviour;
  const FrenetState& x0 = req.start;
  const double m_per_unit_s = scale.m_per_unit_s;
  const double s_dot_cap = scale.s_dot_cap;
  std::vector<LonCandidate> lons;
  lons.reserve(tp.cruise_times_s.size() * (tp.speed_offsets_mps.size() + 1) +
               leaders.size() * tp.follow_times_s.size() + 2 + tp.brake_levels_mps2.size());
  // A refused candidate's sample buffers serve the next one.
  Track1d scratch = take_track(spare);
  const auto add_lon = [&](const Longitudinal& m) {
    if (!sample_within(g, LongitudinalSampler{m}, tp.max_accel_mps2, tp.max_jerk_mps3, true,
                       scratch))
      return;
    LonCandidate c;
    c.motion = m;
    c.samples = std::exchange(scratch, take_track(spare));
    const double travelled = (c.samples.x.back() - x0.s_m) * m_per_unit_s;
    const double deficit = req.wanted_speed_mps * tp.horizon_s - travelled;
    const double jerk = m.braking ? m.brake.jerk_cost() : m.poly.jerk_cost();
    c.terms.progress = tp.progress_weight * deficit;
    c.terms.longitudinal_jerk = tp.lon_jerk_weight * jerk;
    c.cost = c.terms.progress + c.terms.longitudinal_jerk;
    lons.push_back(std::move(c));
  };
  for (const double t : tp.cruise_times_s) {
    // Level off: the acceleration now back to 0 along a straight ramp, then hold that speed
    // (after a hard braking, the other candidates to a faster speed keep braking a while).
    if (std::abs(x0.s_ddot) * m_per_unit_s > kLevelOffMps2) {
      const double v_level = std::max(0.0, x0.s_dot + 0.5 * x0.s_ddot * t);
      add_lon({quartic(x0.s_m, x0.s_dot, x0.s_ddot, v_level, 0.0, t), {}, false});
    }
    double last = -1.0;
    for (const double off : tp.speed_offsets_mps) {
      const double v1 = std::max(0.0, s_dot_cap + off / m_per_unit_s);
      if (std::abs(v1 - last) < 1e-6) continue;
      last = v1;
      add_lon({quartic(x0.s_m, x0.s_dot, x0.s_ddot, v1, 0.0, t), {}, false});
    }
  }
  for (const CarPrediction* lead : leaders) {
    for (const double t : tp.follow_times_s) {
      const double tc = req.start_delay_s + t;
      const double v_lead = lead->s_dot_at(tc);
      const double gap = rss_front_gap(v_lead * m_per_unit_s, v_lead * m_per_unit_s, bp);
      const double s1 = lead->s_at(tc) - (car.length_m + gap) / m_per_unit_s;
      const double v1 = std::min(v_lead, s_dot_cap);
      add_lon({quintic(x0.s_m, x0.s_dot, x0.s_ddot, s1, v1, 0.0, t), {}, false});
    }
  }
  add_lon(fallback_braking(x0, tp, m_per_unit_s));
  Longitudinal gentle;
  gentle.braking = true;
  gentle.brake = BrakingProfile(x0.s_m, x0.s_dot, x0.s_ddot, kGentleStopMps2 / m_per_unit_s,
                                kGentleStopJerkMps3 / m_per_unit_s);
  add_lon(gentle);
  // Braking between the two, each reached gently enough to leave room for a lateral motion.
  for (std::size_t i = 0; i < tp.brake_levels_mps2.size(); ++i) {
    Longitudinal firm;
    firm.braking = true;
    firm.brake = BrakingProfile(x0.s_m, x0.s_dot, x0.s_ddot, tp.brake_levels_mps2[i] / m_per_unit_s,
                                tp.brake_level_jerk_mps3 / m_per_unit_s);
    add_lon(firm);
  }
  spare.push_back(std::move(scratch.x));
  spare.push_back(std::move(scratch.v));
  return lons;
}

SoftLaneCosts soft_lane_costs(const std::vector<LonCandidate>& lons, const std::vector<int>& lanes,
                              const std::vector<LaneCars>& lane_cars, const Grid& g,
                              double m_per_unit_s, const ReferenceParams& params,
                              const core::CarFootprint& car) {
  const auto& b = params.behaviour;
  const auto n = static_cast<std::size_t>(g.n + 1);
  // The cars ahead in each lane in play, with their halves of the RSS gap.
  std::vector<std::vector<AheadCar>> ahead(lane_cars.size());
  for (const int l : lanes) {
    const auto li = static_cast<std::size_t>(l);
    for (const CarSamples* c : lane_cars[li].ahead) {
      AheadCar a;
      a.car = c;
      a.reach_m.resize(n);
      for (std::size_t i = 0; i < n; ++i)
        a.reach_m[i] = rss_front_reach(c->s_dot[i] * m_per_unit_s, b);
      ahead[li].push_back(std::move(a));
    }
  }
  SoftLaneCosts soft;
  soft.lane_count = lane_cars.size();
  soft.costs.resize(lons.size() * soft.lane_count);
  std::vector<double> rear_reach(n);
  std::vector<double> steps(n);
  const RearReach rear_reach_of(b);
  for (std::size_t j = 0; j < lons.size(); ++j) {
    const Track1d& lon = lons[j].samples;
    // (After a polynomial's end, or once braking stands, the speed holds: its reach is
    // worked out once.)
    double last_v = std::numeric_limits<double>::quiet_NaN();  // equal to no speed
    double last_reach = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double v = lon.v[i + static_cast<std::size_t>(kBack)] * m_per_unit_s;
      if (v != last_v) {
        last_v = v;
        last_reach = rear_reach_of(v);
      }
      rear_reach[i] = last_reach;
    }
    for (const int l : lanes) {
      const auto li = static_cast<std::size_t>(l);
      soft.costs[j * soft.lane_count + li] = lane_cost(
          lon, rear_reach, g, ahead[li], lane_cars[li].behind, m_per_unit_s, params, car, steps);
    }
  }
  return soft;
}

}  // namespace trajectory_detail
}  // namespace overtake::planner::reference
