#include "overtake/sim/faithful_traffic.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <sstream>

#include "overtake/core/road.hpp"
#include "overtake/core/units.hpp"
#include "overtake/sim/checkpoint.hpp"

namespace overtake::sim {
namespace {

constexpr std::uint64_t kSpawnStream = 0;
constexpr std::uint64_t kFirstCarStream = 100;
/// A parked car stands at least this far from every waypoint (off any road of the map, and
/// farther from the ego than the distance that releases it); when its spot is not, it moves
/// this much farther out, up to kParkTries times.
constexpr double kParkClearanceM = 250.0;
constexpr int kParkTries = 20;
constexpr double kParkSpacingM = 6.0;
/// Bodies farther than this sideways from a ray cannot be hit by it (half a diagonal + slack).
constexpr double kRayCullSlackM = 1.0;
/// Steps of the open-road table's march along a ray.
constexpr double kOpenRoadStepM = 2.0;
/// Below this speed the turning limit of grip is taken at this speed (no division by 0).
constexpr double kMinTurnSpeedMps = 1.0;

[[nodiscard]] double quintic(double f) {
  return f * f * f * (f * (6.0 * f - 15.0) + 10.0);
}

[[nodiscard]] core::Vec2 unit(double heading_rad) {
  return {std::cos(heading_rad), std::sin(heading_rad)};
}

}  // namespace

// ----- SmoothNoise -------------------------------------------------------------------------

SmoothNoise::SmoothNoise(std::uint64_t seed) : rng_(seed) {
  v0_ = draw();
  v1_ = draw();
}

double SmoothNoise::draw() {
  // Triangular on [0, 1]: like Perlin noise, values gather around the middle.
  return 0.5 * (rng_.uniform01() + rng_.uniform01());
}

double SmoothNoise::at(double x) {
  const auto cell = static_cast<long>(std::floor(x));
  while (cell_ < cell) {
    v0_ = v1_;
    v1_ = draw();
    ++cell_;
  }
  return v0_ + (v1_ - v0_) * quintic(std::clamp(x - static_cast<double>(cell_), 0.0, 1.0));
}

// ----- construction ------------------------------------------------------------------------

FaithfulTraffic::FaithfulTraffic(const core::WaypointFrenet& chords,
                                 const core::ReferenceLine& line, const TrafficParams& params,
                                 const core::RoadParams& road, const core::CarFootprint& car,
                                 std::uint64_t seed, std::shared_ptr<const OpenRoadTable> open_road)
    : chords_(chords),
      line_(line),
      params_(params),
      f_(params.faithful),
      road_(road),
      car_(car),
      spawn_rng_(core::derive_seed(seed, kSpawnStream)) {
  const auto n = static_cast<std::size_t>(std::max(0, params.car_count));
  cars_.resize(n);
  drivers_.resize(n);
  parked_.resize(n);
  commands_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    cars_[i].id = static_cast<int>(i);
    drivers_[i].noise = SmoothNoise(core::derive_seed(seed, kFirstCarStream + i));
    drivers_[i].clear_counts.assign(static_cast<std::size_t>(road.lane_count), 0);
  }
  units_.resize(n);
  body_reach_m_ = 0.5 * std::hypot(car_.length_m, car_.width_m) + kRayCullSlackM;
  open_road_ = open_road ? std::move(open_road) : build_open_road_table(line, road, f_);
}

