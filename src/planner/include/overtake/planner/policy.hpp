#pragma once
// The planner interface: a policy takes the telemetry snapshot of one cycle and returns the
// path points the ego should drive, the same shape the protocol carries.

#include <functional>
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

/// Makes one policy instance (for one drive or one connection). `line` outlives the policy.
/// Built-in policies, C++ plugins and Python planners are all reached through one.
using PolicyFactory = std::function<std::unique_ptr<Policy>(const core::ReferenceLine& line,
                                                            const PlannerParams& params)>;

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

/// The factory of the named built-in policy, or an empty function when there is none.
[[nodiscard]] PolicyFactory builtin_policy_factory(std::string_view name);

}  // namespace overtake::planner
