#include "overtake/app/map_file.hpp"

#include <fstream>
#include <sstream>

namespace overtake::app {

core::Map load_map_file(const std::filesystem::path& path, const core::MapRules& rules) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw core::MapError(path.string() + ": cannot open map file");
  std::ostringstream buf;
  buf << in.rdbuf();
  if (in.bad()) throw core::MapError(path.string() + ": error while reading map file");
  return core::parse_map(buf.str(), path.string(), rules);
}

}  // namespace overtake::app
