// The trajectory layer's plan: the candidates (trajectory_candidates.cpp) combined and ranked
// by cost, searched cheapest first through the checks (trajectory_checks.cpp); when none
// passes, the braking fallback or the least bad.

#include "overtake/planner/reference/trajectory.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "trajectory_internal.hpp"

namespace overtake::planner::reference {
namespace trajectory_detail {
namespace {

/// Longest a collision-failed candidate list is searched for a least-bad one.
constexpr int kLeastBadChecks = 12;

/// The costed candidates of one plan.
struct Candidates {
  std::vector<LatCandidate> lats;
  std::vector<LonCandidate> lons;
  SoftLaneCosts soft;
  int start_lane = 0;  ///< the lane the ego starts in
};

/// Gives a plan's sample buffers back to the spare ones when the plan is done.
struct SpareReturn {
  SpareReturn(SpareBuffers& to, std::vector<CarSamples>& from_cars, Candidates& from)
      : spare(to), cars(from_cars), c(from) {}
  SpareReturn(const SpareReturn&) = delete;
  SpareReturn& operator=(const SpareReturn&) = delete;
  SpareReturn(SpareReturn&&) = delete;
  SpareReturn& operator=(SpareReturn&&) = delete;
  ~SpareReturn() {
    const auto give = [&](std::vector<double>& b) {
      if (b.capacity() > 0) spare.push_back(std::move(b));
    };
    for (CarSamples& car : cars) give(car.buffer);
    for (LatCandidate& lat : c.lats) {
      give(lat.samples.x);
      give(lat.samples.v);
    }
    for (LonCandidate& lon : c.lons) {
      give(lon.samples.x);
      give(lon.samples.v);
    }
  }
  SpareBuffers& spare;
  std::vector<CarSamples>& cars;
  Candidates& c;
};

/// One combination of a lateral and a longitudinal candidate, with its cost.
struct Combo {
  double cost;
  std::uint32_t lat;
  std::uint32_t lon;
};

/// Every combination, cheapest first. The cost is the lateral candidate's, plus the
/// longitudinal's, plus the soft cost of the end lane, plus (when changing lanes) the start
/// lane's early soft cost, added in that order.
std::vector<Combo> rank_combinations(const Candidates& c) {
  std::vector<Combo> combos;
  combos.reserve(c.lats.size() * c.lons.size());
  for (std::size_t i = 0; i < c.lats.size(); ++i) {
    const int end = c.lats[i].end_lane;
    for (std::size_t j = 0; j < c.lons.size(); ++j) {
      double cost = c.lats[i].cost + c.lons[j].cost + c.soft.at(j, end).full;
      if (end != c.start_lane) cost += c.soft.at(j, c.start_lane).early;
      combos.push_back({cost, static_cast<std::uint32_t>(i), static_cast<std::uint32_t>(j)});
    }
  }
  std::sort(combos.begin(), combos.end(),
            [](const Combo& a, const Combo& b) { return a.cost < b.cost; });
  return combos;
}

/// The terms of a combination's cost (their total() is its cost).
TrajectoryCost cost_terms(const Combo& combo, const Candidates& c) {
  const LatCandidate& lat = c.lats[combo.lat];
  const LonCandidate& lon = c.lons[combo.lon];
  TrajectoryCost t = lat.terms;
  t.progress = lon.terms.progress;
  t.longitudinal_jerk = lon.terms.longitudinal_jerk;
  t.lane = c.soft.at(combo.lon, lat.end_lane).full;
  t.early_lane = lat.end_lane != c.start_lane ? c.soft.at(combo.lon, c.start_lane).early : 0.0;
  return t;
}

/// The trajectory of a combination.
Trajectory trajectory_of(const Combo& combo, const Candidates& c) {
  Trajectory t;
  t.lateral = c.lats[combo.lat].poly;
  t.longitudinal = c.lons[combo.lon].motion;
  t.end_lane = c.lats[combo.lat].end_lane;
  return t;
}

/// The checks of one plan's candidates, with what they read.
struct Checker {
  const Grid& g;
  const LaneFrame& line;
  const std::vector<CarSamples>& cars;  ///< the predictions over the grid
  double m_per_unit_s;
  const ReferenceParams& params;
  const core::CarFootprint& car;
  const std::vector<FrenetState>& history;  ///< where the ego was before the start
  int start_lane;
  bool off_centre;  ///< the ego starts off its lane's centre