std::shared_ptr<const OpenRoadTable> build_open_road_table(const core::ReferenceLine& line,
                                                           const core::RoadParams& road,
                                                           const FaithfulTrafficParams& f) {
  auto table = std::make_shared<OpenRoadTable>();
  std::size_t& bins = table->bins;
  std::vector<unsigned char>& open = table->open;
  // A straight ray from a lane's centre along the road drifts off it where the road bends:
  // by K(x) = integral over [0, x] of (x - w) * curvature(s + w) dw, to the outside of the
  // bend. I1, I2: running integrals of the curvature at 1 m steps (past the end by the
  // horizon, wrapping).
  const double horizon = f.ray_horizon_m;
  const double length = line.length_m();
  bins = static_cast<std::size_t>(std::ceil(length));
  const std::size_t extra = static_cast<std::size_t>(std::ceil(horizon)) + 2;
  const std::size_t total = bins + extra;
  std::vector<double> i1(total, 0.0);
  std::vector<double> i2(total, 0.0);
  double prev_k = 0.0;
  for (std::size_t b = 0; b < total; ++b) {
    const core::RoadFrame fr = line.frame(line.wrap_s(line.start_s_m() + static_cast<double>(b)));
    // The frame's normal is on the side d grows: turning left moves a straight ray to the
    // right of the road.
    const double side = core::cross(fr.tangent, fr.normal) < 0.0 ? 1.0 : -1.0;
    const double k = side * fr.curvature_1pm;
    if (b > 0) {
      i1[b] = i1[b - 1] + 0.5 * (prev_k + k);
      i2[b] = i2[b - 1] + 0.5 * (i1[b - 1] + i1[b]);
    }
    prev_k = k;
  }
  const double road_width = core::road_width_m(road);
  const auto lanes = static_cast<std::size_t>(road.lane_count);
  open.assign(lanes * bins, 1);
  for (std::size_t lane = 0; lane < lanes; ++lane) {
    const double d0 = core::lane_center_d(static_cast<int>(lane), road);
    for (std::size_t b = 0; b < bins; ++b) {
      for (double x = kOpenRoadStepM; x <= horizon; x += kOpenRoadStepM) {
        const auto bx = b + static_cast<std::size_t>(x);
        const double d = d0 + (i2[bx] - i2[b] - x * i1[b]);
        if (d < -f.scenery_margin_m || d > road_width + f.scenery_margin_m) {
          open[lane * bins + b] = 0;
          break;
        }
      }
    }
  }
  return table;
}

// ----- start, parking, placement -----------------------------------------------------------

void FaithfulTraffic::park(std::size_t i) {
  TrafficCar& c = cars_[i];
  c.parked = true;
  c.speed_mps = 0.0;
  c.reported_velocity_mps = {};
  c.position = parked_[i];
  c.closest_waypoint = chords_.closest(c.position);
  c.map_frenet = chords_.to_frenet(c.position, c.closest_waypoint);
  c.heading_rad =
      std::atan2(chords_.forward(c.closest_waypoint).y, chords_.forward(c.closest_waypoint).x);
}

void FaithfulTraffic::start(const EgoView& /*ego*/) {
  // Every car waits off the road, on the divider's side near the end of the loop (where the
  // original's scene parks them), moved farther out on maps where that spot is near a road.
  for (std::size_t i = 0; i < cars_.size(); ++i) {
    const double s = chords_.s(0) + chords_.loop_length_m() - f_.parked_s_before_end_m +
                     kParkSpacingM * static_cast<double>(i);
    double d = f_.parked_d_m;
    core::Vec2 spot = chords_.to_cartesian({s, d});
    for (int k = 0; k < kParkTries; ++k) {
      const core::Vec2 near = chords_.position(chords_.closest(spot));
      if (core::distance(near, spot) >= kParkClearanceM) break;
      d += (d < 0.0 ? -1.0 : 1.0) * kParkClearanceM;
      spot = chords_.to_cartesian({s, d});
    }
    parked_[i] = spot;
    park(i);
    drivers_[i].cap_mps = 0.0;
    drivers_[i].staged = false;
  }
  init_ = true;
  frame_counter_ = 0;
  frames_to_batch_ = 0;
}

