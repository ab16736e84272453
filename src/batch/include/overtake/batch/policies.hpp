#pragma once
// The one check of the policy names a bench, a hunt, a suite or calibration is given.

#include <memory>
#include <string>
#include <vector>

#include "overtake/planners/catalog.hpp"

namespace overtake::batch {

/// Throws UsageError "--policy: unknown policy 'NAME' (available: ...)", as a drive does, for
/// the first name that is not in `planners` (null: the built-in policies only).
void check_policy_names(const std::vector<std::string>& names,
                        const std::shared_ptr<const planners::PlannerCatalog>& planners);

}  // namespace overtake::batch
