#pragma once
// What a planner answers for one cycle: the path, and how it was found. A plain struct in
// core, so that the run loop (sim) counts statuses without knowing any planner.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "overtake/core/geometry.hpp"

namespace overtake::core {

/// How a planner found this cycle's path.
enum class PlanStatus : std::uint8_t {
  normal,     ///< planned as it meant to (every check passed, or the policy has no checks)
  least_bad,  ///< nothing passed its checks: the least bad candidate
  fallback,   ///< nothing usable: an emergency manoeuvre (e.g. braking in the lane)
};
inline constexpr std::size_t kPlanStatusCount = 3;

/// "normal", "least_bad", "fallback" (the report's keys).
[[nodiscard]] constexpr std::string_view to_string(PlanStatus s) {
  switch (s) {
    case PlanStatus::normal:
      return "normal";
    case PlanStatus::least_bad:
      return "least_bad";
    case PlanStatus::fallback:
      return "fallback";
  }
  return "unknown";
}

/// A lane change the planner's decision layer chose that its path layer did not take this
/// cycle (it planned to stay, or to go back): for its cost (some path into the lane passes
/// every check, and staying was cheaper) or for safety (none does). Built-in planners say;
/// others answer `no`.
enum class ChangeDeclined : std::uint8_t { no, for_cost, for_safety };

/// Why a running plan() is asked to give up (planner::Policy::interrupt).
enum class PlanInterruption : std::uint8_t {
  timeout,    ///< it took longer than its reply timeout
  user_stop,  ///< the user stopped the run (Ctrl-C, SIGTERM)
};

/// Cycles per status, indexed by PlanStatus.
using PlanStatusCounts = std::array<long, kPlanStatusCount>;

/// One cycle's answer.
struct PlanResult {
  std::vector<Vec2> path;  ///< in map axes, in driving order
  PlanStatus status = PlanStatus::normal;
  /// Why the status is not normal (empty when it is): e.g. "every candidate collides; car 7
  /// at 1.2 s".
  std::string reason;
  /// False when the planner does not say how it planned (a program over the protocol, which
  /// answers points only): `status` then means nothing, and reports show it as unknown.
  bool status_known = true;
  /// Whether the path layer declined its decision layer's lane change this cycle.
  ChangeDeclined change_declined = ChangeDeclined::no;
};

/// How far from the map's origin, on either axis, a path point may be: ten times as far as a
/// map's waypoints may be (MapRules::max_abs_coordinate_m). A point beyond, like one that is not
/// finite, is the planner's error: the world would carry the car there, and every figure of
/// the run after it (distance, speed, its frame on the page) would be nonsense or not finite.
inline constexpr double kMaxPathCoordinateM = 1e6;

/// What is wrong with a path's first bad point ("point 3 is (1e+300, 0): beyond 1,000 km of the
/// map's origin", or not finite), or nullopt when every point is finite and within
/// kMaxPathCoordinateM.
[[nodiscard]] std::optional<std::string> path_problem(std::span<const Vec2> path);

/// A path planned as meant (status normal).
[[nodiscard]] inline PlanResult normal_plan(std::vector<Vec2> path) {
  PlanResult r;
  r.path = std::move(path);
  return r;
}

}  // namespace overtake::core