void FaithfulTraffic::spawn(std::size_t i, const EgoView& ego) {
  const PlacementParams& p = params_.placement;
  TrafficCar& c = cars_[i];
  Driver& dr = drivers_[i];
  const double min_sq = p.min_spawn_distance_m * p.min_spawn_distance_m;
  for (int attempt = 0; attempt < p.max_spawn_attempts; ++attempt) {
    // The original draws the lane, then a spot behind with a cap for it, then whether to go
    // ahead instead (with its own spot and cap); each attempt sets the car's lane and cap.
    const int lane = spawn_rng_.uniform_int(0, road_.lane_count - 1);
    int offset = -spawn_rng_.uniform_int(p.behind_min_waypoints, p.behind_max_waypoints);
    double cap = spawn_rng_.uniform(p.behind_min_speed_mps, p.behind_max_speed_mps);
    if (!spawn_rng_.chance(p.behind_probability)) {
      offset = spawn_rng_.uniform_int(p.ahead_min_waypoints, p.ahead_max_waypoints);
      cap = spawn_rng_.uniform(p.ahead_min_speed_mps, p.ahead_max_speed_mps);
    }
    c.lane = lane;
    dr.cap_mps = cap;
    dr.lane_change_time = 0;
    const std::size_t wp = chords_.wrap_index(static_cast<long>(ego.closest_waypoint) + offset);
    const core::Vec2 spot = chords_.offset_point(wp, core::lane_center_d(lane, road_));
    bool free = true;
    for (const TrafficCar& o : cars_) {
      if (core::distance_sq(o.position, spot) < min_sq) {
        free = false;
        break;
      }
    }
    if (!free) continue;
    const core::Vec2 fwd = chords_.forward(wp);
    c.parked = false;
    c.position = spot;
    c.heading_rad = std::atan2(fwd.y, fwd.x);
    // The original sets the body's velocity to the cap read as m/s; the cap clamps it on
    // the car's next step, but one frame reports it.
    c.speed_mps = core::mps_to_mph(cap);
    c.reported_velocity_mps = c.speed_mps * fwd;
    c.closest_waypoint = wp;
    refresh_frenet(i);
    dr.target_waypoint = wp;
    dr.staged = false;
    dr.fresh = true;
    return;
  }
  // No free spot in all attempts: the original gives up on the car, which stays staged (and
  // so is never placed again) and drives on wherever it is, with the last lane and cap drawn.
}

void FaithfulTraffic::batch(const EgoView& ego) {
  const PlacementParams& p = params_.placement;
  if (!init_ && frame_counter_ < frames_to_batch_) {
    ++frame_counter_;
    return;
  }
  init_ = false;
  const double far_sq = p.despawn_distance_m * p.despawn_distance_m;
  for (std::size_t i = 0; i < cars_.size(); ++i) {
    if (!drivers_[i].staged && core::distance_sq(cars_[i].position, ego.body.center) > far_sq) {
      drivers_[i].staged = true;
      queue_.push_back(i);
    }
  }
  const int push = spawn_rng_.uniform_int(p.batch_min_cars, p.batch_max_cars);
  for (int k = 0; k < push && !queue_.empty(); ++k) {
    const std::size_t i = queue_.front();
    queue_.pop_front();
    spawn(i, ego);
  }
  frame_counter_ = 0;
  // The original's Random.Range(20, 60): 20 to 59, a batch when the counter reaches it.
  frames_to_batch_ = spawn_rng_.uniform_int(p.batch_min_frames,
                                            std::max(p.batch_min_frames, p.batch_max_frames - 1));
}

void FaithfulTraffic::put_on_road_for_testing(std::size_t i, double s_m, int lane, double speed_mps,
                                              double cap_mps) {
  TrafficCar& c = cars_[i];
  Driver& dr = drivers_[i];
  const double d = core::lane_center_d(lane, road_);
  c.position = chords_.to_cartesian({s_m, d});
  c.heading_rad = chords_.chord_heading_rad(s_m);
  c.speed_mps = speed_mps;
  c.reported_velocity_mps = speed_mps * unit(c.heading_rad);
  c.lane = lane;
  c.parked = false;
  c.closest_waypoint = chords_.closest(c.position);
  refresh_frenet(i);
  dr.cap_mps = cap_mps;
  dr.target_waypoint = chords_.next(c.position, c.closest_waypoint);
  dr.lane_change_time = f_.lane_change_wait_steps;
  std::fill(dr.clear_counts.begin(), dr.clear_counts.end(), 0);
  dr.staged = false;
  dr.fresh = false;
  dr.avoid_until_s = -1.0;
  queue_.erase(std::remove(queue_.begin(), queue_.end(), i), queue_.end());
}

void FaithfulTraffic::refresh_frenet(std::size_t i) {
  TrafficCar& c = cars_[i];
  c.closest_waypoint = chords_.closest(c.position, c.closest_waypoint);
  c.map_frenet = chords_.to_frenet(c.position, c.closest_waypoint);
}

// ----- seeing ahead ------------------------------------------------------------------------

