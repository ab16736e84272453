#pragma once
// One knob from cautious to assertive: planner.reference.assertiveness, from 0 (the shipped
// defaults, the safe end) to 1 (the assertive end). It moves the reference's soft costs,
// margins and gaps together, and past 0.75 the car's own pace: how hard it accelerates, how
// soon it passes, how short a gap its own braking needs. docs/figures.md, "The speed-risk
// frontier", measures each point of it. The config loader applies it
// (run::apply_config_json): a key the same file sets by hand keeps its own value.

#include <string>
#include <vector>

#include "overtake/planner/params.hpp"

namespace overtake::planner {

/// Which of the knob's two paths a key follows.
enum class AssertivenessStage {
  /// The soft costs, margins and gaps: from 0 to 0.75 along the way to `edge`, then more
  /// slowly, to 0.85 of the way at 1 (past 0.75 they bought risk and no speed).
  margins,
  /// The car's own pace: held until 0.75, then linearly to `edge` at 1.
  pace,
};

/// The knob on which pace keys start to move, and how far the margins have gone at 1.
inline constexpr double kAssertivenessPaceFrom = 0.75;
inline constexpr double kAssertivenessMarginsAtOne = 0.85;

/// One key the knob moves, from its value at 0 towards `edge`.
struct AssertivenessKey {
  std::string key;  ///< under planner.reference, e.g. "trajectory.lon_margin_m"
  double edge = 0.0;
  /// A soft cost: scaled by (1 - progress)^2, so that it halves by a = 0.3; a margin, gap,
  /// limit or braking assumption moves linearly.
  bool soft_cost = false;
  AssertivenessStage stage = AssertivenessStage::margins;
  double& (*field)(ReferenceParams&) = nullptr;  ///< the key's field in the params
};

/// The keys the knob moves, in the order docs list them.
[[nodiscard]] const std::vector<AssertivenessKey>& assertiveness_keys();

/// How far along its way to `edge` a key of `stage` is at knob `a` (0..1).
[[nodiscard]] double assertiveness_progress(AssertivenessStage stage, double a);

/// `from` with each key of assertiveness_keys() moved to assertiveness `a` (0..1; values
/// outside are clamped) and `assertiveness` set to `a`. At 0 it is `from` itself.
[[nodiscard]] ReferenceParams with_assertiveness(const ReferenceParams& from, double a);

}  // namespace overtake::planner
