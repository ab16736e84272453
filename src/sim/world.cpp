#include "overtake/sim/world.hpp"

#include <cmath>
#include <limits>

#include "overtake/core/random.hpp"
#include "overtake/core/units.hpp"
#include "overtake/core/wire_number.hpp"
#include "overtake/sim/checkpoint.hpp"
#include "overtake/sim/path_queue.hpp"

namespace overtake::sim {
namespace {

constexpr std::uint64_t kTrafficStream = 10;
/// The start position is rounded to this (m), and its heading to this (degrees).
constexpr double kStartPositionStepM = 0.01;
constexpr double kStartHeadingStepDeg = 1.0;

double yaw_0_2pi(double yaw) {
  double y = std::fmod(yaw, 2.0 * core::kPi);
  if (y < 0.0) y += 2.0 * core::kPi;
  return y;
}

double round_to(double v, double step) {
  return std::round(v / step) * step;
}

/// Rounds `path` as the wire does (core::round_like_wire), the points it shares with `queue`
/// (rounded already) kept as they are.
void round_new_points(std::vector<core::Vec2>& path, const std::deque<core::Vec2>& queue) {
  // A planner sends back the points of the path it was given (the queue's, from where the
  // path's first point is in it) before its new ones. The queue holds rounded points and
  // rounding is idempotent, so a point equal to its queue point would round to itself: only
  // the others are rounded (as core::round_like_wire rounds each point).
  std::size_t from = queue.size();
  if (!path.empty()) {
    for (std::size_t q = 0; q < queue.size(); ++q) {
      if (queue[q] == path.front()) {
        from = q;
        break;
      }
    }
  }
  for (std::size_t j = 0; j < path.size(); ++j) {
    core::Vec2& p = path[j];
    if (from + j < queue.size() && p == queue[from + j]) continue;
    p = {core::wire_round(p.x), core::wire_round(p.y)};
  }
}

}  // namespace

World::World(const core::Map& map, const core::ReferenceLine& line, const WorldParams& params,
             TrafficProfile profile, std::uint64_t seed,
             std::shared_ptr<const OpenRoadTable> open_road)
    : line_(line),
      chords_(map),
      params_(params),
      traffic_(map, line, chords_, params.traffic, params.road, params.car, profile,
               core::derive_seed(seed, kTrafficStream), std::move(open_road)) {
  place_ego({params.ego.start_s_m, params.ego.start_d_m});
  traffic_.place_initial(ego_view());
}

World::World(const core::Map& map, const core::ReferenceLine& line, const WorldParams& params,
             const Scenario& scenario)
    : World(
          map, line,
          [&] {
            WorldParams p = params;
            p.ego.start_s_m = scenario.ego_s_m;
            p.ego.start_d_m = scenario.ego_d_m;
            return p;
          }(),
          TrafficProfile::faithful, 0) {
  traffic_.set_script(scenario.cars);
  events_ = scenario.events;
  if (scenario.ego_speed_mps > 0.0) {
    ego_.speed_mps = scenario.ego_speed_mps;
    const double ds = scenario.ego_speed_mps * params_.step_s;
    const auto points = static_cast<int>(std::lround(1.0 / params_.step_s));
    std::vector<core::Vec2> path;
    for (int i = 1; i <= points; ++i) {
      path.push_back(line_.to_cartesian({ego_.frenet.s_m + ds * i, ego_.frenet.d_m}));
    }
    apply_path(std::move(path));
  }
}

void World::place_ego(core::FrenetPoint start) {
  // Where the original's scene puts the car: the chord point of the start s and d, on whole
  // centimetres, facing along the chord to a whole degree.
  const core::Vec2 at = chords_.to_cartesian(start);
  ego_.position = {round_to(at.x, kStartPositionStepM), round_to(at.y, kStartPositionStepM)};
  ego_.yaw_rad = core::deg_to_rad(
      round_to(core::rad_to_deg(chords_.chord_heading_rad(start.s_m)), kStartHeadingStepDeg));
  ego_.speed_mps = 0.0;
  ego_.closest_waypoint = chords_.closest(ego_.position);
  ego_.frenet = line_.to_frenet(ego_.position, line_.wrap_s(start.s_m));
  update_ego_frenet();
}

void World::update_ego_frenet() {
  ego_.closest_waypoint = chords_.closest(ego_.position, ego_.closest_waypoint);
  ego_.map_frenet = chords_.to_frenet(ego_.position, ego_.closest_waypoint);
}

EgoView World::ego_view() const {
  return {ego_footprint(), ego_.speed_mps, ego_.frenet, ego_.map_frenet, ego_.closest_waypoint};
}

core::OrientedBox World::ego_footprint() const {
  return {ego_.position, ego_.yaw_rad, params_.car.length_m, params_.car.width_m};
}

core::Telemetry World::telemetry() const {
  core::Telemetry t;
  t.ego = {ego_.position, yaw_0_2pi(ego_.yaw_rad), ego_.speed_mps, ego_.map_frenet.s_m,
           ego_.map_frenet.d_m};
  t.previous_path.assign(queue_.begin(), queue_.end());
  if (!queue_.empty()) {
    // The original measures the end of the path from the ego's closest waypoint.
    t.end_path = chords_.to_frenet(queue_.back(), ego_.closest_waypoint);
  }
  t.cars.reserve(traffic_.cars().size());
  for (const TrafficCar& c : traffic_.cars()) t.cars.push_back(traffic_.observe(c));
  if (params_.wire_rounding) {
    // The queue holds points rounded already (apply_path): rounding is idempotent, so only
    // the rest is rounded here.
    std::vector<core::Vec2> path = std::move(t.previous_path);
    t = core::round_like_wire(std::move(t));
    t.previous_path = std::move(path);
  }
  return t;
}

void World::apply_path(std::vector<core::Vec2> path) {
  if (params_.wire_rounding) round_new_points(path, queue_);
  const auto kept = trim_new_path(path, ego_.position, params_.ego.stand_on_tolerance_m);
  queue_.assign(kept.begin(), kept.end());
}

void World::step() {
  while (next_event_ < events_.size() && events_[next_event_].t_s <= time_s() + 1e-9) {
    traffic_.apply_event(events_[next_event_++]);
  }
  // Traffic decides from the frame before this step, then moves.
  traffic_.step(ego_view(), params_.step_s);
  if (keep_moved_) moved_ = traffic_.cars();

  // The ego's perfect controller: onto the next point, facing the one after it. With one
  // point left the car stays where it is and the point is dropped.
  if (queue_.size() >= 2) {
    const core::Vec2 next = queue_.front();
    queue_.pop_front();
    const core::Vec2 after = queue_.front();
    ego_.speed_mps = core::distance(ego_.position, next) / params_.step_s;
    ego_.position = next;
    if (!(after == next)) ego_.yaw_rad = std::atan2(after.y - next.y, after.x - next.x);
    ego_.frenet = line_.to_frenet(ego_.position, ego_.frenet.s_m);
    update_ego_frenet();
  } else {
    queue_.clear();
    ego_.speed_mps = 0.0;
  }
  ++steps_;

  contact_ = traffic_.resolve_contacts(ego_view());
}

void World::archive(core::StateArchive& ar) {
  // A queue longer than this was never sent by any planner (the protocol's paths hold a few
  // hundred points).
  constexpr std::size_t kMaxQueue = 1U << 20U;
  ar.part("world");
  ar.io_range(steps_, 0, std::lround(kMaxCheckpointRunS / params_.step_s), "step");
  ar.io(ego_.position, "ego position");
  ar.io(ego_.yaw_rad, "ego heading");
  ar.io_speed(ego_.speed_mps, "ego speed");
  ar.io(ego_.frenet, "ego s and d");
  ar.io(ego_.map_frenet, "ego s and d on the chords");
  ar.io_range(ego_.closest_waypoint, 0, chords_.size() - 1, "ego waypoint");
  const std::size_t queued = ar.io_length(queue_.size(), kMaxQueue, "path queue");
  if (ar.loading()) queue_.assign(queued, core::Vec2{});
  std::uint64_t x_bits = 0, y_bits = 0;
  for (core::Vec2& p : queue_) {
    ar.io_delta(p.x, x_bits, "queued point", core::StateArchive::kMaxMetres);
    ar.io_delta(p.y, y_bits, "queued point", core::StateArchive::kMaxMetres);
  }
  ar.io_optional(contact_, "contact",
                 [](core::StateArchive& a, int& id) { a.io_range(id, 0, 65535, "contact car"); });
  ar.io_range(next_event_, 0, events_.size(), "next event");
  traffic_.archive(ar);
}

void World::replay_traffic(std::vector<std::vector<TrafficCar>> steps) {
  traffic_.set_replayed(std::move(steps));
}

EgoFrame World::ego_frame() const {
  return {time_s(),        ego_.position, ego_.speed_mps, ego_.map_frenet.s_m, ego_.map_frenet.d_m,
          ego_.frenet.d_m, contact_,      std::nullopt};
}

}  // namespace overtake::sim