  /// Longitudinal samples `lon` with the lateral candidate `lat` against the cars.
  [[nodiscard]] CollisionReport collision(const Track1d& lon, const LatCandidate& lat) const {
    const bool changing = lat.end_lane != start_lane;
    return collide(lon, lat.samples, changing, changing || off_centre, g, cars, m_per_unit_s,
                   params, car);
  }
  /// The Cartesian check from the path driven on.
  [[nodiscard]] KinematicReport kinematic(const Track1d& lon, const Track1d& lat,
                                          bool stop_at_first) const {
    return kinematics(lon, lat, g, line, params.trajectory, stop_at_first, history);
  }
  /// How late a predicted collision comes, for choosing the least bad: one with a car ahead
  /// (predicted to brake as hard as it can) counts as later than it is, one with a car from
  /// behind (that does not see the ego) as it is.
  [[nodiscard]] double lateness(const CollisionReport& r) const {
    return r.first_collision_s + (r.from_behind ? 0.0 : params.trajectory.ahead_collision_slack_s);
  }
};

/// A combination that failed the collision check (or would linger on a lane line): when its
/// first incident would come (see Checker::lateness), and its index in the ranking.
struct Failed {
  double incident_s;
  std::size_t combo;
};

/// What the checked search found.
struct CheckedSearch {
  std::optional<std::size_t> passed;  ///< the first combination that passed both checks
  std::vector<Failed> failed;         ///< those with an incident ahead, in ranking order
  int collision_checks = 0;
  int kinematic_checks = 0;
  int collision_failures = 0;
  int blocking_car = -1;  ///< the car the cheapest collision-failed combination would hit
  double blocking_time_s = 0.0;
};

/// The combinations, cheapest first, checked for collision, then (at most
/// max_kinematic_checks of them) in Cartesian space; the first that passes both wins.
CheckedSearch checked_search(const std::vector<Combo>& combos, const Candidates& c,
                             const Checker& check) {
  CheckedSearch out;
  for (std::size_t n = 0; n < combos.size(); ++n) {
    const LatCandidate& lat = c.lats[combos[n].lat];
    const LonCandidate& lon = c.lons[combos[n].lon];
    ++out.collision_checks;
    const CollisionReport col = check.collision(lon.samples, lat);
    if (!col.ok || lat.overstay_s < kInf) {
      // An incident ahead: a collision, or lingering on a lane line (the original counts it
      // as one, so it is weighed as one, at the time it would count).
      if (!col.ok && out.collision_failures++ == 0) {
        out.blocking_car = col.car_id;
        out.blocking_time_s = col.first_collision_s;
      }
      out.failed.push_back({std::min(col.ok ? kInf : check.lateness(col), lat.overstay_s), n});
      continue;
    }
    if (out.kinematic_checks >= check.params.trajectory.max_kinematic_checks) continue;
    ++out.kinematic_checks;
    if (check.kinematic(lon.samples, lat.samples, true).ok) {
      out.passed = n;
      return out;
    }
  }
  return out;
}

/// The braking fallback and when its first incident comes (infinity: none).
struct Fallback {
  Trajectory trajectory;
  double incident_s = kInf;
};

/// The fallback: with each lateral motion in turn, braking as fast as the lateral motion's own
/// jerk leaves room for; it must stay within the limits on the road, then collide as late as
/// it can, then be as gentle as it can. With no lateral motion, the braking fallback back to
/// the start lane's centre.
Fallback choose_fallback(const std::vector<LatCandidate>& lats, const TrajectoryRequest& req,
                         const std::vector<CarPrediction>& cars, const Checker& check,
                         const core::RoadParams& road) {
  const auto& tp = check.params.trajectory;
  const Grid& g = check.g;
  const FrenetState& x0 = req.start;
  const double m_per_unit_s = check.m_per_unit_s;
  Fallback out;
  out.trajectory.longitudinal = fallback_braking(x0, tp, m_per_unit_s);
  if (lats.empty()) {
    out.trajectory.end_lane = check.start_lane;
    const double back_to = core::lane_center_d(check.start_lane, road);
    out.trajectory.lateral =
        quintic(x0.d_m, x0.d_dot_mps, x0.d_ddot_mps2, back_to, 0.0, 0.0,
                std::max(tp.min_lateral_time_s,
                         std::cbrt(60.0 * std::abs(back_to - x0.d_m) / tp.lateral_jerk_mps3)));
    const CollisionReport fb = check_collisions(out.trajectory, cars, req.start_delay_s,
                                                m_per_unit_s, check.params, road, check.car);
    out.incident_s = fb.ok ? kInf : check.lateness(fb);
    return out;
  }
  const LatCandidate* pick = nullptr;
  Longitudinal pick_brake = out.trajectory.longitudinal;
  KinematicReport pick_kin;
  double pick_collision = -kInf;
  for (const LatCandidate& c : lats) {
    double lat_jerk = 0.0;
    const PolynomialSampler lat_at{c.poly};
    for (int k = 0; k <= g.n; ++k) lat_jerk = std::max(lat_jerk, std::abs(lat_at(g.t(k)).j));
    const double room =
        tp.fallback_total_jerk_mps3 * tp.fallback_total_jerk_mps3 - lat_jerk * lat_jerk;
    const double brake_jerk =
        std::clamp(std::sqrt(std::max(0.0, room)), kGentleStopJerkMps3, tp.fallback_jerk_mps3);
    Longitudinal brake;
    brake.braking = true;
    brake.brake = BrakingProfile(x0.s_m, x0.s_dot, x0.s_ddot, tp.fallback_brake_mps2 / m_per_unit_s,
                                 brake_jerk / m_per_unit_s);
    const Track1d brake_samples = sample(g, [&](double t) { return brake.at(t); });
    const CollisionReport col = check.collision(brake_samples, c);
    const KinematicReport kin = check.kinematic(brake_samples, c.samples, false);
    const double incident = std::min(col.ok ? kInf : check.lateness(col), c.overstay_s);
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
  out.trajectory.lateral = pick->poly;
  out.trajectory.longitudinal = pick_brake;
  out.trajectory.end_lane = pick->end_lane;
  out.incident_s = pick_collision;
  return out;
}

/// What the least-bad search found.
struct LeastBad {
  std::optional<std::size_t> passed;  ///< the combination chosen
  int kinematic_checks = 0;
};

/// Of the combinations that failed for an incident ahead, latest incident first, the first
/// whose incident comes later than the fallback's and that passes the Cartesian check (at
/// most kLeastBadChecks of them are checked).
LeastBad least_bad_search(std::vector<Failed> failed, double fallback_incident_s,
                          const std::vector<Combo>& combos, const Candidates& c,
                          const Checker& check) {
  std::stable_sort(failed.begin(), failed.end(),
                   [](const Failed& a, const Failed& b) { return a.incident_s > b.incident_s; });
  LeastBad out;
  int tried = 0;
  for (const Failed& f : failed) {
    if (f.incident_s <= fallback_incident_s || tried >= kLeastBadChecks) break;
    ++tried;
    const Combo& combo = combos[f.combo];
    ++out.kinematic_checks;
    if (check.kinematic(c.lons[combo.lon].samples, c.lats[combo.lat].samples, true).ok) {
      out.passed = f.combo;
      return out;
    }
  }
  return out;
}

/// Why a plan ending in `end_lane` declined the change to `target_lane` (see
/// TrajectoryPlan::change_declined): the combinations into that lane, cheapest first, are
/// checked until one passes both checks (at most max_kinematic_checks Cartesian checks; past
/// them it counts as for safety). Called only when a change was declined, so a cycle that
/// takes it costs nothing more.
core::ChangeDeclined why_declined(int end_lane, int target_lane, const std::vector<Combo>& combos,
                                  const Candidates& c, const Checker& check) {
  if (target_lane == check.start_lane || end_lane == target_lane) return core::ChangeDeclined::no;
  int kinematic = 0;
  for (const Combo& combo : combos) {
    const LatCandidate& lat = c.lats[combo.lat];
    if (lat.end_lane != target_lane || lat.overstay_s < kInf) continue;
    const LonCandidate& lon = c.lons[combo.lon];
    if (!check.collision(lon.samples, lat).ok) continue;
    if (kinematic++ >= check.params.trajectory.max_kinematic_checks) break;
    if (check.kinematic(lon.samples, lat.samples, true).ok) return core::ChangeDeclined::for_cost;
  }
  return core::ChangeDeclined::for_safety;
}

}  // namespace
}  // namespace trajectory_detail

FrenetState Trajectory::at(double t) const {
  const Motion1d s = longitudinal.at(t);
  const Motion1d d = lateral.at(t);
  return {s.x, s.v, s.a, d.x, d.v, d.a};
}

TrajectoryPlan plan_trajectory(const LaneFrame& line, const TrajectoryRequest& req,
                               const ReferenceParams& params, const core::RoadParams& road,
                               const core::CarFootprint& car, TrajectoryScratch* scratch) {
  using namespace trajectory_detail;
  const auto& tp = params.trajectory;
  const Grid g = grid_of(tp);
  const FrenetState& x0 = req.start;
  static const std::vector<CarPrediction> kNoCars;
  const std::vector<CarPrediction>& cars = req.cars ? *req.cars : kNoCars;

  const std::vector<int> lanes = lanes_in_play(x0, req.target_lane, tp.line_band_m, road);
  const AlongRoadScale scale = along_road_scale(line, x0, req.wanted_speed_mps, lanes, tp, road);
  TrajectoryScratch own_scratch;
  SpareBuffers& spare = scratch ? scratch->spare : own_scratch.spare;
  std::vector<CarSamples> car_samples = sample_cars(cars, req.start_delay_s, x0.s_m, g, &spare);
  const std::vector<LaneCars> lane_cars = cars_per_lane(lanes, car_samples, cars, x0.s_m, road);

  Candidates c;
  c.start_lane = core::lane_of(x0.d_m, road);
  // The samples' buffers go back to `spare` on every way out (declared after what holds
  // them, this is destroyed before them).
  const SpareReturn give_back{spare, car_samples, c};
  c.lats = lateral_candidates(lanes, req, g, line, tp, road, spare);
  c.lons =
      longitudinal_candidates(req, lane_leaders(lanes, lane_cars), scale, g, params, car, spare);
  c.soft = soft_lane_costs(c.lons, lanes, lane_cars, g, scale.m_per_unit_s, params, car);
  const std::vector<Combo> combos = rank_combinations(c);

  const bool off_centre = std::abs(x0.d_m - core::lane_center_d(c.start_lane, road)) > kSidewaysM;
  const Checker check{g,   line,        car_samples,  scale.m_per_unit_s, params,
                      car, req.history, c.start_lane, off_centre};

  TrajectoryPlan plan;
  plan.candidates = static_cast<int>(combos.size());
  const auto choose = [&](std::size_t n, PlanStatus status) {
    plan.trajectory = trajectory_of(combos[n], c);
    plan.status = status;
    plan.cost = combos[n].cost;
    plan.cost_terms = cost_terms(combos[n], c);
  };

  CheckedSearch checked = checked_search(combos, c, check);
  plan.collision_checks = checked.collision_checks;
  plan.kinematic_checks = checked.kinematic_checks;
  plan.collision_failures = checked.collision_failures;
  plan.blocking_car = checked.blocking_car;
  plan.blocking_time_s = checked.blocking_time_s;
  const auto declined = [&] {
    plan.change_declined =
        why_declined(plan.trajectory.end_lane, req.target_lane, combos, c, check);
  };
  if (checked.passed) {
    choose(*checked.passed, PlanStatus::feasible);
    declined();
    return plan;
  }

  // Nothing passed: the braking fallback, or the candidate whose first incident comes
  // latest, whichever comes later.
  const Fallback fallback = choose_fallback(c.lats, req, cars, check, road);
  const LeastBad least_bad =
      least_bad_search(std::move(checked.failed), fallback.incident_s, combos, c, check);
  plan.kinematic_checks += least_bad.kinematic_checks;
  if (least_bad.passed) {
    choose(*least_bad.passed, PlanStatus::least_bad);
    declined();
    return plan;
  }
  plan.trajectory = fallback.trajectory;
  plan.status = PlanStatus::fallback;
  declined();
  return plan;
}

}  // namespace overtake::planner::reference
