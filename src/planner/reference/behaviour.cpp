#include "overtake/planner/reference/behaviour.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace overtake::planner::reference {
namespace {

/// A lane counts as settled in once d is this close to its centre.
constexpr double kSettledM = 0.4;
/// A car held up behind another this close (bumper to bumper) may cut in.
constexpr double kHeldUpGapM = 25.0;
/// Slower cars in the next lane this close ahead (bumper to bumper) limit the passing speed.
constexpr double kPassingRangeM = 60.0;
/// Bumper-to-bumper distance under which a car counts as alongside.
constexpr double kAlongsideM = 1.5;

/// True when the leader in a next lane is at least `factor` of the RSS gap ahead (and
/// min_gap_m), or there is none: the room ahead to enter that lane now.
bool front_ok(const LaneView& v, double factor, const ReferenceBehaviourParams& p) {
  return v.leader < 0 || v.leader_gap_m >= std::max(p.min_gap_m, factor * v.entry_rss_gap_m);
}

}  // namespace

double rss_front_gap(double rear_mps, double front_mps, const ReferenceBehaviourParams& p) {
  return rss_gap_of(rss_rear_reach(rear_mps, p), rss_front_reach(front_mps, p), p);
}

std::vector<LaneView> assess_lanes(const std::vector<CarPrediction>& cars, const EgoSnapshot& ego,
                                   double car_length_m, const ReferenceBehaviourParams& p,
                                   const core::RoadParams& road) {
  std::vector<LaneView> lanes(static_cast<std::size_t>(road.lane_count));
  const int cur = core::lane_of(ego.d_m, road);
  for (int l = 0; l < road.lane_count; ++l) {
    LaneView& v = lanes[static_cast<std::size_t>(l)];
    v.lane = l;
    double best_ahead = std::numeric_limits<double>::infinity();
    double best_behind = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < cars.size(); ++i) {
      const CarPrediction& c = cars[i];
      if (!c.occupies(l)) continue;
      const double centre_gap = (c.s_m - ego.s_m) * ego.m_per_unit_s;
      if (std::abs(centre_gap) < car_length_m + kAlongsideM && l != cur) v.alongside = true;
      if (centre_gap >= 0.0) {
        if (centre_gap < best_ahead && centre_gap < p.lookahead_m) {
          best_ahead = centre_gap;
          v.leader = static_cast<int>(i);
          v.leader_gap_m = centre_gap - car_length_m;
          v.leader_speed_mps = c.speed_mps;
        }
      } else if (-centre_gap < best_behind) {
        best_behind = -centre_gap;
        v.follower = static_cast<int>(i);
        v.follower_gap_m = -centre_gap - car_length_m;
        v.follower_speed_mps = c.speed_mps;
      }
    }
    // The speed the lane allows: cruise until the gap to a slower leader has closed to its
    // RSS distance, then the leader's speed.
    const double cruise = p.cruise_speed_mps;
    v.expected_speed_mps = cruise;
    if (v.leader >= 0 && v.leader_speed_mps < cruise) {
      const double wanted = rss_front_gap(v.leader_speed_mps, v.leader_speed_mps, p);
      const double reach_s = std::max(0.0, v.leader_gap_m - wanted) / (cruise - v.leader_speed_mps);
      const double h = p.evaluation_horizon_s;
      const double free_s = std::min(reach_s, h);
      v.expected_speed_mps = (free_s * cruise + (h - free_s) * v.leader_speed_mps) / h;
    }
    // A car closing fast from behind.
    if (v.follower >= 0) {
      const double own = std::min(ego.speed_mps, v.expected_speed_mps);
      const double closing = v.follower_speed_mps - own;
      const double fast =
          std::clamp((closing - p.rear_threat_speed_mps) / p.rear_threat_span_mps, 0.0, 1.0);
      const double near = std::clamp(1.0 - v.follower_gap_m / p.rear_threat_range_m, 0.0, 1.0);
      v.rear_threat = fast * near;
    }
    if (std::abs(l - cur) == 1) {
      v.entry_rss_gap_m = v.leader < 0 ? 0.0 : rss_front_gap(ego.speed_mps, v.leader_speed_mps, p);
      v.rear_ok =
          v.follower < 0 || rear_room(v.follower_gap_m + car_length_m,
                                      v.follower_speed_mps - ego.speed_mps, car_length_m, p) >= 0.0;
      const bool can = !v.alongside && v.rear_ok && ego.speed_mps >= p.min_change_speed_mps;
      v.enterable = can && front_ok(v, p.change_front_factor, p);
      v.passable = can && front_ok(v, p.transit_front_factor, p);
    }
    v.cost = p.speed_weight * (cruise - v.expected_speed_mps) / cruise +
             p.change_cost * std::abs(l - cur) + p.rear_threat_weight * v.rear_threat;
  }
  return lanes;
}

