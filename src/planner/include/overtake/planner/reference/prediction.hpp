#pragma once
// The prediction layer of the reference planner: each other car's lane, speed along the
// road and lateral speed; a car drifting toward or across a lane line is predicted into the
// lane it is entering (a cut-in) before it gets there. Predictions over the horizon are
// constant-velocity along the road (with braking continued for a short while) and either
// lane keeping or a constant lane change (a minimum-jerk lateral profile to the next lane's
// centre).

#include <algorithm>
#include <vector>

#include "overtake/core/reference_line.hpp"
#include "overtake/core/road.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/planner/params.hpp"
#include "overtake/planner/reference/frenet.hpp"

namespace overtake::planner::reference {

/// What a car was last seen doing (kept between cycles to estimate its acceleration).
struct CarTrack {
  int id = -1;
  double s_m = 0.0;            ///< wrapped, as observed
  double s_dot = 0.0;          ///< along the road
  double s_ddot = 0.0;         ///< estimated acceleration along the road
  double top_speed_mps = 0.0;  ///< the fastest it has been seen going
};

/// One car's predicted motion, from the time it was observed.
struct CarPrediction {
  int id = 0;
  double s_m = 0.0;           ///< unwrapped: within half a loop of the ego's s
  double s_dot = 0.0;         ///< ds/dt along the road
  double s_ddot = 0.0;        ///< acceleration continued for a short while (braking; or
                              ///< speeding up, for cars behind the ego); 0 otherwise
  double brake_time_s = 0.0;  ///< how long s_ddot is continued
  /// After that, it speeds back up at this (units of s per second squared; 0: it does not)
  /// to its speed now: a car braking in a stop-and-go wave surges again.
  double recover_s_ddot = 0.0;
  double cap_mps = 0.0;              ///< estimated speed cap (0: unknown)
  double observed_accel_mps2 = 0.0;  ///< its acceleration along the road, as estimated now
  double speed_mps = 0.0;            ///< along the road, m/s
  double d_m = 0.0;
  double d_dot_mps = 0.0;
  int lane = 0;                  ///< the lane its d lies in now
  int target_lane = 0;           ///< where it is heading (== lane unless changing)
  bool changing = false;         ///< a lane change detected
  double change_from_d_m = 0.0;  ///< lane change: start and end d of the lateral profile ...
  double change_to_d_m = 0.0;
  double change_progress = 0.0;  ///< ... and the share of its time already done, in [0, 1]
  double change_duration_s = 3.0;

  /// s at `t_s` after the observation. (Inline, as s_dot_at: the planner samples every car
  /// near over its horizon each cycle.)
  [[nodiscard]] double s_at(double t_s) const {
    const double t = t_s;
    if (s_ddot == 0.0 || t <= 0.0) return s_m + s_dot * t;
    // Braking (or speeding up) for brake_time_s, then steady, or back up to the speed it had;
    // the speed never goes below zero.
    const double tb = std::min(t, brake_time_s);
    const double t_stop = s_ddot < 0.0 ? s_dot / -s_ddot : tb + 1.0;
    if (t_stop <= tb) return s_m + 0.5 * s_dot * t_stop;
    const double v = s_dot + s_ddot * tb;
    const double s_b = s_m + s_dot * tb + 0.5 * s_ddot * tb * tb;
    if (t <= brake_time_s || recover_s_ddot <= 0.0 || v >= s_dot) return s_b + v * (t - tb);
    const double tr = std::min(t - brake_time_s, (s_dot - v) / recover_s_ddot);
    return s_b + v * tr + 0.5 * recover_s_ddot * tr * tr + s_dot * (t - brake_time_s - tr);
  }
  /// ds/dt at `t_s`.
  [[nodiscard]] double s_dot_at(double t_s) const {
    const double t = t_s;
    const double v = std::max(0.0, s_dot + s_ddot * std::clamp(t, 0.0, brake_time_s));
    if (t <= brake_time_s || recover_s_ddot <= 0.0 || v >= s_dot) return v;
    return std::min(s_dot, v + recover_s_ddot * (t - brake_time_s));
  }
  /// d at `t_s`.
  [[nodiscard]] double d_at(double t_s) const;
  /// dd/dt at `t_s`.
  [[nodiscard]] double d_dot_at(double t_s) const;
  /// True when the car is in `lane` now or heading into it.
  [[nodiscard]] bool occupies(int l) const { return l == lane || l == target_lane; }
};

/// Minimum-jerk profile x(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 on [0, 1], clamped outside.
[[nodiscard]] double min_jerk_fraction(double tau);
/// Inverse of min_jerk_fraction on [0, 1].
[[nodiscard]] double min_jerk_progress(double fraction);

/// Predicts every car on the road (cars parked off it are left out). `ego_s_m` (unwrapped)
/// anchors the cars' unwrapped s;
/// `tracks` holds last cycle's tracks and is replaced by this cycle's; `elapsed_s` is the
/// time since the last cycle (0: unknown, no acceleration estimate).
[[nodiscard]] std::vector<CarPrediction> predict_cars(
    const core::Telemetry& telemetry, const LaneFrame& frame, double ego_s_m, double elapsed_s,
    std::vector<CarTrack>& tracks, const ReferencePredictionParams& params,
    const core::RoadParams& road, double car_length_m);

/// A car's speed cap estimated from the fastest it has been seen going (traffic settles at
/// free_speed_share of its cap), within the caps drawn.
[[nodiscard]] double cap_estimate(double top_speed_mps, const ReferencePredictionParams& params);

/// The traffic's stop-and-go waves: a car ahead of the ego that has come within the reaction
/// distance of the car ahead of it (0.5 m * (its cap in mph - the leader's speed in m/s); the
/// cap estimated from its fastest speed seen) brakes hard towards the leader's speed in m/s
/// read as mph. Such cars are predicted to brake at wave_brake_mps2 down to that speed, then
/// to speed up again at wave_recover_mps2.
void anticipate_waves(std::vector<CarPrediction>& cars, const std::vector<CarTrack>& tracks,
                      double ego_s_m, double car_length_m, const ReferencePredictionParams& params);

/// Predicts one car from its Frenet state now (s unwrapped) and an acceleration estimate;
/// braking is continued for braking_horizon_s; a car slower than `speed_up_to_mps` (cars
/// behind the ego) is taken to speed up towards it.
[[nodiscard]] CarPrediction predict_car(int id, double s_m, double s_dot, double s_ddot,
                                        double speed_mps, double d_m, double d_dot_mps,
                                        const ReferencePredictionParams& params,
                                        const core::RoadParams& road, double speed_up_to_mps = 0.0);

}  // namespace overtake::planner::reference
