#pragma once
// The project's configuration: every module's params struct, read from JSON. The shipped
// defaults (config/overtake.json, built into the binary) equal the structs' defaults; a
// user file given with --config overrides any subset of keys.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "overtake/core/road.hpp"
#include "overtake/planner/params.hpp"
#include "overtake/sim/params.hpp"

namespace overtake::run {

/// The longest drive (a week), and so the latest moment a scenario file may name.
inline constexpr double kMaxMinutes = 7.0 * 24.0 * 60.0;

/// All parameters. The facts several modules share are given once, at the top (`road`, `car`)
/// or in the module that owns them (`world.step_s`), and copied into the others' params.
struct Config {
  core::RoadParams road;
  core::CarFootprint car;
  sim::WorldParams world;
  planner::PlannerParams planner;
  friend bool operator==(const Config&, const Config&) = default;
};

/// A config file or value that cannot be used; the message names the file and key.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// JSON text (a config or scenario file's contents). Text that is not JSON, including a
/// number beyond the range of a double such as 1e999, is a ConfigError naming `source` and
/// where the parser stopped; so is text nested deeper than core::kMaxJsonDepth (which would
/// overflow the stack of anything that walks it) and a key given twice in one object.
[[nodiscard]] nlohmann::json parse_json_text(std::string_view text, std::string_view source);

/// The largest JSON file read (a config, a scenario, a bench's bench.json, a hunt's
/// hunt.json): the largest scenario in the library is under 1 MB.
inline constexpr std::uintmax_t kMaxJsonFileBytes = 64ULL << 20;

/// A JSON file's contents; a file that cannot be read (or is not a regular file, or is larger
/// than kMaxJsonFileBytes) or is not JSON is a ConfigError naming the path (and, for bad JSON,
/// where the parser stopped).
[[nodiscard]] nlohmann::json read_json_file(const std::filesystem::path& path);

/// Applies the keys present in `j` (any subset) on top of `base`. Unknown keys, wrong types
/// and invalid values are errors naming `source` and the key. The road and the car footprint
/// are copied into the world's and planner's params, and the world's step into the planner's.
[[nodiscard]] Config apply_config_json(Config base, const nlohmann::json& j,
                                       std::string_view source);

/// apply_config_json on the text of a config file (parse_json_text, then the keys); every
/// fault is a ConfigError naming `source`.
[[nodiscard]] Config apply_config_text(Config base, std::string_view text, std::string_view source);

/// The shipped defaults (the built-in config/overtake.json).
[[nodiscard]] Config default_config();

/// Defaults, then the user's file when given.
[[nodiscard]] Config load_config(const std::optional<std::filesystem::path>& user_file);

/// Every key of the config as JSON (the format of config/overtake.json).
[[nodiscard]] nlohmann::json config_to_json(const Config& c);

/// Hash of the config's JSON, for provenance.
[[nodiscard]] std::string config_hash(const Config& c);

}  // namespace overtake::run
