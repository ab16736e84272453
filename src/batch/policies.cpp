#include "overtake/batch/policies.hpp"

namespace overtake::batch {

void check_policy_names(const std::vector<std::string>& names,
                        const std::shared_ptr<const planners::PlannerCatalog>& planners) {
  const planners::PlannerCatalog builtin;
  const planners::PlannerCatalog& catalog = planners ? *planners : builtin;
  for (const std::string& name : names) static_cast<void>(catalog.require(name));
}

}  // namespace overtake::batch
