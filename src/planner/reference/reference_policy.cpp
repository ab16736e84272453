#include "overtake/planner/reference/reference_policy.hpp"

#include "overtake/core/wire_number.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>

namespace overtake::planner::reference {
namespace {

/// The first queued point must be where the last plan put it, within this (wire rounding
/// is 0.1 mm on a track within +-1000 m).
constexpr double kSyncToleranceM = 0.01;

/// The speed the wire's rounding may add to a step: positions go out with 7 significant
/// digits, so on a map reaching 1000 m or more from the origin a point moves by up to half a
/// millimetre (and the next by as much the other way).
double wire_speed_error_mps(const core::ReferenceLine& line, double step_s) {
  double reach = 0.0;
  for (const double s : line.waypoint_s()) {
    const core::Vec2 p = line.frame_without_heading(s).position;
    reach = std::max({reach, std::abs(p.x), std::abs(p.y)});
  }
  reach += 20.0;  // the road's width and more
  const double digits = std::floor(std::log10(std::max(reach, 1.0))) + 1.0;
  const double resolution = std::pow(10.0, digits - 7.0);
  return 2.0 * resolution / step_s;
}

/// The way a state moves on the map (unit), or its lane's way where it stands.
core::Vec2 heading_of(const RoadPoint& at, const FrenetState& x) {
  const core::Vec2 v = (at.along_scale * x.s_dot) * at.tangent + x.d_dot_mps * at.normal;
  const double speed = core::norm(v);
  return speed > 1e-9 ? (1.0 / speed) * v : at.tangent;
}

/// The point to send after `sent` where the plan is at `x` (at `at` on the map): the plan's
/// point, or `sent` again while the car is less than crawl_max_lag_m behind the plan and the
/// step to the plan's point, as the simulator reads both (rounded like the wire), would turn
/// the car more than crawl_heading_tolerance_rad from the plan's way (a car facing its next
/// point at a crawl of a few wire quanta a step faces noise, tens of degrees off its lane).
core::Vec2 steady_point(core::Vec2 sent, const RoadPoint& at, const FrenetState& x,
                        const ReferenceTrajectoryParams& tp) {
  const core::Vec2 next = at.position;
  if (core::distance_sq(sent, next) >= tp.crawl_max_lag_m * tp.crawl_max_lag_m) return next;
  const core::Vec2 read_step = core::Vec2{core::wire_round(next.x), core::wire_round(next.y)} -
                               core::Vec2{core::wire_round(sent.x), core::wire_round(sent.y)};
  if (read_step == core::Vec2{}) return sent;
  const core::Vec2 way = heading_of(at, x);
  const double turn = std::abs(std::atan2(core::cross(way, read_step), core::dot(way, read_step)));
  return turn <= tp.crawl_heading_tolerance_rad ? next : sent;
}

/// A check step within this many world steps of a whole number of them is one.
constexpr double kWholeStepTolerance = 1e-6;

/// `x` carried `dt_s` forward (back when negative) at its speed and acceleration.
FrenetState carried(const FrenetState& x, double dt_s) {
  FrenetState y = x;
  y.s_m += dt_s * (x.s_dot + 0.5 * dt_s * x.s_ddot);
  y.s_dot += dt_s * x.s_ddot;
  y.d_m += dt_s * (x.d_dot_mps + 0.5 * dt_s * x.d_ddot_mps2);
  y.d_dot_mps += dt_s * x.d_ddot_mps2;
  return y;
}

}  // namespace

core::PlanStatus to_core(PlanStatus s) {
  switch (s) {
    case PlanStatus::feasible:
      return core::PlanStatus::normal;
    case PlanStatus::least_bad:
      return core::PlanStatus::least_bad;
    case PlanStatus::fallback:
      return core::PlanStatus::fallback;
  }
  return core::PlanStatus::fallback;
}

std::string status_reason(const TrajectoryPlan& plan) {
  if (plan.status == PlanStatus::feasible) return {};
  std::string why = "none of " + std::to_string(plan.candidates) + " candidates passed its checks";
  if (plan.blocking_car >= 0) {
    char at[32];
    std::snprintf(at, sizeof at, "%.1f", plan.blocking_time_s);
    why += " (the cheapest meets car " + std::to_string(plan.blocking_car) + " at " + at + " s)";
  }
  return why + (plan.status == PlanStatus::least_bad ? ": the one that collides latest"
                                                     : ": braking in the lane");
}

std::shared_ptr<const ReferenceGeometry> make_reference_geometry(const core::ReferenceLine& line,
                                                                 const PlannerParams& params) {
  auto smooth =
      std::make_shared<const core::ReferenceLine>(line.map(), params.reference.line_smoothing_m3);
  LaneFrame frame = LaneFrame::chord_aligned(*smooth, params.road);
  return std::make_shared<const ReferenceGeometry>(ReferenceGeometry{
      &line, params.reference.line_smoothing_m3, params.road, std::move(smooth), std::move(frame)});
}

namespace {

std::shared_ptr<const ReferenceGeometry> checked_geometry(
    const core::ReferenceLine& line, const PlannerParams& params,
    std::shared_ptr<const ReferenceGeometry> geometry) {
  if (!geometry || geometry->base != &line ||
      geometry->line_smoothing_m3 != params.reference.line_smoothing_m3 ||
      geometry->road != params.road) {
    throw std::invalid_argument(
        "ReferencePolicy: the geometry given was not built for this line, smoothing and road");
  }
  return geometry;
}

}  // namespace

ReferencePolicy::ReferencePolicy(const core::ReferenceLine& line, const PlannerParams& params)
    : ReferencePolicy(line, params, make_reference_geometry(line, params)) {}

ReferencePolicy::ReferencePolicy(const core::ReferenceLine& line, const PlannerParams& params,
                                 std::shared_ptr<const ReferenceGeometry> geometry)
    : line_(line),
      geometry_(checked_geometry(line, params, std::move(geometry))),
      frame_(geometry_->frame),
      road_(params.road),
      step_s_(params.step_s),
      car_(params.car),
      p_(params.reference) {
  p_.trajectory.max_speed_mps -= wire_speed_error_mps(line, step_s_);
}

FrenetState ReferencePolicy::observed_state(const core::Telemetry& t) const {
  const core::Vec2 v =
      t.ego.speed_mps * core::Vec2{std::cos(t.ego.yaw_rad), std::sin(t.ego.yaw_rad)};
  return frenet_from_cartesian(frame_, t.ego.position, v, t.ego.s_m);
}

core::Vec2 ReferencePolicy::sent_as_read(std::size_t i) const {
  return sent_rounded_ ? sent_[i]
                       : core::round_like_wire(std::vector<core::Vec2>{sent_[i]}).front();
}

// Where the car is on the last plan: the simulator consumed the points not queued. Sets
// synced_ (and `car`, the driven states and the band time) when the queue and the car are
// where the plan put them; returns the points consumed.
std::size_t ReferencePolicy::sync_to(const core::Telemetry& t, FrenetState& car) {
  const auto& tp = p_.trajectory;
  const double dt = step_s_;
  const std::size_t remaining = t.previous_path.size();
  synced_ = false;
  std::size_t consumed = 0;
  if (have_plan_ && remaining >= 2 && remaining <= sent_.size()) {
    consumed = sent_.size() - remaining;
    const bool queue_matches =
        core::distance(t.previous_path.front(), sent_as_read(consumed)) < kSyncToleranceM;
    const bool car_matches =
        consumed == 0 ||
        core::distance(t.ego.position, sent_as_read(consumed - 1)) < kSyncToleranceM;
    if (queue_matches && car_matches) {
      car = consumed == 0 ? origin_ : states_[consumed - 1];
      synced_ = true;
      driven_.insert(driven_.end(), states_.begin(),
                     states_.begin() + static_cast<std::ptrdiff_t>(consumed));
      for (std::size_t i = 0; i < consumed; ++i) {
        band_time_s_ =
            in_line_band(frame_.original_d(states_[i].s_m, states_[i].d_m), tp.line_band_m, road_)
                ? band_time_s_ + dt
                : 0.0;
      }
    }
  }
  return consumed;
}

// The path up to the start (driven, then kept), every check step back from the start, for
// the checks across the joint.
std::vector<FrenetState> ReferencePolicy::history_before(const std::vector<FrenetState>& states,
                                                         const FrenetState& start) const {
  const auto& tp = p_.trajectory;
  const double dt = step_s_;
  std::vector<FrenetState> history;
  std::vector<FrenetState> past(driven_);
  past.insert(past.end(), states.begin(), states.end());
  if (past.empty() || !synced_) past.clear();
  for (std::size_t j = 1; j <= 3 && !past.empty(); ++j) {
    // The newest state is the start: the last kept point, or the car (the last driven).
    const std::size_t newest = past.size() - 1;
    const double back_steps = static_cast<double>(j) * tp.check_step_s / dt;
    const long nearest = std::lround(back_steps);
    if (nearest < 1 || static_cast<std::size_t>(nearest) > newest) break;
    FrenetState x = past[newest - static_cast<std::size_t>(nearest)];
    if (std::abs(back_steps - static_cast<double>(nearest)) > kWholeStepTolerance) {
      // A check step that is no whole number of world steps: carried from the nearest state.
      x = carried(x, (static_cast<double>(nearest) - back_steps) * dt);
    }
    x.s_m = start.s_m + line_.s_ahead(start.s_m, x.s_m);
    history.push_back(x);
  }
  return history;
}

core::PlanResult ReferencePolicy::plan(const core::Telemetry& t) {
  return plan(t, scratch_);
}

core::PlanResult ReferencePolicy::plan(const core::Telemetry& t, TrajectoryScratch& scratch) {
  const auto& tp = p_.trajectory;
  const double dt = step_s_;

  FrenetState car;
  const std::size_t consumed = sync_to(t, car);
  const std::size_t remaining = t.previous_path.size();
  std::vector<FrenetState> states;
  std::vector<core::Vec2> points;
  const auto n_points = static_cast<std::size_t>(std::max(tp.path_points, 2));
  states.reserve(n_points);
  points.reserve(n_points);
  if (synced_) {
    const std::size_t keep =
        std::min<std::size_t>(static_cast<std::size_t>(std::max(tp.keep_points, 0)), remaining);
    for (std::size_t i = 0; i < keep; ++i) {
      states.push_back(states_[consumed + i]);
      points.push_back(t.previous_path[i]);
    }
  } else {
    car = observed_state(t);
    tracks_.clear();
    band_time_s_ = 0.0;
    driven_.clear();
  }
  // Enough history for the checks across the joint (3 check steps), no more.
  const auto history_steps = static_cast<std::size_t>(std::lround(3.0 * tp.check_step_s / dt)) + 1;
  if (driven_.size() > history_steps) {
    driven_.erase(driven_.begin(), driven_.end() - static_cast<std::ptrdiff_t>(history_steps));
  }
  double band_time = band_time_s_;
  for (const FrenetState& x : states) {
    band_time =
        in_line_band(frame_.original_d(x.s_m, x.d_m), tp.line_band_m, road_) ? band_time + dt : 0.0;
  }
  // Keep s within one loop at the car (the plan may run past the end).
  const double shift = line_.wrap_s(car.s_m) - car.s_m;
  car.s_m += shift;
  for (FrenetState& x : states) x.s_m += shift;
  const FrenetState start = states.empty() ? car : states.back();
  const double start_delay = static_cast<double>(states.size()) * dt;
  const double elapsed = synced_ ? static_cast<double>(consumed) * dt : 0.0;

  // Prediction, behaviour, trajectory.
  predictions_ =
      predict_cars(t, frame_, car.s_m, elapsed, tracks_, p_.prediction, road_, car_.length_m);
  const RoadPoint at_car = road_point(frame_, car.s_m, car.d_m);
  EgoSnapshot ego;
  ego.s_m = car.s_m;
  ego.d_m = car.d_m;
  ego.speed_mps = car.s_dot * at_car.along_scale;
  ego.m_per_unit_s = at_car.along_scale;
  decision_ = decide(predictions_, ego, behaviour_, elapsed, car_.length_m, p_.behaviour, road_);
  if (command_) take_command(*command_);

  TrajectoryRequest req;
  req.start = start;
  req.history = history_before(states, start);
  req.start_delay_s = start_delay;
  req.target_lane = decision_.target_lane;
  req.wanted_speed_mps = decision_.speed_mps;
  req.band_time_s = band_time;
  req.cars = &predictions_;
  plan_ = plan_trajectory(frame_, req, p_, road_, car_, &scratch);
  const TrajectoryPlan& chosen = plan_;
  status_ = chosen.status;
  if (chosen.trajectory.end_lane != behaviour_.target_lane) {
    // The trajectory layer could not go where behaviour wanted: behaviour follows it.
    behaviour_.target_lane = chosen.trajectory.end_lane;
    behaviour_.goal_lane = chosen.trajectory.end_lane;
  }

  core::PlanResult result = commit(std::move(states), std::move(points), car, n_points);
  result.change_declined = plan_.change_declined;
  return result;
}

// A decision from outside takes the behaviour layer's place (its state follows it).
void ReferencePolicy::take_command(const DrivingCommand& c) {
  decision_.target_lane = std::clamp(c.target_lane, 0, road_.lane_count - 1);
  decision_.goal_lane = decision_.target_lane;
  decision_.speed_mps = std::clamp(c.speed_mps, 0.0, p_.behaviour.cruise_speed_mps);
  behaviour_.target_lane = decision_.target_lane;
  behaviour_.goal_lane = decision_.target_lane;
}

// The plan sent: the kept points and then the chosen trajectory's, to n_points; remembered
// (sent_, states_, origin_) to sync with at the next cycle.
core::PlanResult ReferencePolicy::commit(std::vector<FrenetState> states,
                                         std::vector<core::Vec2> points, const FrenetState& car,
                                         std::size_t n_points) {
  const double dt = step_s_;
  const auto& tp = p_.trajectory;
  const TrajectoryPlan& chosen = plan_;
  const std::size_t fresh = n_points - states.size();
  for (std::size_t i = 1; i <= fresh; ++i) {
    const FrenetState x = chosen.trajectory.at(static_cast<double>(i) * dt);
    const RoadPoint at = road_point(frame_, x.s_m, x.d_m);
    states.push_back(x);
    points.push_back(points.empty() ? at.position : steady_point(points.back(), at, x, tp));
  }
  sent_.assign(points.begin(), points.end());
  sent_rounded_ = false;
  states_ = std::move(states);
  origin_ = car;
  have_plan_ = true;
  return {std::move(points), to_core(chosen.status), status_reason(chosen)};
}

}  // namespace overtake::planner::reference

