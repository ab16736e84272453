#include "overtake/planner/policy.hpp"

#include "overtake/planner/reference/reference_policy.hpp"
#include "overtake/planner/seed_policies.hpp"
#include "overtake/planner/walkthrough.hpp"

namespace overtake::planner {

std::vector<PolicyInfo> list_policies() {
  return {
      {"reference",
       "the reference planner: predictions with cut-ins, lane choice by cost with RSS gaps and "
       "hysteresis, jerk-minimising Frenet trajectories checked for limits and collisions"},
      {"walkthrough",
       "keep lane, ramp to 49.5 mph, slow behind a car closer than 30 m, spline path (the "
       "project walkthrough the seed planners start from)"},
      {"seed000", "write-up 000: per-lane gaps and speeds, speed-dependent minimum gaps"},
      {"seed001", "write-up 001: lane change after 40 cycles of slowing, 35 m gap check"},
      {"seed002", "write-up 002: 30 m ahead / 5 m behind proximity per lane, 80-point path"},
      {"seed003",
       "write-up 003: prioritised rules, strong acceleration, return to the middle lane"},
      {"seed004", "write-up 004: 20 m / 10 m free-lane test, speed matching, 45 m anchor"},
  };
}

std::string unknown_policy_text(std::string_view name, const std::string& available) {
  std::string names = available;
  if (names.empty()) {
    for (const auto& p : list_policies()) names += (names.empty() ? "" : ", ") + p.name;
  }
  return "unknown policy '" + std::string(name) + "' (available: " + names + ")";
}

std::unique_ptr<Policy> make_policy(std::string_view name, const core::ReferenceLine& line,
                                    const PlannerParams& params) {
  if (name == "reference") return std::make_unique<reference::ReferencePolicy>(line, params);
  if (name == "walkthrough") return std::make_unique<WalkthroughPolicy>(line, params);
  if (name == "seed000") return std::make_unique<Seed000Policy>(line, params);
  if (name == "seed001") return std::make_unique<Seed001Policy>(line, params);
  if (name == "seed002") return std::make_unique<Seed002Policy>(line, params);
  if (name == "seed003") return std::make_unique<Seed003Policy>(line, params);
  if (name == "seed004") return std::make_unique<Seed004Policy>(line, params);
  return nullptr;
}

PolicyFactory builtin_policy_factory(std::string_view name) {
  const auto policies = list_policies();
  for (const auto& p : policies) {
    if (p.name == name) {
      return [n = p.name](const core::ReferenceLine& line, const PlannerParams& params) {
        return make_policy(n, line, params);
      };
    }
  }
  return {};
}

}  // namespace overtake::planner

namespace overtake::planner {

std::string save_policy_state(Policy& policy) {
  core::StateArchive ar;
  if (!policy.archive_state(ar)) return {};
  return ar.take();
}

bool restore_policy_state(Policy& policy, std::string_view state) {
  if (state.empty()) return false;
  core::StateArchive ar(state, "planner state");
  if (!policy.archive_state(ar)) return false;
  ar.expect_end();
  return true;
}

}  // namespace overtake::planner
