#include "overtake/app/map_file.hpp"

#include "overtake/app/io.hpp"

namespace overtake::app {

core::Map load_map_file(const std::filesystem::path& path, const core::MapRules& rules) {
  std::string text;
  try {
    text = read_file(path, kMaxMapFileBytes);
  } catch (const std::runtime_error& e) {
    throw core::MapError(std::string(e.what()) + " (map file)");
  }
  return core::parse_map(text, path.string(), rules);
}

}  // namespace overtake::app