core::OrientedBox FaithfulTraffic::body(std::size_t i) const {
  const TrafficCar& c = cars_[i];
  return {c.position, c.heading_rad, car_.length_m, car_.width_m};
}

bool FaithfulTraffic::road_open_ahead(std::size_t i) const {
  const TrafficCar& c = cars_[i];
  // The table is indexed by s on the line; the chord s is within a metre of it.
  double s = c.map_frenet.s_m - line_.start_s_m();
  s = std::fmod(s, line_.length_m());
  if (s < 0.0) s += line_.length_m();
  const OpenRoadTable& table = *open_road_;
  const auto bin = std::min(table.bins - 1, static_cast<std::size_t>(s));
  const auto lane = static_cast<std::size_t>(core::lane_of(c.map_frenet.d_m, road_));
  return table.open[lane * table.bins + bin] != 0;
}

FaithfulTraffic::Sight FaithfulTraffic::look(std::size_t i, const EgoView& ego, core::Vec2 ego_axis,
                                             double ego_reach_m) {
  const TrafficCar& self = cars_[i];
  const std::size_t n = cars_.size();
  // The units were refreshed at the start of the step, and headings do not change while
  // the cars decide.
  const core::Vec2 dir = units_[i].of_current();
  const core::Vec2 origin = self.position + (0.5 * car_.length_m) * dir;
  // The ray meets the nearest body it enters (the first in order, cars then the ego, of
  // equally near ones). A body whose centre is farther than its reach (half its diagonal,
  // and slack) beside the ray or behind its origin cannot be met; one cannot be met nearer
  // than its distance along the ray less its reach. Exact tests go nearest-first, so that
  // once one is met the bodies beyond it are skipped.
  near_ray_.clear();
  const auto note = [&](core::Vec2 center, double reach, std::size_t order) {
    const core::Vec2 rel = center - origin;
    const double along = core::dot(rel, dir);
    if (along < -reach) return;
    if (std::abs(core::cross(dir, rel)) > reach) return;
    double least = along - reach;
    if (std::isnan(least)) least = -std::numeric_limits<double>::infinity();  // always tested
    near_ray_.push_back({least, order});
  };
  for (std::size_t j = 0; j < n; ++j) {
    if (j == i || cars_[j].parked) continue;
    note(cars_[j].position, body_reach_m_, j);
  }
  note(ego.body.center, ego_reach_m, n);
  std::sort(near_ray_.begin(), near_ray_.end(),
            [](const NearRay& a, const NearRay& b) { return a.least_t_m < b.least_t_m; });
  Sight best;
  double best_t = std::numeric_limits<double>::infinity();
  std::size_t best_order = n + 1;
  for (const NearRay& c : near_ray_) {
    if (c.least_t_m > best_t) break;
    const bool is_ego = c.order == n;
    const std::optional<double> t =
        is_ego ? core::ray_box_distance(origin, dir, ego.body, ego_axis)
               : core::ray_box_distance(origin, dir, body(c.order), units_[c.order].of_current());
    if (t && (*t < best_t || (*t == best_t && c.order < best_order))) {
      best_t = *t;
      best_order = c.order;
      best = is_ego
                 ? Sight{SightKind::ego, -1, *t, ego.speed_mps}
                 : Sight{SightKind::car, static_cast<int>(c.order), *t, cars_[c.order].speed_mps};
    }
  }
  if (best.kind != SightKind::nothing) return best;
  // No body: scenery beside the road where the ray leaves it, or nothing at all (the
  // original then reads a distance of 0).
  if (road_open_ahead(i)) return {};
  return {SightKind::scenery, -1, f_.ray_horizon_m, 0.0};
}