namespace {

/// The wanted speed: cruise, but not much faster than a held-up car in the next lane ahead,
/// which may cut in.
double wanted_speed(const std::vector<CarPrediction>& cars, const EgoSnapshot& ego, int cur,
                    double car_length_m, const ReferenceBehaviourParams& p) {
  double speed = p.cruise_speed_mps;
  for (const CarPrediction& c : cars) {
    if (std::abs(c.lane - cur) != 1 || c.target_lane != c.lane) continue;
    const double gap = (c.s_m - ego.s_m) * ego.m_per_unit_s - car_length_m;
    if (gap <= 0.0 || gap > kPassingRangeM) continue;
    bool held_up = false;
    for (const CarPrediction& o : cars) {
      if (&o == &c || !o.occupies(c.lane)) continue;
      const double ahead = (o.s_m - c.s_m) * ego.m_per_unit_s - car_length_m;
      if (ahead > -car_length_m && ahead < kHeldUpGapM) held_up = true;
    }
    if (held_up) speed = std::min(speed, c.speed_mps + p.passing_speed_mps);
  }
  return speed;
}

/// True when the ego can move into a next lane now with gap_seek_front_factor of the full RSS
/// gap to the car ahead there and room for the car behind: a change the trajectory layer takes
/// without cost to spare.
bool comfortable_entry(const LaneView& v, const ReferenceBehaviourParams& p) {
  return !v.alongside && v.rear_ok && front_ok(v, p.gap_seek_front_factor, p);
}

/// Gap seeking: when a lane clearly cheaper than the ego's lies across (or is) a next lane
/// that cars pacing the ego block, the speed that lets the ego drop back behind the last of
/// them while itself held up in its lane (infinity: no need). Blocked means no comfortable
/// entry (comfortable_entry): a gap the behaviour would take but that is shorter than the
/// RSS gap is one the trajectory layer declines, and the ego would wait beside it for ever.
double gap_seek_speed(const std::vector<CarPrediction>& cars, const std::vector<LaneView>& lanes,
                      const EgoSnapshot& ego, int cur, double car_length_m,
                      const ReferenceBehaviourParams& p) {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  if (!(p.gap_seek_gain > 0.0)) return kNone;
  const auto lane = [&](int l) -> const LaneView& { return lanes[static_cast<std::size_t>(l)]; };
  int best = -1;
  double best_cost = lane(cur).cost - p.gap_seek_gain;
  for (int l = 0; l < static_cast<int>(lanes.size()); ++l) {
    if (l != cur && lane(l).cost < best_cost) {
      best = l;
      best_cost = lane(l).cost;
    }
  }
  if (best < 0) return kNone;
  const int step = cur + (best > cur ? 1 : -1);
  if (comfortable_entry(lane(step), p)) return kNone;
  if (lane(cur).follower >= 0 && lane(cur).follower_gap_m < p.gap_seek_rear_gap_m) return kNone;
  // Only when held up in the ego's lane too (else it passes them): a leader within passing
  // range. (Not one at the ego's speed: dropping back, the ego is slower than it.)
  const LaneView& own = lane(cur);
  if (own.leader < 0 || own.leader_gap_m > kPassingRangeM) return kNone;
  double last_gap = kNone;
  double last_speed = kNone;
  for (const CarPrediction& c : cars) {
    // Cars faster than the ego by more than the pace clear the way by themselves.
    if (!c.occupies(step) ||
        c.speed_mps > std::max(ego.speed_mps, own.leader_speed_mps) + p.gap_seek_pace_mps)
      continue;
    const double centre_gap = (c.s_m - ego.s_m) * ego.m_per_unit_s;
    if (centre_gap < -(car_length_m + p.gap_seek_behind_m) ||
        centre_gap > car_length_m + p.gap_seek_ahead_m)
      continue;
    if (centre_gap < last_gap) {
      last_gap = centre_gap;
      last_speed = c.speed_mps;
    }
  }
  if (last_gap == kNone) return kNone;
  return std::max(p.gap_seek_min_speed_mps, last_speed - p.gap_seek_drop_mps);
}

}  // namespace

