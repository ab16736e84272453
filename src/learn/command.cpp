#include "overtake/learn/command.hpp"

#include <algorithm>
#include <cmath>

#include "overtake/learn/vec_env.hpp"

namespace overtake::learn {

void apply_meta(EgoContext& e, std::int64_t action, int lanes, double cruise_mps,
                double speed_step_mps) {
  switch (action) {
    case MetaAction::left:
      e.target_lane = std::max(0, e.target_lane - 1);
      break;
    case MetaAction::right:
      e.target_lane = std::min(lanes - 1, e.target_lane + 1);
      break;
    case MetaAction::faster:
      e.target_speed_mps = std::min(cruise_mps, e.target_speed_mps + speed_step_mps);
      break;
    case MetaAction::slower:
      e.target_speed_mps = std::max(0.0, e.target_speed_mps - speed_step_mps);
      break;
    default:
      break;
  }
}

void apply_continuous(EgoContext& e, float speed, float lane, int lanes, double cruise_mps) {
  e.target_speed_mps = std::clamp(static_cast<double>(speed), 0.0, 1.0) * cruise_mps;
  const double at = (std::clamp(static_cast<double>(lane), -1.0, 1.0) + 1.0) / 2.0 * (lanes - 1);
  e.target_lane = std::clamp(static_cast<int>(std::lround(at)), 0, lanes - 1);
}

}  // namespace overtake::learn
