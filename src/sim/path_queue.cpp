#include "overtake/sim/path_queue.hpp"

#include <limits>

namespace overtake::sim {

std::vector<core::Vec2> trim_new_path(std::span<const core::Vec2> path, core::Vec2 car,
                                      double stand_on_tolerance_m) {
  if (path.empty()) return {};
  std::size_t nearest = 0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < path.size(); ++i) {
    const double d2 = core::distance_sq(path[i], car);
    if (d2 < best) {
      best = d2;
      nearest = i;
    }
  }
  std::size_t first_kept = nearest + 1;
  if (nearest == 0 && best > stand_on_tolerance_m * stand_on_tolerance_m) first_kept = 0;
  return {path.begin() + static_cast<std::ptrdiff_t>(first_kept), path.end()};
}

}  // namespace overtake::sim
