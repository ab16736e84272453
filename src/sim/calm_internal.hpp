#pragma once
// What the calm traffic's files share: calm_traffic.cpp (the model: steps, scripts, bodies),
// calm_driving.cpp (IDM with the ACC model's blend, MOBIL lane changes, motion) and
// calm_placement.cpp (where cars are put). CalmImpl holds the helpers, with access to
// CalmTraffic's state. Not part of the simulator's interface.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>

#include "overtake/core/road.hpp"
#include "overtake/sim/calm_traffic.hpp"

namespace overtake::sim {

/// The implementation, as static helpers with access to CalmTraffic's state.
struct CalmImpl {
  using Vehicle = CalmTraffic::Vehicle;
  using Decision = CalmTraffic::Decision;

  /// Lateral motion (lane changes, wander) runs at its full pace at this speed and above, and
  /// slower below it in proportion, stopping when the car stands: a car does not move
  /// sideways at a crawl. A 4 m change over 3 s peaks at 2.5 m/s sideways, so a car is never
  /// more than ~20 degrees off its lane.
  static constexpr double kFullLateralPaceMps = 7.0;
  /// The ego counts in a lane when its d is within this of the lane's centre.
  static constexpr double kEgoLaneRadiusM = 3.0;
  /// A car's body counts in a lane when it comes within this of it (sideways), beyond half
  /// its width: room for its heading during a lane change.
  static constexpr double kBodyMarginM = 0.5;
  static constexpr double kInf = std::numeric_limits<double>::infinity();

  [[nodiscard]] static constexpr unsigned lane_bit(int lane) {
    return 1U << static_cast<unsigned>(lane);
  }

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

  /// Lanes the ego counts in: those whose centre its d is within kEgoLaneRadiusM of.
  [[nodiscard]] static unsigned ego_lanes(const CalmTraffic& t, double ego_d) {
    unsigned mask = 0;
    for (int k = 0; k < t.road_.lane_count; ++k) {
      if (std::abs(ego_d - core::lane_center_d(k, t.road_)) < kEgoLaneRadiusM) {
        mask |= lane_bit(k);
      }
    }
    return mask;
  }

  /// The lane a car's d lies in.
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
  static void build_vehicles(CalmTraffic& t, const EgoView& ego, double ego_s, double dt);

  /// Nearest vehicle ahead (smallest positive gap) among those occupying any of `lanes`,
  /// other than `self` and `skip`.
  [[nodiscard]] static Nearest leader(const CalmTraffic& t, int self, unsigned lanes,
                                      int skip = -1);

  // ----- calm profile ----------------------------------------------------------------------

  /// IDM acceleration (Treiber, Hennecke, Helbing 2000) of a vehicle at speed v wanting v0,
  /// `gap_m` centre to centre behind a leader at `leader_speed` (gap infinite: free road).
  /// Not clamped: MOBIL compares these, and a clamp would make every emergency look alike.
  [[nodiscard]] static double idm(const CalmTraffic& t, double v, double v0, double gap_m,
                                  double leader_speed);

  /// The constant-acceleration heuristic of the ACC model (Kesting, Treiber, Helbing 2010):
  /// the deceleration that just avoids a collision if the leader keeps its acceleration.
  [[nodiscard]] static double cah(const CalmTraffic& t, double v, double leader_speed,
                                  double leader_accel, double bumper_gap_m);

  /// The acceleration a calm car applies: IDM, except where IDM brakes harder than the
  /// situation needs (a gap far below the desired one, but not closing), where the ACC
  /// model's blend with the CAH takes over; then the physical braking limit. Without this,
  /// cars spawned ~6 m apart all brake at the limit at once and the faster ones run into
  /// the slower ones ahead.
  [[nodiscard]] static double applied_accel(const CalmTraffic& t, int self, int lead, double gap_m,
                                            double a_idm);

  /// Desired speed of a vehicle for IDM: a car's cruise speed; for the ego (whose wishes are
  /// unknown) its own speed, so that only the interaction term counts.
  [[nodiscard]] static double desired_speed(const CalmTraffic& t, const Vehicle& v);

  /// IDM acceleration of vehicle `k` behind `lead` (-1: free road) at `gap_m`.
  [[nodiscard]] static double idm_of(const CalmTraffic& t, int k, int lead, double gap_m);

