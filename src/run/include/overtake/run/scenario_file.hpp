#pragma once
// Scenario files (JSON) for `--scenario FILE`. Format (SI units; see docs/scenarios.md):
//   {"name": "...", "duration_s": 40,
//    "ego": {"s_m": 300, "lane": 1, "speed_mps": 21.9},         (or "d_m" instead of "lane")
//    "cars": [{"gap_m": 20, "lane": 0, "speed_mps": 17.9}, ...], (or "s_m": absolute)
//    "events": [{"t_s": 2, "car": 0, "change_lane": 1},
//               {"t_s": 6, "car": 1, "brake_mps2": 6, "duration_s": 2},
//               {"t_s": 9, "car": 1, "speed_mps": 20, "accel_mps2": 2}]}

#include <cstddef>
#include <filesystem>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "overtake/core/road.hpp"
#include "overtake/sim/scenario.hpp"

namespace overtake::run {

/// The most cars a scripted scenario may place (random traffic keeps 12; the library's
/// scripted scenarios place at most 4). Events name cars 0 to this less one.
inline constexpr std::size_t kMaxScenarioCars = 64;
/// The most timed events a scripted scenario may hold (the library's most is 28).
inline constexpr std::size_t kMaxScenarioEvents = 10000;
/// The most bytes one blob of a cut scenario (its checkpoint, its recorded traffic) may inflate
/// to: the library's largest, 20 s of replayed traffic, is 0.98 MB; a checkpoint is 21 KB.
/// `cut` refuses a window whose replayed traffic would be larger.
inline constexpr std::size_t kMaxBlobBytes = std::size_t{16} << 20U;
/// The most bytes a cut scenario's warm-up may inflate to: what a planner was told and answered
/// takes about 1 to 2 KB a cycle (a 10-minute run played whole is 12 to 25 MB).
inline constexpr std::size_t kMaxWarmUpBytes = std::size_t{256} << 20U;

/// Reads a scenario from JSON; errors (ConfigError) name `source` and the key.
[[nodiscard]] sim::Scenario parse_scenario(const nlohmann::json& j, std::string_view source,
                                           const core::RoadParams& road);

/// Reads a scenario from the text of a file (parse_json_text, then parse_scenario); every
/// fault is a ConfigError naming `source`.
[[nodiscard]] sim::Scenario parse_scenario_text(std::string_view text, std::string_view source,
                                                const core::RoadParams& road);

/// Bytes as scenario files carry them: zlib, then base64.
[[nodiscard]] std::string pack_blob(std::string_view bytes);
/// The bytes back; a ConfigError naming `what` when the text is not base64 of exactly one
/// whole zlib stream (nothing after its end), or inflates beyond kMaxBlobBytes.
[[nodiscard]] std::string unpack_blob(std::string_view text, std::string_view what,
                                      std::size_t max_bytes = kMaxBlobBytes);

/// Reads a scenario file.
[[nodiscard]] sim::Scenario load_scenario(const std::filesystem::path& path,
                                          const core::RoadParams& road);

}  // namespace overtake::run
