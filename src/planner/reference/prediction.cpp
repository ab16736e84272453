#include "overtake/planner/reference/prediction.hpp"

#include <algorithm>
#include <cmath>

#include "overtake/core/units.hpp"
#include "overtake/planner/reference/frenet.hpp"

namespace overtake::planner::reference {
namespace {

constexpr int kInverseIterations = 40;

double min_jerk_rate(double tau) {
  if (tau <= 0.0 || tau >= 1.0) return 0.0;
  return tau * tau * (30.0 + tau * (-60.0 + 30.0 * tau));
}

}  // namespace

double min_jerk_fraction(double tau) {
  tau = std::clamp(tau, 0.0, 1.0);
  return tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
}

double min_jerk_progress(double fraction) {
  fraction = std::clamp(fraction, 0.0, 1.0);
  double lo = 0.0;
  double hi = 1.0;
  for (int i = 0; i < kInverseIterations; ++i) {
    const double mid = 0.5 * (lo + hi);
    (min_jerk_fraction(mid) < fraction ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double CarPrediction::d_at(double t) const {
  if (!changing) return d_m;
  const double tau = change_progress + t / change_duration_s;
  return change_from_d_m + (change_to_d_m - change_from_d_m) * min_jerk_fraction(tau);
}

double CarPrediction::d_dot_at(double t) const {
  if (!changing) return 0.0;
  const double tau = change_progress + t / change_duration_s;
  return (change_to_d_m - change_from_d_m) * min_jerk_rate(tau) / change_duration_s;
}

CarPrediction predict_car(int id, double s_m, double s_dot, double s_ddot, double speed_mps,
                          double d_m, double d_dot_mps, const ReferencePredictionParams& params,
                          const core::RoadParams& road, double speed_up_to_mps) {
  CarPrediction c;
  c.id = id;
  c.s_m = s_m;
  c.s_dot = std::max(0.0, s_dot);
  c.speed_mps = std::max(0.0, speed_mps);
  c.d_m = d_m;
  c.d_dot_mps = d_dot_mps;
  c.lane = core::lane_of(d_m, road);
  c.target_lane = c.lane;
  c.change_duration_s = params.lane_change_duration_s;
  if (s_ddot < -params.braking_threshold_mps2) {
    c.s_ddot = s_ddot;
    c.brake_time_s = params.braking_horizon_s;
  }
  if (c.speed_mps < speed_up_to_mps) {
    // A car behind may speed up (traffic in front of it may pull away), as fast as it does
    // now or at least at follower_speed_up_mps2.
    const double scale = c.s_dot > 1e-9 && c.speed_mps > 1e-9 ? c.speed_mps / c.s_dot : 1.0;
    const double accel = std::max(s_ddot, params.follower_speed_up_mps2 / scale);
    if (accel > 0.0) {
      c.s_ddot = accel;
      c.brake_time_s = (speed_up_to_mps / scale - c.s_dot) / accel;
    }
  }

  // Lane change: moving sideways faster than lane keeping does. Away from its lane's
  // centre: heading for the next lane that way; towards it from far off: finishing a change
  // into it.
  const double w = road.lane_width_m;
  const int nearest = core::lane_of(d_m, road);
  const double offset = d_m - core::lane_center_d(nearest, road);
  const double dir = d_dot_mps > 0.0 ? 1.0 : -1.0;
  const bool fast = std::abs(d_dot_mps) > params.lane_change_speed_mps;
  bool changing = false;
  double to_d = 0.0;
  if (fast) {
    if (offset * dir >= 0.0) {
      const int next = nearest + (dir > 0.0 ? 1 : -1);
      if (next >= 0 && next < road.lane_count) {
        changing = true;
        to_d = core::lane_center_d(next, road);
      }
    } else if (std::abs(offset) > params.lane_change_offset_m) {
      changing = true;
      to_d = core::lane_center_d(nearest, road);
    }
  }
  if (changing) {
    const double from_d = to_d - dir * w;
    const double fraction = (d_m - from_d) / (to_d - from_d);
    c.changing = true;
    c.change_from_d_m = from_d;
    c.change_to_d_m = to_d;
    c.change_progress = min_jerk_progress(fraction);
    c.target_lane = core::lane_of(to_d, road);
    if (c.change_progress >= 1.0 - 1e-6) {
      c.changing = false;
      c.target_lane = c.lane;
    }
  }
  return c;
}

double cap_estimate(double top_speed_mps, const ReferencePredictionParams& p) {
  // Traffic settles at a share of its speed cap; caps are drawn from 40 mph up.
  return std::clamp(top_speed_mps / p.free_speed_share, p.min_cap_mps, p.max_cap_mps);
}

void anticipate_waves(std::vector<CarPrediction>& cars, const std::vector<CarTrack>& tracks,
                      double ego_s_m, double car_length_m, const ReferencePredictionParams& p) {
  const double length = car_length_m;
  for (CarPrediction& c : cars) {
    if (c.s_m <= ego_s_m || c.s_ddot < 0.0) continue;  // ahead of the ego, not braking already
    // Its leader: the nearest car ahead in its lane.
    const CarPrediction* lead = nullptr;
    for (const CarPrediction& o : cars) {
      if (&o == &c || !o.occupies(c.lane) || o.s_m <= c.s_m) continue;
      if (!lead || o.s_m < lead->s_m) lead = &o;
    }
    if (!lead) continue;
    const auto track =
        std::find_if(tracks.begin(), tracks.end(), [&](const CarTrack& t) { return t.id == c.id; });
    const double top = track == tracks.end() ? c.speed_mps : track->top_speed_mps;
    const double cap_mph = core::mps_to_mph(cap_estimate(top, p));
    const double scale = c.s_dot > 1e-9 && c.speed_mps > 1e-9 ? c.speed_mps / c.s_dot : 1.0;
    const double gap = (lead->s_m - c.s_m) * scale - length;
    const double reaction = p.reaction_gain_m * (cap_mph - lead->speed_mps);
    const double target = lead->speed_mps / core::kMphPerMps;  // the leader's m/s read as mph
    if (gap < reaction && c.speed_mps > target + p.braking_threshold_mps2) {
      c.s_ddot = -p.wave_brake_mps2 / scale;
      c.brake_time_s = (c.speed_mps - target) / p.wave_brake_mps2;
      c.recover_s_ddot = p.wave_recover_mps2 / scale;
    }
  }
}

std::vector<CarPrediction> predict_cars(const core::Telemetry& telemetry, const LaneFrame& frame,
                                        double ego_s_m, double elapsed_s,
                                        std::vector<CarTrack>& tracks,
                                        const ReferencePredictionParams& params,
                                        const core::RoadParams& road, double car_length_m) {
  std::vector<CarPrediction> out;
  out.reserve(telemetry.cars.size());
  std::vector<CarTrack> next;
  next.reserve(telemetry.cars.size());
  const core::ReferenceLine& line = frame.line();
  const double road_width = core::road_width_m(road);
  for (const core::CarObservation& car : telemetry.cars) {
    // The original reports a newly placed car's speed cap read as m/s for one frame (2.24
    // times its real speed); no car on its roads goes that fast.
    core::Vec2 velocity = car.velocity_mps;
    if (core::norm(velocity) > params.max_plausible_speed_mps)
      velocity = (1.0 / core::kMphPerMps) * velocity;
    RoadPoint at;  // the frame's geometry where the car is
    const FrenetState x = frenet_from_cartesian(frame, car.position, velocity, car.s_m, &at);
    // Cars waiting off the road (the original parks them far beside it) are no traffic.
    if (x.d_m < -params.off_road_margin_m || x.d_m > road_width + params.off_road_margin_m)
      continue;
    const double speed = x.s_dot * at.along_scale;
    double accel = 0.0;
    double top_speed = speed;
    const auto prev = std::find_if(tracks.begin(), tracks.end(),
                                   [&](const CarTrack& t) { return t.id == car.id; });
    if (prev != tracks.end() && elapsed_s > 0.0 &&
        std::abs(line.s_ahead(prev->s_m, x.s_m) - prev->s_dot * elapsed_s) <
            params.max_track_jump_m) {
      accel = (x.s_dot - prev->s_dot) / elapsed_s;
      // A change no car's brakes or engine make is a glitch of the report, not a motion.
      if (std::abs(accel * at.along_scale) > params.max_plausible_accel_mps2) accel = 0.0;
      top_speed = std::max(top_speed, prev->top_speed_mps);
    }
    next.push_back({car.id, x.s_m, x.s_dot, accel, top_speed});
    const double s_unwrapped = ego_s_m + line.s_ahead(ego_s_m, x.s_m);
    // Cars behind may speed up (they may be closing on the ego): towards the fastest it has
    // been seen going and a margin. (A placed car's first frame shows its cap.) Ahead, only
    // braking is extrapolated.
    const double up_to = top_speed + params.follower_speed_margin_mps;
    out.push_back(predict_car(car.id, s_unwrapped, x.s_dot, accel, speed, x.d_m, x.d_dot_mps,
                              params, road, s_unwrapped < ego_s_m ? up_to : 0.0));
    out.back().cap_mps = cap_estimate(top_speed, params);
    out.back().observed_accel_mps2 = accel * at.along_scale;
  }
  anticipate_waves(out, next, ego_s_m, car_length_m, params);
  tracks = std::move(next);
  return out;
}

}  // namespace overtake::planner::reference