BehaviourDecision decide(const std::vector<CarPrediction>& cars, const EgoSnapshot& ego,
                         BehaviourState& state, double elapsed_s, double car_length_m,
                         const ReferenceBehaviourParams& p, const core::RoadParams& road) {
  BehaviourDecision out;
  out.lanes = assess_lanes(cars, ego, car_length_m, p, road);
  const int cur = core::lane_of(ego.d_m, road);
  if (state.target_lane < 0 || state.target_lane >= road.lane_count) {
    state.target_lane = cur;
    state.goal_lane = cur;
  }
  const bool settled =
      state.target_lane == cur && std::abs(ego.d_m - core::lane_center_d(cur, road)) < kSettledM;
  state.since_settled_s = settled ? state.since_settled_s + elapsed_s : 0.0;

  const auto lane = [&](int l) -> const LaneView& {
    return out.lanes[static_cast<std::size_t>(l)];
  };
  if (!settled) {
    // Changing lanes (or centring): carry on unless a car came alongside in the target lane
    // before we crossed. (The trajectory layer returns when the change is no longer safe.)
    const int target = state.target_lane;
    if (cur != target && lane(target).alongside) {
      state.target_lane = cur;
      state.goal_lane = cur;
    }
  } else {
    // Settled: the cheapest lane we can head for, if clearly cheaper than staying.
    int best = cur;
    double best_cost = lane(cur).cost;
    for (int l = 0; l < road.lane_count; ++l) {
      if (l == cur) continue;
      const int step = cur + (l > cur ? 1 : -1);
      if (step == l ? !lane(step).enterable : !lane(step).passable) continue;
      if (lane(l).cost < best_cost) {
        best = l;
        best_cost = lane(l).cost;
      }
    }
    const bool continuing = state.goal_lane != cur && best == state.goal_lane;
    if (best != cur && best_cost + p.hysteresis < lane(cur).cost &&
        (continuing || state.since_settled_s >= p.change_dwell_s)) {
      state.target_lane = cur + (best > cur ? 1 : -1);
      state.goal_lane = best;
      state.since_settled_s = 0.0;
    } else {
      state.target_lane = cur;
      state.goal_lane = cur;
    }
  }
  out.target_lane = state.target_lane;
  out.goal_lane = state.goal_lane;
  out.speed_mps = wanted_speed(cars, ego, core::lane_of(ego.d_m, road), car_length_m, p);
  // Boxed in: drop back behind the cars that pace the ego in the next lane.
  if (settled && state.target_lane == cur) {
    out.speed_mps =
        std::min(out.speed_mps, gap_seek_speed(cars, out.lanes, ego, cur, car_length_m, p));
  }
  return out;
}

}  // namespace overtake::planner::reference
