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
#include "overtake/core/state_archive.hpp"
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
  /// Writes or restores the state it keeps between cycles (for checkpoints and cut
  /// scenarios), and says whether it did: false for a policy whose state overtake cannot
  /// see (a plugin, a Python planner), which then starts afresh from a checkpoint.
  virtual bool archive_state(core::StateArchive& /*ar*/) { return false; }
  /// Asks a plan() that is running on another thread right now to give up soon, by throwing
  /// from it (`why` says what its message should tell). Called from a watchdog thread, at any
  /// time, also when no plan() runs (then it must do nothing harmful). Returns whether this
  /// policy can be interrupted at all: false (the default) for code overtake cannot stop
  /// from outside (a C++ plugin), which the caller must then end some other way.
  virtual bool interrupt(core::PlanInterruption /*why*/) noexcept { return false; }
};

/// The policy's state as bytes (empty when it keeps none overtake can see).
[[nodiscard]] std::string save_policy_state(Policy& policy);
/// Restores a state save_policy_state wrote; false (nothing changed) when `state` is empty or
/// the policy keeps none; core::StateError when the bytes do not fit the policy.
bool restore_policy_state(Policy& policy, std::string_view state);

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

/// The words every layer refuses a policy name with: "unknown policy 'NAME' (available: A, B)",
/// `available` the names that layer knows (the built-in policies' when empty).
[[nodiscard]] std::string unknown_policy_text(std::string_view name,
                                              const std::string& available = {});

/// A new instance of the named policy, or nullptr when there is no policy of that name.
/// `line` must outlive the policy.
[[nodiscard]] std::unique_ptr<Policy> make_policy(std::string_view name,
                                                  const core::ReferenceLine& line,
                                                  const PlannerParams& params);

/// The factory of the named built-in policy, or an empty function when there is none.
[[nodiscard]] PolicyFactory builtin_policy_factory(std::string_view name);

}  // namespace overtake::planner
