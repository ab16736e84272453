#include "overtake/run/map_file.hpp"

#include "overtake/base/io.hpp"

namespace overtake::run {

using base::read_file;

core::Map load_map_file(const std::filesystem::path& path, const core::MapRules& rules) {
  std::string text;
  try {
    text = read_file(path, kMaxMapFileBytes);
  } catch (const std::runtime_error& e) {
    throw core::MapError(std::string(e.what()) + " (map file)");
  }
  return core::parse_map(text, path.string(), rules);
}

}  // namespace overtake::run
