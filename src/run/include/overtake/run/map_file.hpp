#pragma once
// Map files on disk: read here, at the edge; the core parses their text (core::parse_map).

#include <cstdint>
#include <filesystem>

#include "overtake/core/map.hpp"

namespace overtake::run {

/// The largest map file read: the original's is 8 KB, and one of the 20,000 waypoints a map
/// may have (core::MapRules) about 2 MB.
inline constexpr std::uintmax_t kMaxMapFileBytes = 16ULL << 20;

/// Reads and parses a map file in the original format. Throws core::MapError naming the path
/// (also when the file cannot be read).
[[nodiscard]] core::Map load_map_file(const std::filesystem::path& path,
                                      const core::MapRules& rules = {});

}  // namespace overtake::run