bool FaithfulTraffic::lane_clear(std::size_t i, int lane, const EgoView& ego) const {
  // CarTraffic.lane_clear: every other car whose d is within 2 m of the lane's centre, and
  // the ego within 3 m, more than 20 m away in s (raw differences, as the original compares).
  const double centre = core::lane_center_d(lane, road_);
  const double s = cars_[i].map_frenet.s_m;
  for (std::size_t j = 0; j < cars_.size(); ++j) {
    if (j == i) continue;
    const core::FrenetPoint& o = cars_[j].map_frenet;
    if (o.d_m < centre + f_.car_lane_half_width_m && o.d_m > centre - f_.car_lane_half_width_m &&
        std::abs(o.s_m - s) <= f_.clear_gap_m) {
      return false;
    }
  }
  const core::FrenetPoint& e = ego.map_frenet;
  return !(e.d_m < centre + f_.ego_lane_half_width_m && e.d_m > centre - f_.ego_lane_half_width_m &&
           std::abs(e.s_m - s) <= f_.clear_gap_m);
}

int FaithfulTraffic::count_lane_change(std::size_t i, const EgoView& ego) {
  // The original's counters: from an edge lane it counts towards the lane beside it; from a
  // middle lane towards the divider's side first, then the other; any blocked check resets
  // every counter. More than clear_steps counted steps: change now.
  Driver& dr = drivers_[i];
  const int lane = cars_[i].lane;
  const int last = road_.lane_count - 1;
  if (last < 1) return -1;
  const auto reset = [&dr] { std::fill(dr.clear_counts.begin(), dr.clear_counts.end(), 0); };
  const auto try_lane = [&](int target) -> bool {
    int& count = dr.clear_counts[static_cast<std::size_t>(target)];
    if (lane_clear(i, target, ego)) {
      ++count;
    } else {
      reset();
    }
    if (count > f_.clear_steps) {
      count = 0;
      return true;
    }
    return false;
  };
  if (lane == 0) return try_lane(1) ? 1 : -1;
  if (lane == last) return try_lane(last - 1) ? last - 1 : -1;
  if (try_lane(lane - 1)) return lane - 1;
  return try_lane(lane + 1) ? lane + 1 : -1;
}

// ----- one step ----------------------------------------------------------------------------

FaithfulTraffic::Command FaithfulTraffic::decide(std::size_t i, const EgoView& ego,
                                                 core::Vec2 ego_axis, double ego_reach_m) {
  TrafficCar& c = cars_[i];
  Driver& dr = drivers_[i];
  Command cmd;
  const double speed_mph = core::mps_to_mph(c.speed_mps);
  const double cap_mph = core::mps_to_mph(dr.cap_mps);

  // The target waypoint moves on when the car comes within reach of it (more for the outer
  // lanes, whose points are farther from the waypoint). (ours) Also when the car is past it:
  // after a lane change close to a waypoint it may pass wide of the smaller reach, and the
  // original would then turn back for it.
  for (std::size_t k = 0; k < chords_.size(); ++k) {
    const std::size_t wp = dr.target_waypoint;
    const double reach = f_.target_reach_m + f_.target_reach_per_lane_m * c.lane;
    const core::Vec2 at = chords_.position(wp);
    const bool passed = core::dot(at - c.position, chords_.forward(wp)) < 0.0;
    if (core::distance_at_least(at, c.position, reach) && !passed) break;
    dr.target_waypoint = chords_.wrap_index(static_cast<long>(wp) + 1);
  }

  // The ray ahead, and the reaction to what it meets.
  const Sight sight = look(i, ego, ego_axis, ego_reach_m);
  const bool body = sight.kind == SightKind::car || sight.kind == SightKind::ego;
  const double reaction_m =
      body ? f_.reaction_gain_m * (cap_mph - sight.body_speed_mps) : f_.no_body_reaction_m;
  const bool react = sight.distance_m < reaction_m;
  double desired_mph = cap_mph;
  // The body's speed in m/s taken as mph: about 0.45 of it.
  if (react && body) desired_mph = sight.body_speed_mps;

  if (react && c.speed_mps > f_.lane_change_min_speed_mps &&
      dr.lane_change_time >= f_.lane_change_wait_steps) {
    const std::size_t next = chords_.next(c.position, c.closest_waypoint);
    if (core::distance(chords_.position(next), c.position) < f_.waypoint_trigger_m) {
      cmd.new_lane = count_lane_change(i, ego);
    }
  }
  if (dr.lane_change_time < f_.lane_change_wait_steps) ++dr.lane_change_time;

  // Wander (or evasive action after a contact) and the pedal.
  const double noise = dr.noise.at(time_s_ * f_.wander_rate_hz);
  double lateral_m = (2.0 * noise - 1.0) * f_.lateral_wander_m;
  if (time_s_ < dr.avoid_until_s) {
    desired_mph *= dr.avoid_slowdown;
    lateral_m = dr.avoid_offset_m;
  }
  const double sensitivity =
      desired_mph < speed_mph ? f_.brake_sensitivity_per_mph : f_.accel_sensitivity_per_mph;
  cmd.pedal = std::clamp((desired_mph - speed_mph) * sensitivity, -1.0, 1.0) *
              ((1.0 - f_.accel_wander_amount) + noise * f_.accel_wander_amount);

  // Steering: towards the lane point of the target waypoint (the new lane's, after a
  // change), in proportion to the angle to it.
  const int lane = cmd.new_lane >= 0 ? cmd.new_lane : c.lane;
  const core::Vec2 target =
      chords_.offset_point(dr.target_waypoint, core::lane_center_d(lane, road_) + lateral_m);
  const core::Vec2 fwd = units_[i].of_current();
  const core::Vec2 rel = target - c.position;
  const double angle_deg =
      core::rad_to_deg(std::atan2(-core::cross(fwd, rel), core::dot(fwd, rel)));
  cmd.steer = std::clamp(angle_deg * f_.steer_sensitivity_per_deg, -1.0, 1.0);

  dr.sight = sight.kind;
  dr.sight_car = sight.car;
  dr.sight_distance_m = sight.distance_m;
  dr.reacting = react;
  dr.desired_mph = desired_mph;
  dr.pedal = cmd.pedal;
  return cmd;
}

