#pragma once
// What the files of `overtake hunt` share (batch/hunt*.cpp): a hunt's checks of its spec, its
// identity across shards, and its maps.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "overtake/batch/hunt.hpp"
#include "overtake/run/config.hpp"
#include "overtake/run/drive.hpp"

namespace overtake::batch::hunt_detail {

/// A map as the hunt's files name it: its path, or "default" for the built-in track.
[[nodiscard]] inline std::string map_name(const std::optional<std::filesystem::path>& map) {
  return map ? map->string() : std::string("default");
}

/// Every flag of the spec checked against its bounds and the others (not the files it names).
void check_spec(const HuntSpec& spec);

/// What makes the shards of a hunt one hunt: every flag that changes what it finds.
[[nodiscard]] nlohmann::json hunt_sweep(const HuntSpec& spec, const run::Config& config);

/// The hunt's maps, each once: two files with the same contents are one map driven twice.
[[nodiscard]] std::vector<std::shared_ptr<const run::Track>> load_hunt_tracks(const HuntSpec& spec);

}  // namespace overtake::batch::hunt_detail
