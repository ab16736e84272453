#pragma once
// Recorded traffic: the bodies of every car at every step of a stretch of a run, for a cut
// scenario whose traffic replays what happened whatever the ego does (World::replay_traffic).

#include <string>
#include <string_view>
#include <vector>

#include "overtake/sim/traffic.hpp"

namespace overtake::sim {

/// Step k holds every car after the k-th step from the start (step 0: at the start).
using RecordedTraffic = std::vector<std::vector<TrafficCar>>;

/// The bodies as bytes, exact: each double is stored as its bits XOR those of the same
/// car's value one step before, so that a general compressor finds the repetition.
[[nodiscard]] std::string encode_recorded_traffic(const RecordedTraffic& steps);
/// Reads them back; core::StateError naming `name` and what is wrong. Lanes and waypoint
/// indices are checked against the road and the map the scenario runs on.
[[nodiscard]] RecordedTraffic decode_recorded_traffic(std::string_view bytes, std::string_view name,
                                                      int lanes, std::size_t waypoints);

}  // namespace overtake::sim
