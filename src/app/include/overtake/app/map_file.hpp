#pragma once
// Map files on disk: read here, at the edge; the core parses their text (core::parse_map).

#include <filesystem>

#include "overtake/core/map.hpp"

namespace overtake::app {

/// Reads and parses a map file in the original format. Throws core::MapError naming the path
/// (also when the file cannot be read).
[[nodiscard]] core::Map load_map_file(const std::filesystem::path& path,
                                      const core::MapRules& rules = {});

}  // namespace overtake::app
