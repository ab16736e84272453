#pragma once
// One knob from cautious to assertive: planner.reference.assertiveness, from 0 (the shipped
// defaults, the safe end) to 1 (the edge where contacts become common). It moves the reference's
// soft costs, margins and gaps together; docs/figures.md, "The speed-risk frontier", measures
// each point of it. The config loader applies it (run::apply_config_json): a key the same file
// sets by hand keeps its own value.

#include <string>
#include <vector>

#include "overtake/planner/params.hpp"

namespace overtake::planner {

/// One key the knob moves: from its value at 0 towards `edge` at 1.
struct AssertivenessKey {
  std::string key;  ///< under planner.reference, e.g. "trajectory.lon_margin_m"
  double edge = 0.0;
  /// A soft cost: scaled by (1 - a)^2, so that it halves by a = 0.3 and is 0 at 1; a margin,
  /// gap or braking assumption moves linearly.
  bool soft_cost = false;
};

/// The keys the knob moves, in the order docs list them.
[[nodiscard]] const std::vector<AssertivenessKey>& assertiveness_keys();

/// `from` with each key of assertiveness_keys() moved to assertiveness `a` (0..1; values
/// outside are clamped) and `assertiveness` set to `a`. At 0 it is `from` itself.
[[nodiscard]] ReferenceParams with_assertiveness(const ReferenceParams& from, double a);

}  // namespace overtake::planner