void FaithfulTraffic::move(std::size_t i, const Command& cmd, double dt_s) {
  TrafficCar& c = cars_[i];
  Driver& dr = drivers_[i];
  if (cmd.new_lane >= 0) {
    // The original resets its counter and, later in the same update, counts this step.
    c.lane = cmd.new_lane;
    dr.lane_change_time = std::min(1, f_.lane_change_wait_steps);
  }
  // The cap holds the body's speed (the first step after placement clamps the cap read as
  // m/s); then throttle against drag, or the brake.
  double v = std::min(c.speed_mps, dr.cap_mps);
  const double throttle = std::max(0.0, cmd.pedal);
  const double brake = std::max(0.0, -cmd.pedal);
  const double accel = f_.engine_mps2 * throttle - f_.drag_per_s * v - f_.brake_mps2 * brake;
  v = std::clamp(v + accel * dt_s, 0.0, dr.cap_mps);
  // Turning: a car with front-wheel steering, as far as its grip allows.
  const double steer_rad = core::deg_to_rad(cmd.steer * f_.max_steer_deg);
  double yaw_rate = -v * std::tan(steer_rad) / f_.wheelbase_m;
  const double grip = f_.max_lateral_accel_mps2 / std::max(v, kMinTurnSpeedMps);
  yaw_rate = std::clamp(yaw_rate, -grip, grip);
  c.heading_rad = core::wrap_angle_rad(c.heading_rad + yaw_rate * dt_s);
  c.speed_mps = v;
  const core::Vec2 dir = units_[i].of(c.heading_rad);
  c.position = c.position + (v * dt_s) * dir;
  c.reported_velocity_mps = v * dir;
  dr.fresh = false;
  refresh_frenet(i);
}

void FaithfulTraffic::step(const EgoView& ego, double dt_s) {
  const std::size_t n = cars_.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (!cars_[i].parked) (void)units_[i].of(cars_[i].heading_rad);
  }
  const core::Vec2 ego_axis = ego_unit_.of(ego.body.heading_rad);
  const double ego_reach_m =
      ego.body.length_m == car_.length_m && ego.body.width_m == car_.width_m
          ? body_reach_m_
          : 0.5 * std::hypot(ego.body.length_m, ego.body.width_m) + kRayCullSlackM;
  for (std::size_t i = 0; i < n; ++i) {
    if (!cars_[i].parked) commands_[i] = decide(i, ego, ego_axis, ego_reach_m);
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (!cars_[i].parked) move(i, commands_[i], dt_s);
  }
  time_s_ += dt_s;
  if (!batches_held_) batch(ego);
}