  /// MOBIL (Kesting, Treiber, Helbing 2007) for car i into `lane`, on IDM accelerations:
  /// the incentive when the change is safe and its incentive beats `best`, else nullopt.
  /// Safe: no vehicle in the target lane within car length + s0; the new follower (the
  /// ego included) need not brake harder than safe_decel; (ours) nor need the car itself.
  [[nodiscard]] static std::optional<double> mobil(const CalmTraffic& t, int i, int lane,
                                                   double best);

  /// Whether car j's change into a lane conflicts with car i's change into the same lane.
  [[nodiscard]] static bool changes_conflict(const CalmTraffic& t, int i, int j);

  /// Each car's decision for this step from the previous frame (vehicles_ filled): its
  /// acceleration behind the most demanding leader of the lanes it occupies, and a lane change
  /// when MOBIL finds one worth it and no earlier car moves into the same lane too close.
  static void decide_calm(CalmTraffic& t, double dt);

  // ----- motion ----------------------------------------------------------------------------

  /// Moves car i one step by its decision: speed, lane change (minimum-jerk lateral profile)
  /// or wander about its lane centre, then along the line.
  static void move(CalmTraffic& t, std::size_t i, const Decision& dec, double dt);

  /// Car i's body from its state (bodies_ and lane_scales_ sized to the cars).
  static void publish_car(CalmTraffic& t, std::size_t i);

  /// line.metres_per_s(line.sample(s), d) for car i, from publish()'s cache when it asked
  /// at the same s and d.
  [[nodiscard]] static double lane_metres_per_s(const CalmTraffic& t, std::size_t i, double s,
                                                double d);

  // ----- placement -------------------------------------------------------------------------

  /// The behind and ahead regions around the ego's previous waypoint, as offsets from the ego.
  static void regions(const CalmTraffic& t, double ego_s, Region& behind, Region& ahead_region);

  /// How much the gap between two vehicles in one lane can shrink at most when the one
  /// behind (speed v_f) brakes at b while the one ahead (v_l) keeps braking at decel_l >= 0
  /// until it stands: the spawn rule's dv^2 / (2 b) when the leader holds its speed.
  [[nodiscard]] static double worst_closing_m(double v_f, double v_l, double decel_l, double b);

  /// (ours) In one lane, the vehicle behind must be able to brake in time for the one ahead
  /// (which keeps its present deceleration, if it is braking) at spawn_brake_mps2.
  [[nodiscard]] static bool room_to_brake(const CalmTraffic& t, double s, double v, double other_s,
                                          double other_v, double other_accel);

  /// The ego as placement sees it.
  struct EgoSpot {
    double s_m = 0.0;  // wrapped
    core::Vec2 position;
    unsigned lanes = 0;
    double speed_mps = 0.0;
    double accel_mps2 = 0.0;
  };

  /// The ego now; its acceleration is the last step's when the step has built vehicles_.
  [[nodiscard]] static EgoSpot ego_spot(const CalmTraffic& t, const EgoView& ego);

  /// Whether car i may be put at (s, d) in `lane` at `speed`, given the cars [0, limit)
  /// other than i (positions in positions_) and the ego.
  [[nodiscard]] static bool spot_ok(const CalmTraffic& t, int i, int limit, double s, double d,
                                    int lane, double speed, const EgoSpot& ego);

  /// Puts car i at a spot and resets its state.
  static void commit(CalmTraffic& t, CalmCar& c, double s, int lane, double cruise, double phase,
                     double omega);

  /// A car's wander, drawn from its own stream at each placement.
  struct Wander {
    double omega_rps = 0.0;
    double phase_rad = 0.0;
  };

  [[nodiscard]] static Wander draw_wander(const CalmTraffic& t, CalmCar& c);

  /// Positions of the cars [0, limit), for the spacing checks.
  static void cache_positions(CalmTraffic& t, int limit);

  /// Where a car may be placed: by the behind probability, or only behind or ahead.
  enum class Where { either, behind, ahead };

  /// Tries to place car i by the spawn rule (up to max_spawn_attempts draws) against the
  /// cars [0, limit). `initial`: not behind the ego in the ego's lane.
  static bool try_place(CalmTraffic& t, int i, int limit, const EgoView& ego_view, bool initial,
                        Where where);

  /// Last resort of the initial placement: farther ahead, ego + 150 m + 10 m * k.
  static void place_fallback(CalmTraffic& t, int i, const EgoView& ego_view);
};

}  // namespace overtake::sim
