#include "overtake/sim/world.hpp"

#include <cmath>

#include "overtake/core/random.hpp"
#include "overtake/core/units.hpp"
#include "overtake/sim/path_queue.hpp"

namespace overtake::sim {
namespace {

constexpr std::uint64_t kTrafficStream = 10;
// Cars farther apart than this along the road cannot touch (footprints are ~5 m long).
constexpr double kCollisionCullM = 12.0;

double yaw_0_2pi(double yaw) {
  double y = std::fmod(yaw, 2.0 * core::kPi);
  if (y < 0.0) y += 2.0 * core::kPi;
  return y;
}

}  // namespace

World::World(const core::Map& map, const core::ReferenceLine& line, const WorldParams& params,
             TrafficProfile profile, std::uint64_t seed)
    : line_(line),
      params_(params),
      traffic_(map, line, params.traffic, params.road, profile,
               core::derive_seed(seed, kTrafficStream)),
      referee_(params.referee, params.step_s, params.road) {
  const core::FrenetPoint start{line.wrap_s(params.ego.start_s_m), params.ego.start_d_m};
  ego_.position = line.to_cartesian(start);
  ego_.frenet = line.to_frenet(ego_.position, start.s_m);
  ego_.yaw_rad = line.frame(start.s_m).heading_rad;
  ego_.speed_mps = 0.0;
  traffic_.place_initial(ego_view());
}

World::World(const core::Map& map, const core::ReferenceLine& line, const WorldParams& params,
             const Scenario& scenario)
    : World(map, line,
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
      path.push_back(line_.to_cartesian({ego_.frenet.s_m + ds * i, scenario.ego_d_m}));
    }
    apply_path(std::move(path));
  }
}

EgoView World::ego_view() const {
  return {ego_.frenet.s_m, ego_.frenet.d_m, ego_.speed_mps};
}

core::OrientedBox World::ego_footprint() const {
  return {ego_.position, ego_.yaw_rad, params_.ego.length_m, params_.ego.width_m};
}

core::Telemetry World::telemetry() const {
  core::Telemetry t;
  t.ego = {ego_.position, yaw_0_2pi(ego_.yaw_rad), ego_.speed_mps, ego_.frenet.s_m,
           ego_.frenet.d_m};
  t.previous_path.assign(queue_.begin(), queue_.end());
  if (!queue_.empty()) {
    t.end_path = line_.to_frenet(queue_.back(), ego_.frenet.s_m);
  }
  t.cars.reserve(traffic_.cars().size());
  for (const TrafficCar& c : traffic_.cars()) t.cars.push_back(traffic_.observe(c));
  if (params_.wire_rounding) t = core::round_like_wire(std::move(t));
  return t;
}

void World::apply_path(std::vector<core::Vec2> path) {
  if (params_.wire_rounding) path = core::round_like_wire(std::move(path));
  const auto kept = trim_new_path(path, ego_.position, params_.ego.stand_on_tolerance_m);
  queue_.assign(kept.begin(), kept.end());
}

std::optional<int> World::collision() const {
  const core::OrientedBox ego_box = ego_footprint();
  for (const TrafficCar& c : traffic_.cars()) {
    if (std::abs(line_.s_ahead(ego_.frenet.s_m, c.s_m)) > kCollisionCullM) continue;
    if (core::boxes_overlap(ego_box, traffic_.footprint(c))) return c.id;
  }
  return std::nullopt;
}

void World::step() {
  while (next_event_ < events_.size() && events_[next_event_].t_s <= time_s() + 1e-9) {
    traffic_.apply_event(events_[next_event_++]);
  }
  // Traffic decides from the frame before this step, then moves.
  traffic_.step(ego_view(), params_.step_s);

  // The ego's perfect controller: onto the next point, facing the one after it.
  if (queue_.size() >= 2) {
    const core::Vec2 next = queue_.front();
    queue_.pop_front();
    const core::Vec2 after = queue_.front();
    ego_.speed_mps = core::distance(ego_.position, next) / params_.step_s;
    ego_.position = next;
    if (!(after == next)) ego_.yaw_rad = std::atan2(after.y - next.y, after.x - next.x);
    ego_.frenet = line_.to_frenet(ego_.position, ego_.frenet.s_m);
  } else {
    ego_.speed_mps = 0.0;
  }
  ++steps_;

  referee_.observe({time_s(), ego_.position, ego_.speed_mps, ego_.frenet.s_m, ego_.frenet.d_m,
                    collision()});
}

}  // namespace overtake::sim
