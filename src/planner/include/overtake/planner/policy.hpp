#pragma once
// The planner interface: a policy takes the telemetry snapshot of one cycle and returns the
// path points the ego should drive, the same shape the protocol carries.

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "overtake/core/plan.hpp"
#include "overtake/core/reference_line.hpp"
#include "overtake/core/telemetry.hpp"
#include "overtake/planner/params.hpp"

namespace overtake::planner {

/// A driving policy. Holds its own state between cycles (one instance per drive or
/// connection).
class Policy {
 public:
  virtual ~Policy() = default;
  /// The path for this cycle (in map axes, in driving order) and how it was found.
  [[nodiscard]] virtual core::PlanResult plan(const core::Telemetry& telemetry) = 0;
};

/// A policy's name and one-line description.
struct PolicyInfo {
  std::string name;
  std::string summary;
};

/// Every selectable policy.
[[nodiscard]] std::vector<PolicyInfo> list_policies();

/// A new instance of the named policy, or nullptr when there is no policy of that name.
/// `line` must outlive the policy.
[[nodiscard]] std::unique_ptr<Policy> make_policy(std::string_view name,
                                                  const core::ReferenceLine& line,
                                                  const PlannerParams& params);

}  // namespace overtake::planner
