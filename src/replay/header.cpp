// The replay header: what a viewer needs of the road and the limits, and what was run.

#include <nlohmann/json.hpp>

#include "wire.hpp"

namespace overtake::replay {

using nlohmann::json;
using namespace wire;

ReplayHeader make_replay_header(const core::ReferenceLine& line, const sim::WorldParams& params,
                                ReplayProvenance provenance) {
  ReplayHeader h;
  h.step_s = params.step_s;
  h.lanes = params.road.lane_count;
  h.lane_width_m = params.road.lane_width_m;
  h.car_length_m = params.car.length_m;
  h.car_width_m = params.car.width_m;
  h.speed_limit_mps = params.referee.speed_limit_mps;
  h.max_acceleration_mps2 = params.referee.max_accel_mps2;
  h.max_jerk_mps3 = params.referee.max_jerk_mps3;
  h.track_length_m = line.length_m();
  const auto n = static_cast<long>(std::ceil(line.length_m() / kReplayLaneLineSpacingM));
  const double ds = line.length_m() / static_cast<double>(n);
  const auto round_cm = [](double m) { return std::round(m * kCmPerM) / kCmPerM; };
  for (int k = 0; k <= h.lanes; ++k) {
    const double d = k * h.lane_width_m;
    std::vector<double> xy;
    xy.reserve(static_cast<std::size_t>(2 * (n + 1)));
    for (long i = 0; i < n; ++i) {
      const core::Vec2 p = line.to_cartesian({line.start_s_m() + ds * static_cast<double>(i), d});
      xy.push_back(round_cm(p.x));
      xy.push_back(round_cm(p.y));
    }
    xy.push_back(xy[0]);  // closed: the last point is the first
    xy.push_back(xy[1]);
    h.lane_lines.push_back(std::move(xy));
  }
  for (std::size_t i = 0; i < sim::kIncidentTypeCount; ++i)
    h.incident_types.push_back(incident_type_name(i));
  for (std::size_t k = 0; k < sim::kCollisionKindCount; ++k) {
    h.collision_kinds.emplace_back(sim::to_string(static_cast<sim::CollisionKind>(k)));
  }
  h.provenance = std::move(provenance);
  return h;
}

std::string replay_header_json(const ReplayHeader& h) {
  const ReplayProvenance& p = h.provenance;
  json j = json::object();
  j["format"] = "overtake-replay";
  j["version"] = kReplayVersion;
  j["step_s"] = h.step_s;
  j["road"] = {{"lanes", h.lanes}, {"lane_width_m", h.lane_width_m}};
  j["car"] = {{"length_m", h.car_length_m}, {"width_m", h.car_width_m}};
  j["limits"] = {{"speed_mps", h.speed_limit_mps},
                 {"acceleration_mps2", h.max_acceleration_mps2},
                 {"jerk_mps3", h.max_jerk_mps3}};
  j["track_length_m"] = h.track_length_m;
  j["lane_lines"] = h.lane_lines;
  j["incident_types"] = h.incident_types;
  j["collision_kinds"] = h.collision_kinds;
  j["provenance"] = {{"policy", p.policy},
                     {"traffic", p.traffic},
                     {"seed", p.seed},
                     {"track", p.track},
                     {"duration_s", p.duration_s},
                     {"overtake_version", p.overtake_version},
                     {"config_hash", p.config_hash}};
  if (p.cut_from) {
    const ReplayCutOrigin& c = *p.cut_from;
    j["provenance"]["cut_from"] = {{"scenario", c.scenario}, {"replay", c.replay},
                                   {"policy", c.policy},     {"traffic", c.traffic},
                                   {"seed", c.seed},         {"at_s", c.at_s},
                                   {"start_s", c.start_s},   {"incident", c.incident}};
  }
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);  // stray bytes: U+FFFD
}

std::string replay_preamble(const ReplayHeader& header) {
  const std::string text = replay_header_json(header);
  std::string out(kReplayMagic);
  put_u32(out, kReplayVersion);
  put_u32(out, static_cast<std::uint32_t>(text.size()));
  out += text;
  return out;
}

}  // namespace overtake::replay
