#include "overtake/planner/reference/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "overtake/core/units.hpp"
#include "overtake/planner/reference/behaviour.hpp"

namespace overtake::planner::reference {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
/// Samples before t = 0, so that the 0.1 s windows at the start see the start state's
/// continuation.
constexpr int kBack = 3;
/// Slowest speed used when turning a lateral speed into a heading.
constexpr double kMinHeadingSpeedMps = 3.0;
/// Lateral distances below this need no manoeuvre.
constexpr double kHoldLateralM = 0.02;
/// Cars farther than this along the road are not considered.
constexpr double kRelevantM = 200.0;
/// The ego never reverses: a planned ds/dt below this is refused.
constexpr double kReverseTolerance = -1e-4;
/// A gentle stop (to standstill behind a stopped car, or at a crawl): its braking and jerk.
constexpr double kGentleStopMps2 = 2.0;
constexpr double kGentleStopJerkMps3 = 2.5;
/// Spacing of the samples that find a lane's largest along-road scale ahead.
constexpr double kScaleSampleM = 10.0;
/// Lane changes costed as this many seconds of lateral time at least.
constexpr double kRearRoomScaleM = 3.0;
/// Off its lane's centre by more than this, the ego counts as moving across lanes.
constexpr double kSidewaysM = 0.5;
/// Of two lateral motions that overstay on a lane line as soon, the shorter stay counts as
/// later by this share of its length.
constexpr double kOverstayTieBreak = 0.01;
/// A car speeding up harder than this is not taken to brake early for the ego.
constexpr double kSpeedingUpMps2 = 1.0;
/// A follower's sensor meets the ego once the ego's middle is this close sideways to its own.
constexpr double kSensorCoverM = 0.8;
/// Longest a collision-failed candidate list is searched for a least-bad one.
constexpr int kLeastBadChecks = 12;
/// Levelling-off candidates are added from accelerations beyond this.
constexpr double kLevelOffMps2 = 1.0;
/// Beyond an outer lane's centre a lateral motion may overshoot this far where that centre
/// itself reads closer to the edge than the road margin.
constexpr double kOvershootM = 0.2;

/// Samples of one motion over the grid k = -kBack .. n (index k + kBack).
struct Track1d {
  std::vector<double> x;
  std::vector<double> v;
};

struct LonCandidate {
  Longitudinal motion;
  Track1d samples;
  double cost = 0.0;
};

struct LatCandidate {
  Polynomial1d poly;
  Track1d samples;
  int end_lane = 0;
  double cost = 0.0;
  double overstay_s = 0.0;  // when it would have lingered on a lane line too long (or infinity)
};

struct CarSamples {
  int id = 0;
  double cap_mps = 0.0;                    // estimated speed cap
  bool speeding_up = false;                // accelerating now: not a car that brakes for the ego
  std::vector<double> s, s_dot, d, d_dot;  // k = 0 .. n
};

struct Grid {
  double h = 0.1;
  int n = 50;
  [[nodiscard]] std::size_t size() const { return static_cast<std::size_t>(n + 1 + kBack); }
  [[nodiscard]] double t(int k) const { return h * k; }
};

Grid grid_of(const ReferenceTrajectoryParams& p) {
  Grid g;
  g.h = p.check_step_s;
  g.n = std::max(1, static_cast<int>(std::lround(p.horizon_s / p.check_step_s)));
  return g;
}

template <class F>
Track1d sample(const Grid& g, F&& motion_at) {
  Track1d out;
  out.x.resize(g.size());
  out.v.resize(g.size());
  for (int k = -kBack; k <= g.n; ++k) {
    const Motion1d m = motion_at(g.t(k));
    out.x[static_cast<std::size_t>(k + kBack)] = m.x;
    out.v[static_cast<std::size_t>(k + kBack)] = m.v;
  }
  return out;
}

/// Whether a motion stays within the limits along one axis (no reversing for s).
template <class F>
bool axis_ok(const Grid& g, F&& motion_at, double max_accel, double max_jerk, bool forward) {
  for (int k = 0; k <= g.n; ++k) {
    const Motion1d m = motion_at(g.t(k));
    if (forward && m.v < kReverseTolerance) return false;
    if (std::abs(m.a) > max_accel || std::abs(m.j) > max_jerk) return false;
  }
  return true;
}

std::vector<CarSamples> sample_cars(const std::vector<CarPrediction>& cars, double delay, double s0,
                                    const Grid& g) {
  std::vector<CarSamples> out;
  out.reserve(cars.size());
  for (const CarPrediction& c : cars) {
    if (std::abs(c.s_m - s0) > kRelevantM) continue;
    CarSamples cs;
    cs.id = c.id;
    cs.cap_mps = c.cap_mps;
    cs.speeding_up = c.observed_accel_mps2 > kSpeedingUpMps2;
    const auto n = static_cast<std::size_t>(g.n + 1);
    cs.s.resize(n);
    cs.s_dot.resize(n);
    cs.d.resize(n);
    cs.d_dot.resize(n);
    for (int k = 0; k <= g.n; ++k) {
      const double t = delay + g.t(k);
      const auto i = static_cast<std::size_t>(k);
      cs.s[i] = c.s_at(t);
      cs.s_dot[i] = c.s_dot_at(t);
      cs.d[i] = c.d_at(t);
      cs.d_dot[i] = c.d_dot_at(t);
    }
    out.push_back(std::move(cs));
  }
  return out;
}

/// The collision check over samples (indexed k + kBack). `ego_changing`: the ego moves into
/// another lane; `sideways`: it is off its lane's centre or moving into another lane.
///
/// A car behind the ego is the ego's concern only when the ego moves across its path: a
/// follower reacts to one ray straight ahead from the middle of its front, so it does not
/// react to the ego until the ego's middle is within kSensorCoverM of its own sideways. Until
/// then it keeps going (and must not reach the ego); once it sees the ego within its reaction
/// gap, it must have room to stop closing (rear_room).
CollisionReport collide(const Track1d& lon, const Track1d& lat, bool ego_changing, bool sideways,
                        const Grid& g, const std::vector<CarSamples>& cars, double mps,
                        const ReferenceParams& p, const core::CarFootprint& car) {
  const double length = car.length_m;
  const double lon_need = length + p.trajectory.lon_margin_m;
  const double lat_base = car.width_m + p.trajectory.lat_margin_m;
  const double react_gap = p.behaviour.follower_reaction_gap_m;
  CollisionReport r;
  for (const CarSamples& c : cars) {
    bool seen = false;
    bool follower = false;
    for (int k = 0; k <= g.n; ++k) {
      const auto e = static_cast<std::size_t>(k + kBack);
      const auto i = static_cast<std::size_t>(k);
      const double t = g.t(k);
      if (t >= r.first_collision_s) break;
      const double ve = std::max(lon.v[e] * mps, kMinHeadingSpeedMps);
      const double vc = std::max(c.s_dot[i] * mps, kMinHeadingSpeedMps);
      const double side_gap = std::abs(lat.x[e] - c.d[i]);
      const double lat_need =
          lat_base + 0.5 * length * (std::abs(lat.v[e]) / ve + std::abs(c.d_dot[i]) / vc);
      if (side_gap >= lat_need) {
        if (follower) break;  // the ego has left its path
        continue;
      }
      double ahead = (c.s[i] - lon.x[e]) * mps;
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
      ahead = (c.s[i] - own_s) * mps;
      const double closing = (c.s_dot[i] - own_v) * mps;
      // Once it sees the ego it reacts within 0.5 m * (its cap in mph - the ego's speed in
      // m/s), bumper to bumper; never later than the behaviour's follower reaction gap. One
      // speeding up hard is taken to react only that late.
      const double sees_at =
          c.speeding_up ? react_gap
                        : std::max(react_gap, p.prediction.reaction_gain_m *
                                                      (core::mps_to_mph(c.cap_mps) - own_v * mps) +
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
    }
  }
  return r;
}

/// The Cartesian check over samples; before t = 0, the positions driven (`history`, newest
/// first) where given.
KinematicReport kinematics(const Track1d& lon, const Track1d& lat, const Grid& g,
                           const LaneFrame& line, const ReferenceTrajectoryParams& p,
                           bool stop_at_first, const std::vector<FrenetState>& history = {}) {
  KinematicReport r;
  const double h2 = g.h * g.h;
  const double h3 = h2 * g.h;
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
    const double speed =
        std::hypot(lon.v[e] * at.along_scale, lat.v[e] - at.offset_slope * lon.v[e]);
    const double accel = core::norm(back[0] - 2.0 * back[1] + back[2]) / h2;
    const double jerk = core::norm(back[0] - 3.0 * back[1] + 3.0 * back[2] - back[3]) / h3;
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

/// Largest and smallest along-road scale of a lane over s in [s0, s1].
struct ScaleRange {
  double max = 1.0;
  double min = 1.0;
};

ScaleRange lane_scale(const LaneFrame& line, double s0, double s1, double d) {
  ScaleRange r{0.0, kInf};
  const int n = std::max(1, static_cast<int>(std::ceil((s1 - s0) / kScaleSampleM)));
  for (int i = 0; i <= n; ++i) {
    const double s = s0 + (s1 - s0) * i / n;
    const double k = road_point(line, s, d).along_scale;
    r.max = std::max(r.max, k);
    r.min = std::min(r.min, k);
  }
  return r;
}

/// Soft costs of one longitudinal candidate in one lane: inside the RSS gap of the cars ahead,
/// and leaving too little room to cars closing from behind; over the whole horizon and over
/// its first change_early_window_s.
struct LaneCost {
  double full = 0.0;
  double early = 0.0;
};

LaneCost lane_cost(const Track1d& lon, const Grid& g, const std::vector<const CarSamples*>& ahead,
                   const CarSamples* behind, double mps, const ReferenceParams& p,
                   const core::CarFootprint& footprint) {
  const auto& b = p.behaviour;
  const auto& tp = p.trajectory;
  LaneCost c;
  const int early_n = static_cast<int>(std::lround(tp.change_early_window_s / g.h));
  for (int k = 0; k <= g.n; ++k) {
    const auto e = static_cast<std::size_t>(k + kBack);
    const auto i = static_cast<std::size_t>(k);
    const double ve = lon.v[e] * mps;
    double step = 0.0;
    for (const CarSamples* car : ahead) {
      const double gap = (car->s[i] - lon.x[e]) * mps - footprint.length_m;
      const double want = rss_front_gap(ve, car->s_dot[i] * mps, b);
      const double short_by = std::max(0.0, want - gap) / want;
      step += tp.proximity_weight * short_by * short_by;
    }
    if (behind) {
      const double centre_gap = (lon.x[e] - behind->s[i]) * mps;
      if (centre_gap < b.follower_reaction_gap_m + kRearRoomScaleM * 5.0) {
        const double closing = (behind->s_dot[i] - lon.v[e]) * mps;
        const double room = rear_room(b.follower_reaction_gap_m, closing, footprint.length_m, b);
        const double short_by = std::max(0.0, -room) / kRearRoomScaleM;
        step += tp.rear_weight * short_by * short_by;
      }
    }
    c.full += step * g.h;
    if (k <= early_n) c.early += step * g.h;
  }
  return c;
}

/// A lateral motion's time in lane-line bands over the grid (the first stretch extended by
/// `already_s`), d read as the original reads it, at s along a steady motion from `x0`.
struct BandTime {
  double longest_s = 0.0;  ///< the longest stretch without a break
  double overstay_s = std::numeric_limits<double>::infinity();  ///< when one passes `limit_s`
};

BandTime band_time(const Track1d& lat, const Grid& g, double already_s, double half_width,
                   double limit_s, const LaneFrame& frame, const FrenetState& x0,
                   const core::RoadParams& road) {
  BandTime b;
  double run = already_s;
  for (int k = 0; k <= g.n; ++k) {
    const double s = x0.s_m + x0.s_dot * g.t(k);
    if (in_line_band(frame.original_d(s, lat.x[static_cast<std::size_t>(k + kBack)]), half_width,
                     road)) {
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
bool on_road(const Track1d& lat, const Grid& g, const LaneFrame& frame, const FrenetState& x0,
             const ReferenceTrajectoryParams& tp, const core::RoadParams& road) {
  const double first = core::lane_center_d(0, road);
  const double last = core::lane_center_d(road.lane_count - 1, road);
  for (int k = 0; k <= g.n; ++k) {
    const double s = x0.s_m + x0.s_dot * g.t(k);
    const double d = frame.original_d(s, lat.x[static_cast<std::size_t>(k + kBack)]);
    const double lo = std::min(tp.road_edge_margin_m, frame.original_d(s, first) - kOvershootM);
    const double hi = std::max(core::road_width_m(road) - tp.road_edge_margin_m,
                               frame.original_d(s, last) + kOvershootM);
    if (d < lo || d > hi) return false;
  }
  return true;
}

}  // namespace

bool in_line_band(double d_m, double half_width_m, const core::RoadParams& road) {
  if (road.lane_count < 2) return false;
  const double k = std::clamp(std::round(d_m / road.lane_width_m), 1.0,
                              static_cast<double>(road.lane_count - 1));
  return std::abs(d_m - k * road.lane_width_m) <= half_width_m;
}

FrenetState Trajectory::at(double t) const {
  const Motion1d s = longitudinal.at(t);
  const Motion1d d = lateral.at(t);
  return {s.x, s.v, s.a, d.x, d.v, d.a};
}

KinematicReport check_kinematics(const Trajectory& t, const LaneFrame& line,
                                 const ReferenceTrajectoryParams& p) {
  const Grid g = grid_of(p);
  const Track1d lon = sample(g, [&](double x) { return t.longitudinal.at(x); });
  const Track1d lat = sample(g, [&](double x) { return t.lateral.at(x); });
  return kinematics(lon, lat, g, line, p, false);
}

CollisionReport check_collisions(const Trajectory& t, const std::vector<CarPrediction>& cars,
                                 double start_delay_s, double metres_per_s,
                                 const ReferenceParams& p, const core::RoadParams& road,
                                 const core::CarFootprint& car) {
  const Grid g = grid_of(p.trajectory);
  const Track1d lon = sample(g, [&](double x) { return t.longitudinal.at(x); });
  const Track1d lat = sample(g, [&](double x) { return t.lateral.at(x); });
  const double d0 = lat.x[kBack];
  const bool changing = core::lane_of(d0, road) != t.end_lane;
  const bool sideways =
      changing || std::abs(d0 - core::lane_center_d(core::lane_of(d0, road), road)) > kSidewaysM;
  return collide(lon, lat, changing, sideways, g, sample_cars(cars, start_delay_s, lon.x[kBack], g),
                 metres_per_s, p, car);
}

TrajectoryPlan plan_trajectory(const LaneFrame& line, const TrajectoryRequest& req,
                               const ReferenceParams& params, const core::RoadParams& road,
                               const core::CarFootprint& car) {
  const auto& tp = params.trajectory;
  const auto& bp = params.behaviour;
  const Grid g = grid_of(tp);
  const FrenetState& x0 = req.start;
  static const std::vector<CarPrediction> kNoCars;
  const std::vector<CarPrediction>& cars = req.cars ? *req.cars : kNoCars;
  TrajectoryPlan plan;

  // Lanes in play: behaviour's, the one the ego is in (to stay or return), and on a lane
  // line both lanes of that line (to finish or undo a change).
  const int start_lane = core::lane_of(x0.d_m, road);
  std::vector<int> lanes{req.target_lane};
  const auto add_lane = [&](int l) {
    if (l >= 0 && l < road.lane_count && std::find(lanes.begin(), lanes.end(), l) == lanes.end())
      lanes.push_back(l);
  };
  add_lane(start_lane);
  if (in_line_band(x0.d_m, tp.line_band_m, road)) {
    add_lane(core::lane_of(x0.d_m - tp.line_band_m, road));
    add_lane(core::lane_of(x0.d_m + tp.line_band_m, road));
  }

  // Along-road scale over the stretch ahead: the wanted speed as ds/dt, and s to metres.
  const double reach = std::max(x0.s_dot, req.wanted_speed_mps) * tp.horizon_s + kScaleSampleM;
  double max_scale = 0.0;
  double mps = kInf;
  for (const int l : lanes) {
    const ScaleRange r = lane_scale(line, x0.s_m, x0.s_m + reach, core::lane_center_d(l, road));
    max_scale = std::max(max_scale, r.max);
    mps = std::min(mps, r.min);
  }
  {
    const ScaleRange here = lane_scale(line, x0.s_m, x0.s_m, x0.d_m);
    max_scale = std::max(max_scale, here.max);
    mps = std::min(mps, here.min);
  }
  const double s_dot_cap = std::min(req.wanted_speed_mps, tp.max_speed_mps) / max_scale;

  // Cars over the grid, and per lane the cars ahead (nearest two) and the nearest behind.
  const std::vector<CarSamples> car_samples = sample_cars(cars, req.start_delay_s, x0.s_m, g);
  struct LaneCars {
    std::vector<const CarSamples*> ahead;
    const CarSamples* behind = nullptr;
    const CarPrediction* leader = nullptr;
  };
  std::vector<LaneCars> lane_cars(static_cast<std::size_t>(road.lane_count));
  for (const int l : lanes) {
    LaneCars& lc = lane_cars[static_cast<std::size_t>(l)];
    std::vector<std::pair<double, std::size_t>> ahead;
    double behind_gap = kInf;
    for (std::size_t i = 0; i < car_samples.size(); ++i) {
      const CarSamples& c = car_samples[i];
      const auto pred = std::find_if(cars.begin(), cars.end(),
                                     [&](const CarPrediction& x) { return x.id == c.id; });
      if (!pred->occupies(l)) continue;
      const double gap = c.s[0] - x0.s_m;
      if (gap >= 0.0) {
        ahead.emplace_back(gap, i);
      } else if (-gap < behind_gap) {
        behind_gap = -gap;
        lc.behind = &c;
      }
    }
    std::sort(ahead.begin(), ahead.end());
    for (std::size_t i = 0; i < ahead.size() && i < 2; ++i)
      lc.ahead.push_back(&car_samples[ahead[i].second]);
    if (!ahead.empty()) {
      const int id = car_samples[ahead.front().second].id;
      lc.leader = &*std::find_if(cars.begin(), cars.end(),
                                 [&](const CarPrediction& x) { return x.id == id; });
    }
  }

  // Lateral candidates: to the centre of each lane in play; one that would linger on a lane
  // line costs so much that it is driven only when nothing else is safe.
  std::vector<LatCandidate> lats;
  const bool off_centre = std::abs(x0.d_m - core::lane_center_d(start_lane, road)) > kSidewaysM;
  for (const int l : lanes) {
    const double target = core::lane_center_d(l, road);
    const double dist = std::abs(target - x0.d_m);
    const bool hold = dist < kHoldLateralM && std::abs(x0.d_dot_mps) < kHoldLateralM;
    const double t_min =
        std::max(tp.min_lateral_time_s, std::cbrt(60.0 * dist / tp.lateral_jerk_mps3));
    for (const double f : tp.lateral_time_factors) {
      LatCandidate c;
      c.poly = quintic(x0.d_m, x0.d_dot_mps, x0.d_ddot_mps2, target, 0.0, 0.0, t_min * f);
      c.end_lane = l;
      const auto at = [&](double t) { return c.poly.at(t); };
      if (!axis_ok(g, at, tp.max_accel_mps2, tp.max_jerk_mps3, false)) continue;
      c.samples = sample(g, at);
      if (!on_road(c.samples, g, line, x0, tp, road)) continue;
      c.cost = tp.lat_jerk_weight * c.poly.jerk_cost() +
               (hold ? 0.0 : tp.lat_time_weight * c.poly.duration_s) +
               tp.lane_weight * std::abs(l - req.target_lane);
      // Longer than the budget on a lane line costs; as long as the original counts as an
      // incident is an incident.
      const BandTime band = band_time(c.samples, g, req.band_time_s, tp.line_band_m,
                                      tp.band_incident_s, line, x0, road);
      // (Of two that overstay as soon, the one that leaves the line sooner is less bad.)
      c.overstay_s = band.overstay_s - kOverstayTieBreak * band.longest_s;
      c.cost += tp.linger_weight * std::max(0.0, band.longest_s - tp.max_band_time_s);
      lats.push_back(std::move(c));
      if (hold) break;
    }
  }

  // Longitudinal candidates.
  std::vector<LonCandidate> lons;
  const auto add_lon = [&](Longitudinal m) {
    LonCandidate c;
    c.motion = m;
    const auto at = [&](double t) { return c.motion.at(t); };
    if (!axis_ok(g, at, tp.max_accel_mps2, tp.max_jerk_mps3, true)) return;
    c.samples = sample(g, at);
    const double travelled = (c.samples.x.back() - x0.s_m) * mps;
    const double deficit = req.wanted_speed_mps * tp.horizon_s - travelled;
    const double jerk = m.braking ? m.brake.jerk_cost() : m.poly.jerk_cost();
    c.cost = tp.progress_weight * deficit + tp.lon_jerk_weight * jerk;
    lons.push_back(std::move(c));
  };
  for (const double t : tp.cruise_times_s) {
    // Level off: the acceleration now back to 0 along a straight ramp, then hold that speed
    // (after a hard braking, the other candidates to a faster speed keep braking a while).
    if (std::abs(x0.s_ddot) * mps > kLevelOffMps2) {
      const double v_level = std::max(0.0, x0.s_dot + 0.5 * x0.s_ddot * t);
      add_lon({quartic(x0.s_m, x0.s_dot, x0.s_ddot, v_level, 0.0, t), {}, false});
    }
    double last = -1.0;
    for (const double off : tp.speed_offsets_mps) {
      const double v1 = std::max(0.0, s_dot_cap + off / mps);
      if (std::abs(v1 - last) < 1e-6) continue;
      last = v1;
      add_lon({quartic(x0.s_m, x0.s_dot, x0.s_ddot, v1, 0.0, t), {}, false});
    }
  }
  std::vector<const CarPrediction*> leaders;
  for (const int l : lanes) {
    const CarPrediction* lead = lane_cars[static_cast<std::size_t>(l)].leader;
    if (lead && std::find(leaders.begin(), leaders.end(), lead) == leaders.end())
      leaders.push_back(lead);
  }
  for (const CarPrediction* lead : leaders) {
    for (const double t : tp.follow_times_s) {
      const double tc = req.start_delay_s + t;
      const double v_lead = lead->s_dot_at(tc);
      const double gap = rss_front_gap(v_lead * mps, v_lead * mps, bp);
      const double s1 = lead->s_at(tc) - (car.length_m + gap) / mps;
      const double v1 = std::min(v_lead, s_dot_cap);
      add_lon({quintic(x0.s_m, x0.s_dot, x0.s_ddot, s1, v1, 0.0, t), {}, false});
    }
  }
  Longitudinal braking;
  braking.braking = true;
  braking.brake = BrakingProfile(x0.s_m, x0.s_dot, x0.s_ddot, tp.fallback_brake_mps2 / mps,
                                 tp.fallback_jerk_mps3 / mps);
  add_lon(braking);
  Longitudinal gentle;
  gentle.braking = true;
  gentle.brake =
      BrakingProfile(x0.s_m, x0.s_dot, x0.s_ddot, kGentleStopMps2 / mps, kGentleStopJerkMps3 / mps);
  add_lon(gentle);
  // Braking between the two, each reached gently enough to leave room for a lateral motion.
  for (std::size_t i = 0; i < tp.brake_levels_mps2.size(); ++i) {
    Longitudinal firm;
    firm.braking = true;
    firm.brake = BrakingProfile(x0.s_m, x0.s_dot, x0.s_ddot, tp.brake_levels_mps2[i] / mps,
                                tp.brake_level_jerk_mps3 / mps);
    add_lon(firm);
  }

  // Soft lane costs per longitudinal candidate.
  const std::size_t lane_n = static_cast<std::size_t>(road.lane_count);
  std::vector<LaneCost> soft(lons.size() * lane_n);
  for (std::size_t j = 0; j < lons.size(); ++j) {
    for (const int l : lanes) {
      const LaneCars& lc = lane_cars[static_cast<std::size_t>(l)];
      soft[j * lane_n + static_cast<std::size_t>(l)] =
          lane_cost(lons[j].samples, g, lc.ahead, lc.behind, mps, params, car);
    }
  }

  // Every combination, cheapest first.
  struct Combo {
    double cost;
    std::uint32_t lat;
    std::uint32_t lon;
  };
  std::vector<Combo> combos;
  combos.reserve(lats.size() * lons.size());
  for (std::size_t i = 0; i < lats.size(); ++i) {
    const auto end = static_cast<std::size_t>(lats[i].end_lane);
    for (std::size_t j = 0; j < lons.size(); ++j) {
      double c = lats[i].cost + lons[j].cost + soft[j * lane_n + end].full;
      if (lats[i].end_lane != start_lane)
        c += soft[j * lane_n + static_cast<std::size_t>(start_lane)].early;
      combos.push_back({c, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)});
    }
  }
  plan.candidates = static_cast<int>(combos.size());
  std::sort(combos.begin(), combos.end(),
            [](const Combo& a, const Combo& b) { return a.cost < b.cost; });

  const auto make = [&](const Combo& c) {
    Trajectory t;
    t.lateral = lats[c.lat].poly;
    t.longitudinal = lons[c.lon].motion;
    t.end_lane = lats[c.lat].end_lane;
    return t;
  };
  // How late a predicted collision comes, for choosing the least bad: one with a car ahead
  // (predicted to brake as hard as it can) counts as later than it is, one with a car from
  // behind (that does not see the ego) as it is.
  const auto lateness = [&](const CollisionReport& r) {
    return r.first_collision_s + (r.from_behind ? 0.0 : tp.ahead_collision_slack_s);
  };
  std::vector<std::pair<double, std::size_t>> failed;  // (lateness, combo index)
  for (std::size_t n = 0; n < combos.size(); ++n) {
    const Combo& c = combos[n];
    const LatCandidate& lat = lats[c.lat];
    const LonCandidate& lon = lons[c.lon];
    ++plan.collision_checks;
    const bool changing = lat.end_lane != start_lane;
    const CollisionReport col = collide(lon.samples, lat.samples, changing, changing || off_centre,
                                        g, car_samples, mps, params, car);
    if (!col.ok || lat.overstay_s < kInf) {
      // An incident ahead: a collision, or lingering on a lane line (the original counts it
      // as one, so it is weighed as one, at the time it would count).
      if (!col.ok && plan.collision_failures++ == 0) {
        plan.blocking_car = col.car_id;
        plan.blocking_time_s = col.first_collision_s;
      }
      failed.emplace_back(std::min(col.ok ? kInf : lateness(col), lat.overstay_s), n);
      continue;
    }
    if (plan.kinematic_checks >= tp.max_kinematic_checks) continue;
    ++plan.kinematic_checks;
    if (kinematics(lon.samples, lat.samples, g, line, tp, true, req.history).ok) {
      plan.trajectory = make(c);
      plan.status = PlanStatus::feasible;
      plan.cost = c.cost;
      return plan;
    }
  }

  // Nothing passed: the braking fallback, or the candidate whose first incident comes
  // latest, whichever comes later.
  Trajectory fallback;
  fallback.longitudinal = braking;
  double fallback_incident = kInf;
  if (!lats.empty()) {
    // With each lateral motion in turn, braking as fast as the lateral motion's own jerk
    // leaves room for: it must stay within the limits on the road, then collide as late as
    // it can, then be as gentle as it can.
    const LatCandidate* pick = nullptr;
    Longitudinal pick_brake = braking;
    KinematicReport pick_kin;
    double pick_collision = -kInf;
    for (const LatCandidate& c : lats) {
      double lat_jerk = 0.0;
      for (int k = 0; k <= g.n; ++k) lat_jerk = std::max(lat_jerk, std::abs(c.poly.at(g.t(k)).j));
      const double room =
          tp.fallback_total_jerk_mps3 * tp.fallback_total_jerk_mps3 - lat_jerk * lat_jerk;
      const double brake_jerk =
          std::clamp(std::sqrt(std::max(0.0, room)), kGentleStopJerkMps3, tp.fallback_jerk_mps3);
      Longitudinal brake;
      brake.braking = true;
      brake.brake = BrakingProfile(x0.s_m, x0.s_dot, x0.s_ddot, tp.fallback_brake_mps2 / mps,
                                   brake_jerk / mps);
      const Track1d brake_samples = sample(g, [&](double t) { return brake.at(t); });
      const bool changing = c.end_lane != start_lane;
      const CollisionReport col = collide(brake_samples, c.samples, changing,
                                          changing || off_centre, g, car_samples, mps, params, car);
      const KinematicReport kin =
          kinematics(brake_samples, c.samples, g, line, tp, false, req.history);
      const double incident = std::min(col.ok ? kInf : lateness(col), c.overstay_s);
      // Within the checked limits; else within the total jerk allowed to a fallback; else not.
      const auto tier = [&](const KinematicReport& k) {
        return k.ok ? 0 : (k.peak_jerk_mps3 <= tp.fallback_total_jerk_mps3 ? 1 : 2);
      };
      const auto better = [&] {
        if (!pick) return true;
        if (tier(kin) != tier(pick_kin)) return tier(kin) < tier(pick_kin);
        if (incident != pick_collision) return incident > pick_collision;
        return kin.peak_jerk_mps3 < pick_kin.peak_jerk_mps3;
      };
      if (better()) {
        pick = &c;
        pick_brake = brake;
        pick_kin = kin;
        pick_collision = incident;
      }
    }
    fallback.lateral = pick->poly;
    fallback.longitudinal = pick_brake;
    fallback.end_lane = pick->end_lane;
    fallback_incident = pick_collision;
  } else {
    fallback.end_lane = start_lane;
    const double back_to = core::lane_center_d(start_lane, road);
    fallback.lateral =
        quintic(x0.d_m, x0.d_dot_mps, x0.d_ddot_mps2, back_to, 0.0, 0.0,
                std::max(tp.min_lateral_time_s,
                         std::cbrt(60.0 * std::abs(back_to - x0.d_m) / tp.lateral_jerk_mps3)));
  }
  if (lats.empty()) {
    const CollisionReport fb =
        check_collisions(fallback, cars, req.start_delay_s, mps, params, road, car);
    fallback_incident = fb.ok ? kInf : lateness(fb);
  }
  std::stable_sort(failed.begin(), failed.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  int tried = 0;
  for (const auto& [when, n] : failed) {
    if (when <= fallback_incident || tried >= kLeastBadChecks) break;
    ++tried;
    const Combo& c = combos[n];
    ++plan.kinematic_checks;
    if (kinematics(lons[c.lon].samples, lats[c.lat].samples, g, line, tp, true, req.history).ok) {
      plan.trajectory = make(c);
      plan.status = PlanStatus::least_bad;
      plan.cost = c.cost;
      return plan;
    }
  }
  plan.trajectory = fallback;
  plan.status = PlanStatus::fallback;
  return plan;
}

}  // namespace overtake::planner::reference
