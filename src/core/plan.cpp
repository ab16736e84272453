#include "overtake/core/plan.hpp"

#include <cmath>
#include <cstdio>

namespace overtake::core {

std::optional<std::string> path_problem(std::span<const Vec2> path) {
  for (std::size_t i = 0; i < path.size(); ++i) {
    const Vec2 p = path[i];
    const bool finite = std::isfinite(p.x) && std::isfinite(p.y);
    if (finite && std::abs(p.x) <= kMaxPathCoordinateM && std::abs(p.y) <= kMaxPathCoordinateM) {
      continue;
    }
    char where[96];
    std::snprintf(where, sizeof where, "point %zu is (%.6g, %.6g)", i, p.x, p.y);
    return std::string(where) +
           (finite ? ": beyond 1,000 km of the map's origin" : ": not a finite number");
  }
  return std::nullopt;
}

}  // namespace overtake::core