namespace overtake::planner::reference {
namespace {

void archive_frenet_state(core::StateArchive& ar, FrenetState& f) {
  ar.io_metres(f.s_m, "state s");
  ar.io_speed(f.s_dot, "state s rate");
  ar.io(f.s_ddot, "state s acceleration");
  ar.io_metres(f.d_m, "state d");
  ar.io_speed(f.d_dot_mps, "state d rate");
  ar.io(f.d_ddot_mps2, "state d acceleration");
}

/// States along a path, each field against the state before it (they compress).
void archive_states(core::StateArchive& ar, std::vector<FrenetState>& states,
                    std::string_view what) {
  constexpr std::size_t kMaxPoints = 1U << 16U;
  const std::size_t n = ar.io_length(states.size(), kMaxPoints, what);
  if (ar.loading()) states.assign(n, FrenetState{});
  std::array<std::uint64_t, 6> prev{};
  for (FrenetState& f : states) {
    ar.io_delta(f.s_m, prev[0], what, core::StateArchive::kMaxMetres);
    ar.io_delta(f.s_dot, prev[1], what, core::StateArchive::kMaxSpeed);
    ar.io_delta(f.s_ddot, prev[2], what);
    ar.io_delta(f.d_m, prev[3], what, core::StateArchive::kMaxMetres);
    ar.io_delta(f.d_dot_mps, prev[4], what, core::StateArchive::kMaxSpeed);
    ar.io_delta(f.d_ddot_mps2, prev[5], what);
  }
}

}  // namespace

bool ReferencePolicy::archive_state(core::StateArchive& ar) {
  constexpr std::size_t kMaxPoints = 1U << 16U;
  ar.part("reference");
  archive_states(ar, states_, "states sent");
  archive_states(ar, driven_, "states driven");
  // The points as the simulator read them (what a cycle compares).
  if (!sent_rounded_) sent_ = core::round_like_wire(std::move(sent_));
  sent_rounded_ = true;
  const std::size_t sent = ar.io_length(sent_.size(), kMaxPoints, "points sent");
  if (ar.loading()) sent_.assign(sent, core::Vec2{});
  std::uint64_t x_bits = 0, y_bits = 0;
  for (core::Vec2& p : sent_) {
    ar.io_delta(p.x, x_bits, "point sent", core::StateArchive::kMaxMetres);
    ar.io_delta(p.y, y_bits, "point sent", core::StateArchive::kMaxMetres);
  }
  ar.require(sent_.size() == states_.size() || sent_.empty(), "points sent: not one per state");
  archive_frenet_state(ar, origin_);
  ar.io(have_plan_, "has a plan");
  ar.io(band_time_s_, "time in a line band");
  ar.io_vector(tracks_, kMaxPoints, "car tracks", [](core::StateArchive& a, CarTrack& t) {
    a.io_range(t.id, -1, 65535, "track id");
    a.io_metres(t.s_m, "track s");
    a.io_speed(t.s_dot, "track speed");
    a.io(t.s_ddot, "track acceleration");
    a.io_speed(t.top_speed_mps, "track top speed");
  });
  ar.io_range(behaviour_.target_lane, -1, road_.lane_count - 1, "target lane");
  ar.io_range(behaviour_.goal_lane, -1, road_.lane_count - 1, "goal lane");
  ar.io(behaviour_.since_settled_s, "since settled");
  return true;
}

}  // namespace overtake::planner::reference