void FaithfulTraffic::on_contact(std::size_t i, core::Vec2 shift_m, double speed_mps,
                                 const core::OrientedBox& other) {
  TrafficCar& c = cars_[i];
  Driver& dr = drivers_[i];
  c.position = c.position + shift_m;
  c.speed_mps = std::max(0.0, speed_mps);
  c.reported_velocity_mps = c.speed_mps * unit(c.heading_rad);
  refresh_frenet(i);
  // The original's evasive action: for a second, slow down when the other is in front, and
  // steer along an offset away from it.
  const core::Vec2 fwd = unit(c.heading_rad);
  const core::Vec2 rel = other.center - c.position;
  dr.avoid_until_s = time_s_ + f_.avoid_time_s;
  dr.avoid_slowdown = core::dot(fwd, rel) > 0.0 ? f_.avoid_slowdown : 1.0;
  const double right = -core::cross(fwd, rel);  // > 0: the other is to the right
  dr.avoid_offset_m = (right > 0.0 ? -1.0 : 1.0) * f_.lateral_wander_m;
}

}  // namespace overtake::sim

// ----- checkpoints -------------------------------------------------------------------------

namespace overtake::sim {

void SmoothNoise::archive(core::StateArchive& ar, long max_cell) {
  ar.io(rng_, "noise stream");
  ar.io_range(cell_, 0, max_cell, "noise cell");
  ar.io(v0_, "noise value");
  ar.io(v1_, "noise value");
}

void FaithfulTraffic::archive(core::StateArchive& ar) {
  ar.part("faithful traffic");
  const std::size_t n = cars_.size();
  const int lanes = road_.lane_count;
  const std::size_t waypoints = chords_.size();
  // The noise is sampled at time * rate, and time never passes kMaxCheckpointRunS.
  const auto max_cell = static_cast<long>(std::floor(kMaxCheckpointRunS * f_.wander_rate_hz)) + 1;
  ar.io(spawn_rng_, "spawn stream");
  ar.require(ar.io_length(n, n, "cars") == n, "the checkpoint has another number of cars");
  for (std::size_t i = 0; i < n; ++i) {
    archive_car(ar, cars_[i], lanes, waypoints);
    Driver& d = drivers_[i];
    ar.io_speed(d.cap_mps, "cap");
    ar.io_range(d.target_waypoint, 0, waypoints - 1, "target waypoint");
    ar.io(d.lane_change_time, "lane change time");
    ar.require(ar.io_length(d.clear_counts.size(), d.clear_counts.size(), "clear counts") ==
                   d.clear_counts.size(),
               "the checkpoint has another number of lanes");
    for (int& c : d.clear_counts) ar.io(c, "clear count");
    ar.io(d.staged, "staged");
    ar.io(d.fresh, "fresh");
    ar.io(d.avoid_until_s, "avoid until");
    ar.io(d.avoid_slowdown, "avoid slowdown");
    ar.io_metres(d.avoid_offset_m, "avoid offset");
    d.noise.archive(ar, max_cell);
    ar.io_enum(d.sight, SightKind::ego, "sight");
    ar.io_range(d.sight_car, -1, static_cast<int>(n) - 1, "sight car");
    ar.io_metres(d.sight_distance_m, "sight distance");
    ar.io(d.reacting, "reacting");
    ar.io_speed(d.desired_mph, "desired speed");
    ar.io(d.pedal, "pedal");
    ar.io(parked_[i], "parked position");
  }
  const std::size_t queued = ar.io_length(queue_.size(), n, "staged queue");
  if (ar.loading()) queue_.assign(queued, 0);
  for (std::size_t& i : queue_) ar.io_range(i, 0, n - 1, "staged car");
  ar.io(init_, "first frame");
  ar.io(batches_held_, "batches held");
  ar.io(frame_counter_, "frame counter");
  ar.io(frames_to_batch_, "frames to batch");
  ar.io(time_s_, "time");
  if (ar.loading() && !(time_s_ >= 0.0 && time_s_ <= kMaxCheckpointRunS)) {
    std::ostringstream os;
    os << "time: " << time_s_ << " s is outside [0, " << kMaxCheckpointRunS << "] s";
    ar.require(false, os.str());
  }
}

}  // namespace overtake::sim
